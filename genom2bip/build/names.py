"""Turning description names into BIP identifiers, consistently and reversibly readable.

BIP2 identifiers are C-like; GenoM names may be BIP keywords (``error``,
``clock``...) or contain ``-``/``::``.  Every name that reaches the model goes
through :func:`ident`, so a renamed word is renamed the same way everywhere.
"""
from __future__ import annotations

from genom2bip.back.bip2 import bip_identifier


def ident(name: str) -> str:
    """A BIP identifier for ``name``: ``a::b`` → ``a_b``, then the writer's renaming rule (``error`` → ``error_``)."""
    return bip_identifier(name.replace("::", "_"))


def joined(*parts: str) -> str:
    """``joined("NDD", "GoTo", "exec")`` → ``NDD_GoTo_exec``: names of generated types and externs."""
    return ident("_".join(parts))


def place(state: str) -> str:
    """Places are the FSM state names in upper case, so they never collide with port names."""
    return ident(state.upper())
