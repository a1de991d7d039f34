"""Turning description names into BIP identifiers, consistently and reversibly readable.

BIP2 identifiers are C-like; GenoM names may be BIP keywords (``error``,
``clock``...) or contain ``-``/``::``.  Every name that reaches the model goes
through :func:`ident`, so a renamed word is renamed the same way everywhere.
"""
from __future__ import annotations

import re

#: Every word reserved by some version of the BIP2 grammar (untimed, timed, annotations).
RESERVED = frozenset(
    """
    package end use as extern data type function operator port atom compound connector
    component define export place initial internal on from to provided do up down if then
    else fi priority const true false bool int float string native refine
    error at clock unit sync async resume lazy eager delayable invariant remember ignore
    urgency urgent last first wait time tick
    """.split()
)

_INVALID = re.compile(r"[^A-Za-z0-9_]")


def ident(name: str) -> str:
    """A BIP identifier for ``name``: invalid characters become ``_``, reserved words get a ``_`` suffix."""
    out = _INVALID.sub("_", name.replace("::", "_"))
    if not out or out[0].isdigit():
        out = "_" + out
    if out in RESERVED:
        out += "_"
    return out


def joined(*parts: str) -> str:
    """``joined("NDD", "GoTo", "exec")`` → ``NDD_GoTo_exec``: names of generated types and externs."""
    return ident("_".join(parts))


def place(state: str) -> str:
    """Places are the FSM state names in upper case, so they never collide with port names."""
    return ident(state.upper())
