"""When a connector can fire again: an atom it needs must still be able to reach the port it takes part with.

The dead-variable reduction (runtime/explore/layout.py) lets go of what only connectors that can no longer fire
read; the flags read only together (runtime/explore/conjunctions.py) ask when a port can still be offered.
"""
from __future__ import annotations

from runtime.engine.flatten import FlatAtom, FlatSystem, Leaf


def reaching(fa: FlatAtom, port: str) -> int:
    """The mask of the atom's places from which some path of its transitions (guards aside) takes ``port``."""
    return places_to(fa, [tr for tr in fa.type.transitions if tr.port == port])


def places_to(fa: FlatAtom, ends, through=None) -> int:
    """The mask of the atom's places from which a path of ``through`` (its transitions unless given; guards
    aside) leads to a place where one of the transitions ``ends`` starts."""
    bit = {p: 1 << i for i, p in enumerate(fa.places)}
    mask = 0
    for tr in ends:
        mask |= _or_places(bit, tr.sources)
    through = fa.type.transitions if through is None else through
    grew = True
    while grew:
        grew = False
        for tr in through:
            if _or_places(bit, tr.targets) & mask and _or_places(bit, tr.sources) & ~mask:
                mask |= _or_places(bit, tr.sources)
                grew = True
    return mask


def _or_places(bit: dict[str, int], places) -> int:
    out = 0
    for p in places:
        out |= bit.get(p, 0)
    return out


def connector_alive(flat: FlatSystem, fc, owner: int) -> tuple[tuple[int, int], ...] | None:
    """A necessary condition for connector ``fc`` to fire again, as ``(marking slot, mask)`` pairs one of which
    holds while it may: an atom other than ``owner`` whose port takes part in every interaction of ``fc`` in one
    of the places from which it can still take that port (the fewest such places, where several atoms qualify);
    for a connector that fires only within others (it exports a port), that of each of them.  None when the
    places say nothing (it may always fire again)."""
    from runtime.engine.defines import compile_define, required

    index = {p.name: i for i, p in enumerate(fc.type.params)}
    need = required(compile_define(fc.type.define, index, fc.path))
    best = None
    for i, alts in enumerate(fc.params):
        if not need >> i & 1 or len(alts) != 1 or not isinstance(alts[0], Leaf):
            continue
        fp = flat.ports[alts[0].port]
        fa = flat.atoms[fp.atom]
        if fa.index == owner:
            continue
        mask = reaching(fa, fp.name)
        if mask != (1 << len(fa.places)) - 1 and (best is None or bin(mask).count("1") < bin(best[1]).count("1")):
            best = (fa.offset, mask)
    if best is not None:
        return (best,)
    if fc.top or not fc.parents:
        return None
    out: list[tuple[int, int]] = []
    for parent in fc.parents:
        got = connector_alive(flat, flat.connectors[parent], owner)
        if got is None:
            return None
        out += got
    return tuple(out)
