"""LALR parsers whose tables are kept in the cache: a command reads a grammar's tables instead of building them.

Building the tables of dotgen.lark takes about a second, bip2.lark's 0.7 s: every ``python -m genom2bip`` on a
description paid it before it read a line.  The tables are kept in the cache folder (runtime/cachefiles.py) as
lark saves a parser, in a file named by a hash of the grammar, its options, lark's version and Python's, and
written whole (two commands starting at once never read half of one).  A file that cannot be read is built again
and replaced; without a writable cache folder the tables are built every time.
"""
from __future__ import annotations

import hashlib
import io
import sys
from pathlib import Path

from runtime.cachefiles import cache_dir, write_atomic

#: Options given to a parser when its tables are read, not saved with them.
_AT_LOAD = ("postlex", "transformer", "lexer_callbacks")


def parser(grammar: str, **options):
    """A ``lark.Lark`` LALR parser of ``grammar`` with ``options``, its tables read from the cache when they are
    there and built (then kept) when not."""
    from lark import Lark

    path = tables_path(grammar, options)
    try:
        with open(path, "rb") as f:
            # lark's own cache reads its files so (Lark.load takes no options; the postlexer is one)
            return Lark.__new__(Lark)._load(f, **{k: v for k, v in options.items() if k in _AT_LOAD})
    except Exception:  # missing or damaged (of another lark, it has another name): built again below
        pass
    built = Lark(grammar, parser="lalr", **options)
    data = io.BytesIO()
    built.save(data, _AT_LOAD)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_atomic(path, data.getvalue())
    except OSError:
        pass  # no cache folder to write in: the next command builds them again
    return built


def tables_path(grammar: str, options: dict) -> Path:
    """Where the tables of ``grammar`` with ``options`` are kept."""
    from lark import __version__

    named = sorted((k, type(v).__name__ if k in _AT_LOAD else repr(v)) for k, v in options.items())
    key = hashlib.sha256("\0".join([grammar, repr(named), __version__, sys.version]).encode()).hexdigest()
    return cache_dir() / f"lark-{key[:24]}.tables"
