"""A search restricted to a few atoms: their abstract product, partners outside left free.

The atoms of a set S are composed through every interaction touching S;
ports of atoms outside S are assumed always ready, guards and priorities are
ignored.  That allows more than the system does, so the projection on S of
every reachable global state is among the states found here: a potential
deadlock whose projection is not among them is unreachable.
"""
from __future__ import annotations

from itertools import product

from runtime.compositional.interactions import StaticInteraction
from runtime.compositional.local import AtomAbstraction

#: A restricted product larger than this is abandoned (the verdict stays open).
MAX_PRODUCT = 50_000


def restricted_reach(atoms: list[AtomAbstraction], interactions: list[StaticInteraction],
                     subset: tuple[int, ...], limit: int = MAX_PRODUCT) -> set[tuple[int, ...]] | None:
    """The reachable projections on ``subset`` (atom indices, sorted), or None past ``limit`` states."""
    position = {a: n for n, a in enumerate(subset)}
    moves: dict[tuple[int, str], dict[int, list[int]]] = {}
    for a in subset:
        for e in atoms[a].edges:
            moves.setdefault((a, e.port), {}).setdefault(e.source, []).append(e.target)
    steps = []
    seen_keys = set()
    for inter in interactions:
        inside = tuple(sorted((a, p) for a, p, _ in inter.ports if a in position))
        if not inside or inside in seen_keys or len({a for a, _ in inside}) != len(inside):
            continue
        seen_keys.add(inside)
        steps.append([(position[a], moves.get((a, p), {})) for a, p in inside])
    starts = product(*(atoms[a].initial for a in subset))
    reach: set[tuple[int, ...]] = set(starts)
    stack = list(reach)
    while stack:
        cur = stack.pop()
        for step in steps:
            options = []
            for pos, table in step:
                got = table.get(cur[pos])
                if not got:
                    break
                options.append((pos, got))
            else:
                for combo in product(*(g for _, g in options)):
                    nxt = list(cur)
                    for (pos, _), t in zip(options, combo):
                        nxt[pos] = t
                    nt = tuple(nxt)
                    if nt not in reach:
                        reach.add(nt)
                        if len(reach) > limit:
                            return None
                        stack.append(nt)
    return reach
