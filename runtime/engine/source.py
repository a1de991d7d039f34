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
import threading
from collections import OrderedDict
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


#: Generated sources from this many characters on (a model's step: hundreds of KB, whose compile takes longer than
#: reading its code back) are compiled once per text without its comments, the code kept beside the compiled C.
CACHE_FROM = 64 * 1024
#: A comment ending a line, with no quote in it: the part of a line that never reaches the code.
_COMMENT = re.compile(r"  # [^'\"\n]*$", re.M)


def compile_generated(source: str, what: str) -> CodeType:
    """``compile(source)`` under a name that finds its text again: ``<what #hash>``, or a dumped file.  The code is
    kept for the process (:data:`KEPT_CHARS`) and, from :data:`CACHE_FROM` characters on, beside the compiled C."""
    path = dumped(source, what)
    if path is not None:
        return compile(source, str(path), "exec")
    name = f"<{what} #{_digest(source)}>"
    linecache.cache[name] = (len(source), None, source.splitlines(keepends=True), name)
    if _open_strings(source):
        return compile(source, name, "exec")
    bare = _COMMENT.sub("", source)
    key = hashlib.sha256(bare.encode("utf-8")).digest()
    code = _kept.get(key)
    if code is not None:
        return code if code.co_filename == name else _named(code, name)
    code = compile(bare, name, "exec") if len(source) < CACHE_FROM else _cached(bare, name)
    _kept.put(key, code, len(bare))
    return code


class _Kept:
    """The code of the generated texts a process compiled, the most recently used kept up to :data:`KEPT_CHARS`
    characters of text: a model's engine is made again for each check of a command and each job of a campaign
    worker, from the same text (the suite compiled 1,566 texts 19,944 times).  Shared by threads."""

    def __init__(self) -> None:
        self.codes: OrderedDict[bytes, tuple[CodeType, int]] = OrderedDict()
        self.chars = 0
        self.lock = threading.Lock()

    def get(self, key: bytes) -> CodeType | None:
        with self.lock:
            got = self.codes.get(key)
            if got is None:
                return None
            self.codes.move_to_end(key)
            return got[0]

    def put(self, key: bytes, code: CodeType, chars: int) -> None:
        with self.lock:
            if key in self.codes:
                return
            self.codes[key] = (code, chars)
            self.chars += chars
            while self.chars > KEPT_CHARS and len(self.codes) > 1:
                self.chars -= self.codes.popitem(last=False)[1][1]

    def clear(self) -> None:
        with self.lock:
            self.codes.clear()
            self.chars = 0


#: Characters of generated text whose code a process keeps (whole DALA's step is 434,000).
KEPT_CHARS = 8 * 2 ** 20
_kept = _Kept()


def _open_strings(source: str) -> bool:
    """Some line opens a triple-quoted string it does not close (a comment-like text could be inside it)."""
    return any(line.count('"""') % 2 or line.count("'''") % 2 for line in source.splitlines())


def _cached(bare: str, name: str) -> CodeType:
    """The code of a large generated source (``bare``: its text without comments), read back when a source with
    the same text but for its comments (the model's file names in them: a client in another temporary directory)
    was compiled before.

    Comments end lines, so removing them moves no line or column: the code is the same but for its file name,
    which is set to ``name``.  The file is keyed by the text without comments and the interpreter's bytecode
    version; one that does not read back is compiled again; a cache that cannot be written is done without.
    """
    import importlib.util
    import marshal
    import sys

    from runtime.cachefiles import cache_dir, write_atomic

    key = hashlib.sha256("\0".join((bare, importlib.util.MAGIC_NUMBER.hex(), sys.version)).encode())
    file = cache_dir() / f"py-{key.hexdigest()[:24]}.marshal"
    try:
        code = marshal.loads(file.read_bytes())
        if isinstance(code, CodeType):
            return _named(code, name)
    except (OSError, EOFError, ValueError, TypeError):
        pass
    code = compile(bare, name, "exec")
    try:
        file.parent.mkdir(parents=True, exist_ok=True)
        write_atomic(file, marshal.dumps(code))
    except OSError:
        pass
    return code


def _named(code: CodeType, name: str) -> CodeType:
    """``code`` and the functions in it under the file name ``name``."""
    consts = tuple(_named(c, name) if isinstance(c, CodeType) else c for c in code.co_consts)
    return code.replace(co_filename=name, co_consts=consts)
