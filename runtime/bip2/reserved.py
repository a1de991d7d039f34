"""Words that no BIP2 identifier may be, and the shape of a valid identifier.

The set is the union of the keywords of every version of the Verimag BIP2
grammar (untimed, timed, real-time), so that a ``.bip`` file we write is
accepted by any of their compilers, even though our reader uses only some.
"""
from __future__ import annotations

import re

#: Keywords our grammar (bip2.lark) actually uses.
KEYWORDS = frozenset({
    "package", "end", "use", "const", "data", "extern", "function", "type", "port", "atom",
    "connector", "compound", "component", "export", "place", "initial", "to", "from", "on",
    "internal", "provided", "do", "priority", "define", "up", "down", "as", "if", "then", "else",
    "fi", "true", "false", "int", "bool", "float", "string",
    # timed BIP2
    "clock", "unit", "nanosecond", "microsecond", "millisecond", "second", "lazy", "delayable", "eager",
    "resume", "invariant", "at",
    # extern ports' event policies
    "remember", "ignore", "error",
})

#: Words the Verimag grammars reserve for constructs we do not read (operators, type refinement, longer
#: time units).
UNUSED_KEYWORDS = frozenset({
    "refine", "operator", "minute", "hour", "day", "sync", "async",
})

RESERVED = KEYWORDS | UNUSED_KEYWORDS

IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def is_identifier(name: str) -> bool:
    """True when ``name`` can be written as a BIP2 identifier as it is."""
    return bool(IDENTIFIER.match(name)) and name not in RESERVED
