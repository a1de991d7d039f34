"""Compile generated Python so that tracebacks, debuggers and profilers show its real lines.

Every generated step (the engine's, the explorer's codec and successors) is
compiled here.  Its text is registered with ``linecache`` under a name unique
to the source, so a traceback through it quotes the generated line.  With
``GENOM2BIP_DUMP=DIR`` in the environment the source is also written to a
file in DIR and compiled under that file's path, for a debugger or profiler
that opens files (docs/engine.md).
"""
from __future__ import annotations

import hashlib
import linecache
import os
import re
from pathlib import Path
from types import CodeType

DUMP_ENV = "GENOM2BIP_DUMP"


def compile_generated(source: str, what: str) -> CodeType:
    """``compile(source)`` under a name that finds its text again: ``<what #hash>``, or a dumped file."""
    digest = hashlib.sha1(source.encode("utf-8")).hexdigest()[:12]
    dump = os.environ.get(DUMP_ENV)
    if dump:
        directory = Path(dump)
        directory.mkdir(parents=True, exist_ok=True)
        slug = re.sub(r"[^A-Za-z0-9]+", "-", what).strip("-").lower() or "generated"
        path = directory / f"{slug}-{digest}.py"
        if not path.exists():
            path.write_text(source, encoding="utf-8")
        name = str(path.resolve())
    else:
        name = f"<{what} #{digest}>"
        linecache.cache[name] = (len(source), None, source.splitlines(keepends=True), name)
    return compile(source, name, "exec")
