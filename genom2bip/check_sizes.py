"""Values too large to hold: an ids member, a port or a parameter whose fixed arrays add up to millions of numbers.

The generated controller holds every ids member and port as a Python value
from the start, zero-filled; ``long a[100000000]`` would take gigabytes
before anything runs.  A sequence holds only what is written into it, so it
counts for nothing here.
"""
from __future__ import annotations

import math

from genom2bip.ir import (
    ArrayType,
    Component,
    Description,
    NamedType,
    OptionalType,
    SequenceType,
    StructType,
    Type,
    Typedef,
    UnionType,
)
from runtime.diagnostics import Reporter

#: Numbers in one value: a 1280 x 1024 RGB image in an octet array is 3.9 million.
MAX_VALUE_SIZE = 1 << 22


class _Sizes:
    """How many numbers a value of each type holds once zero-filled (named types counted once)."""

    def __init__(self, description: Description) -> None:
        self.types = description.types
        self.known: dict[str, int] = {}

    def of(self, t: Type | None) -> int:
        if isinstance(t, ArrayType):
            return math.prod(t.dims) * self.of(t.element)
        if isinstance(t, StructType):
            return sum(self.of(m.type) for m in t.members)
        if isinstance(t, UnionType):
            return 1 + max((self.of(c.member.type) for c in t.cases), default=0)
        if isinstance(t, Typedef):
            return self.of(t.type)
        if isinstance(t, NamedType):
            if t.name not in self.known:
                self.known[t.name] = 0  # a type reaching itself does so through a sequence: nothing to fill
                self.known[t.name] = self.of(self.types.get(t.name))
            return self.known[t.name]
        return 0 if t is None or isinstance(t, (SequenceType, OptionalType)) else 1


def check_sizes(component: Component, description: Description, reporter: Reporter) -> None:
    """Report each ids member, port and service parameter of ``component`` holding more than MAX_VALUE_SIZE."""
    sizes = _Sizes(description)
    typed = [("ids member", m.name, m.type, m.span) for m in component.ids]
    typed += [("port", p.name, p.type, p.span) for p in component.ports]
    typed += [("parameter", f"{s.name}.{p.name}", p.type, p.span) for s in component.services for p in s.parameters]
    for what, name, t, span in typed:
        size = sizes.of(t)
        if size > MAX_VALUE_SIZE:
            reporter.error(span, f"{what} '{name}' would hold {size:,} numbers: more than the {MAX_VALUE_SIZE:,} "
                                 "one value may hold", "a sequence<T, N> holds only what is written into it")
