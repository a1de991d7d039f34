"""Timed BIP2: clocks with a unit, urgency and ``resume`` on transitions, atom invariants, clock rates.

Plain data like the rest of the model; the engine reads it through
``runtime.engine.timed`` (see docs/bip2.md, "Timed BIP2").
"""
from __future__ import annotations

from dataclasses import dataclass, field

from runtime.diagnostics import Span
from runtime.model.common import _span
from runtime.model.expressions import Expr

#: Nanoseconds in one unit of each BIP2 time unit.
TIME_UNITS: dict[str, int] = {"nanosecond": 1, "microsecond": 10**3, "millisecond": 10**6, "second": 10**9}
#: The unit of a clock declared without ``unit`` (the Verimag compiler's default).
DEFAULT_UNIT = "second"
#: Urgencies, weakest first: a lazy transition never stops time, a delayable one stops it at the end of
#: its window, an eager one as soon as it is enabled.
URGENCIES = ("lazy", "delayable", "eager")


@dataclass
class ClockDecl:
    """``clock x unit millisecond`` in an atom; ``unit`` is None when the declaration names none."""

    name: str
    unit: str | None = None
    span: Span = _span()

    @property
    def nanoseconds(self) -> int:
        return TIME_UNITS[self.unit or DEFAULT_UNIT]


@dataclass(frozen=True)
class Rate:
    """``x' = e;``: from now on clock ``x`` runs at speed ``e`` (1.0 unless set)."""

    clock: str
    value: Expr


@dataclass
class Resume:
    """``resume (g)`` after a transition's action: the atom resumes (its action completes) at a time where g
    holds; ``resume`` alone has no constraint of its own."""

    guard: Expr | None = None
    span: Span = _span()


@dataclass
class Invariant:
    """``invariant n [at p, q | from p, q] provided (g)``: g holds whenever the invariant is in force: always
    (no places), when the marking is exactly ``p, q`` (``at``, ``exact``) or when ``p`` and ``q`` are marked
    among others (``from``), as the Verimag engine checks it.  On clocks it bounds time; on data only, a
    violation is a model error."""

    name: str
    places: list[str] = field(default_factory=list)
    guard: Expr | None = None
    span: Span = _span()
    exact: bool = True

    def in_force(self, marking: int, mask: int) -> bool:
        """Whether the invariant applies at ``marking``, ``mask`` being the bits of its places."""
        return marking == mask if self.exact and mask else marking & mask == mask
