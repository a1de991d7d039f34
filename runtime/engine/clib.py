"""C library functions that BIP2 models call as extern functions (``@cpp(include="stdio.h")``): ``printf``.

Bound by default, when the user's bindings do not name them, so that a model
written for the Verimag C++ engine prints the same lines here.
"""
from __future__ import annotations

import re
import sys

_SPEC = re.compile(r"%[-+ #0]*(\d*|\*)(?:\.(\d+|\*))?(?:hh|h|ll|l|z|L)?([diouxXfFeEgGcs%])")


def printf(fmt: str, *args) -> int:
    """C ``printf`` on standard output: the conversions of Python's ``%``; returns the characters written."""
    text = c_format(fmt, args)
    sys.stdout.write(text)
    sys.stdout.flush()
    return len(text)


def c_format(fmt: str, args: tuple) -> str:
    """``fmt`` with its C conversions (``%d``, ``%5.2f``, ``%s``, ``%%``...) applied to ``args`` in order."""
    rest = list(args)

    def one(m: re.Match) -> str:
        kind = m.group(3)
        if kind == "%":
            return "%"
        if not rest:
            raise ValueError(f"printf: no argument for {m.group(0)!r} in {fmt!r}")
        value = rest.pop(0)
        spec = re.sub(r"(hh|h|ll|l|z|L)(?=[a-zA-Z%]$)", "", m.group(0))
        if kind in "diouxXc" and isinstance(value, float):
            value = int(value)
        if kind == "u" and isinstance(value, int) and value < 0:
            value += 1 << 32
        return (spec[:-1] + "d" if kind in "iu" else spec) % value

    return _SPEC.sub(one, fmt)


#: name -> callable: what the engine binds when the model declares the name and nothing else binds it
DEFAULTS = {"printf": printf}
