"""Compile generated sources so that tracebacks, debuggers and profilers show their real lines.

Every generated Python step (the engine's, the explorer's codec and
successors) is compiled here.  Its text is registered with ``linecache``
under a name unique to the source, so a traceback through it quotes the
generated line.  With ``GENOM2BIP_DUMP=DIR`` in the environment the source is
also written to a file in DIR and compiled under that file's path, for a
debugger or profiler that opens files; the compiled search's C step is
written there too (:func:`dumped`) and compiled from it with debug
information (docs/engine.md).
"""
from __future__ import annotations

import hashlib
import linecache
import os
import re
from pathlib import Path
from types import CodeType

DUMP_ENV = "GENOM2BIP_DUMP"


def dumped(source: str, what: str, suffix: str = ".py") -> Path | None:
    """With ``GENOM2BIP_DUMP=DIR``: the file ``DIR/<what>-<hash><suffix>`` holding ``source`` (written once)."""
    dump = os.environ.get(DUMP_ENV)
    if not dump:
        return None
    directory = Path(dump)
    directory.mkdir(parents=True, exist_ok=True)
    slug = re.sub(r"[^A-Za-z0-9]+", "-", what).strip("-").lower() or "generated"
    path = (directory / f"{slug}-{_digest(source)}{suffix}").resolve()
    if not path.exists():
        partial = path.with_name(f".{path.name}.{os.getpid()}")
        partial.write_text(source, encoding="utf-8")
        os.replace(partial, path)  # a reader never sees half a file
    return path


def _digest(source: str) -> str:
    return hashlib.sha1(source.encode("utf-8")).hexdigest()[:12]


def compile_generated(source: str, what: str) -> CodeType:
    """``compile(source)`` under a name that finds its text again: ``<what #hash>``, or a dumped file."""
    path = dumped(source, what)
    if path is not None:
        name = str(path)
    else:
        name = f"<{what} #{_digest(source)}>"
        linecache.cache[name] = (len(source), None, source.splitlines(keepends=True), name)
    return compile(source, name, "exec")
