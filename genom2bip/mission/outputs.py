"""Where a mission writes (``--out``): checked before it runs, so that a run is never lost for want of a place.

A mission takes a minute and cannot be replayed exactly; its trace and its
picture were written after the run, and an ``--out`` that named a file, or a
directory nothing can be made in (``/proc/x``), lost them.  The check makes
nothing: it creates a temporary directory where the output will be, and
removes it.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path


def output_problem(out: Path, names: list[str]) -> str | None:
    """Why the files ``names`` cannot be written into the directory ``out`` (made if need be), or None."""
    folder = out
    while not os.path.lexists(folder) and folder != folder.parent:
        folder = folder.parent
    if not folder.is_dir():
        return f"{folder} is not a directory" if folder != out else "not a directory"
    for name in names:
        target = out / name
        if os.path.lexists(target) and not target.is_file():
            return f"{target} exists and is not a file"
        if target.is_file() and not os.access(target, os.W_OK):
            return f"{target} is not writable"
    try:  # the kernel's word: os.access says yes to root everywhere, /proc included
        probe = tempfile.mkdtemp(prefix=".genom2bip-", dir=folder)
    except OSError as exc:
        return f"nothing can be made in {folder}: {exc.strerror or exc}"
    os.rmdir(probe)
    return None
