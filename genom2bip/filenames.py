"""Names that become file names (a mission's, a campaign's): one plain component of a path, or why not.

A mission named ``../../escape`` wrote its picture outside ``--out``; one
named ``x\\ud800`` (a lone surrogate) ran, then could not name its file.
"""
from __future__ import annotations

#: Characters of one name: a file name must stay far below the 255 bytes of most file systems, suffix included.
MAX_NAME = 100


def name_problem(name: str) -> str | None:
    """Why ``name`` cannot be a file name of its own inside an output directory (None when it can)."""
    if not name or name.strip() != name:
        return "an empty name, or one with spaces at its ends"
    if name in (".", ".."):
        return f"{name!r} names a directory"
    if "/" in name or "\\" in name:
        return "a name is one component of a path, without '/' or '\\'"
    if any(ord(c) < 32 or ord(c) == 127 or 0xD800 <= ord(c) <= 0xDFFF for c in name):
        return "a name holds no control character and no lone surrogate"
    if len(name) > MAX_NAME:
        return f"a name has at most {MAX_NAME} characters"
    return None
