"""Leaps over time in a tick model: how many ticks in a row change nothing but the clocks (docs/smc.md).

A tick adds one to the clocks that advance and changes nothing else (the
zone analysis, runtime/zones/model.py, checks that of the model).  What a
state enables can then change only where a comparison of a clock changes
value: a guard's ``clock op bound`` (the bound a constant or data of the
atom), a tick guard (a place time cannot stay in past a bound), an
observer's ``clock > bound``, a capped clock's ``if (clock < k)``, a
priority's difference of two clocks.  :meth:`Leaps.length` gives the
number of ticks ``K`` such that the states ``0 .. K-1`` ticks ahead all
compare alike: every one of them enables the same interactions, and the
tick path through them only adds to the clocks.  The simulator takes them
in one leap, drawing how many of them a race with other interactions lets
pass (runtime/smc/simulate.py).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from runtime.model import Binary, Const, If, Var
from runtime.zones.model import TICK, Unsupported, analyse

#: What :meth:`Leaps.length` answers when no comparison ever changes value (only the horizon ends the leap).
FAR = 1 << 62


@dataclass(frozen=True)
class Bound:
    """Clock (its slot in the state) compared with a constant, or with the value of another slot."""

    clock: int
    const: int | None = None
    slot: int | None = None


@dataclass(frozen=True)
class Gap:
    """``clock i - clock j`` (slots; None: no clock) compared with ``k``."""

    i: int | None
    j: int | None
    k: int


class Leaps:
    """The clock comparisons of a tick model, read once (``Unsupported`` where the model is outside the zone
    analysis' fragment, or a bound is not a constant or a variable of its atom)."""

    def __init__(self, package, root: str, flat) -> None:
        z = analyse(package, root)
        atoms = {fa.name: fa for fa in flat.atoms}
        mine = [atoms[z.flat.atoms[a].name] for a, _ in z.clocks]
        self.clocks = [fa.slot(var) for fa, (_, var) in zip(mine, z.clocks)]  # zone index - 1 -> slot
        bounds: set[Bound] = set()

        def bound(clock: int, rhs, fa, where: str) -> None:
            if isinstance(rhs, Const):
                bounds.add(Bound(self.clocks[clock - 1], const=int(rhs.value)))
            elif isinstance(rhs, Var) and rhs.name in fa.constants:
                bounds.add(Bound(self.clocks[clock - 1], const=int(fa.constants[rhs.name][0])))
            elif isinstance(rhs, Var):
                bounds.add(Bound(self.clocks[clock - 1], slot=fa.slot(rhs.name)))
            else:
                raise Unsupported(f"{where}: a clock compared with '{rhs}' (a constant or a variable is expected)")

        def owner(a: int):
            return atoms[z.flat.atoms[a].name]

        for (a, port, _), step in z.steps.items():
            for c in step.atoms:
                bound(c.clock, c.rhs, owner(a), f"atom {owner(a).name}, port {port or 'internal'}")
        for (a, _), place in z.places.items():
            for c in place.atoms:
                bound(c.clock, c.rhs, owner(a), f"atom {owner(a).name}, tick")
        for a, (_, clock, rhs) in z.observers.items():
            bound(clock, rhs, owner(a), f"observer {owner(a).name}")
        for fa in z.flat.atoms:  # capped clocks: ``if (c < k) c = c + 1`` in a tick transition
            names = {var: k for k, (b, var) in enumerate(z.clocks, 1) if b == fa.index}
            for tr in fa.type.transitions:
                if tr.port != TICK:
                    continue
                for st in tr.action:
                    if isinstance(st, If) and isinstance(st.cond, Binary) and isinstance(st.cond.left, Var) \
                            and st.cond.left.name in names:
                        bound(names[st.cond.left.name], st.cond.right, owner(fa.index), f"atom {fa.name}, tick")
        gaps = set()
        for rule in z.rules:
            if isinstance(rule.guard, list):
                for d in rule.guard:
                    gaps.add(Gap(self.clocks[d.i - 1] if d.i else None, self.clocks[d.j - 1] if d.j else None,
                                 int(d.k)))
        self.consts = sorted((b.clock, b.const) for b in bounds if b.const is not None)
        self.dynamic = sorted((b.clock, b.slot) for b in bounds if b.slot is not None)
        self.gaps = sorted(gaps, key=lambda g: (g.i or -1, g.j or -1, g.k))

    def length(self, value: Callable[[int], int], rate: dict[int, int]) -> int:
        """``K >= 1``: the states 0 .. K-1 ticks ahead compare every clock alike (``value(slot)`` reads the state;
        ``rate[slot]`` is 1 for a clock that advances with a tick here, 0 otherwise)."""
        best = FAR
        for clock, b in self.consts:
            if rate.get(clock):
                best = _nearer(best, b - value(clock))
        for clock, slot in self.dynamic:
            if rate.get(clock):
                best = _nearer(best, value(slot) - value(clock))
        for g in self.gaps:
            r = (rate.get(g.i, 0) if g.i is not None else 0) - (rate.get(g.j, 0) if g.j is not None else 0)
            if r:
                d = (value(g.i) if g.i is not None else 0) - (value(g.j) if g.j is not None else 0)
                best = _nearer(best, (g.k - d) * r)
                best = _nearer(best, (g.k - d) * r - 1)
        return best


def _nearer(best: int, gap: int) -> int:
    """``x op b`` with ``x`` ``gap`` below ``b`` changes value at ``gap`` or ``gap + 1`` ticks ahead: the nearest
    positive of the two, if nearer than ``best``."""
    for j in (gap, gap + 1):
        if 0 < j < best:
            best = j
    return best
