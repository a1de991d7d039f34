"""Interaction invariants: initially marked traps of the boolean abstraction, found on demand by SAT.

The boolean abstraction is a Petri net whose places are the atoms' local
states (one token per atom) and whose transitions are every combination of
local edges an interaction synchronises (guards and priorities ignored: more
behaviour, so every trap found is still a trap of the real system).  A set
T of places is a trap when every transition taking a token from T puts one
back in T; if T is marked initially it stays marked, so "some atom is in a
state of T" is an invariant (II).

For an interaction with ports p_1..p_k and local edges E_1..E_k, the trap
condition over all combinations factorises: for each edge s -> s' of E_j,
z[s] implies z[s'] or, for some other l, every target of E_l is in T
(product of sums = sum of products).  One auxiliary per port makes the
encoding linear.  ``TrapFinder.exclude(state)`` asks for a trap disjoint
from a given abstract global state: the state violates that invariant.

Traps are kept by name (atom path, local state description), so a trap
found for one module is offered to the system that contains it
(:class:`TrapStore`): it is checked against the new interactions and
reused when it is still a trap, as the incremental construction asks.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from pysat.solvers import Solver

from runtime.compositional.interactions import StaticInteraction
from runtime.compositional.local import AtomAbstraction

#: Places of a trap tried for removal (one SAT call each): enough to reach small traps, bounded on big ones.
SHRINK = 24

Place = tuple[int, int]  # (atom index, local state)
Named = frozenset  # of (atom path, local state description)


@dataclass
class TrapStore:
    """Traps found so far, by name, reusable by any system that contains the same atoms."""

    traps: list[Named] = field(default_factory=list)

    def add(self, trap: Named) -> None:
        if trap not in self.traps:
            self.traps.append(trap)


class TrapFinder:
    """A SAT solver over "place s is in the trap" variables, for one system's boolean abstraction."""

    def __init__(self, atoms: list[AtomAbstraction], interactions: list[StaticInteraction], solver: str) -> None:
        self.atoms = atoms
        self.var: dict[Place, int] = {}
        for i, a in enumerate(atoms):
            for k in range(len(a.states)):
                self.var[(i, k)] = len(self.var) + 1
        top = len(self.var)
        self.clauses: list[list[int]] = []
        targets: dict[tuple[int, str], list[int]] = {}
        sources: dict[tuple[int, str], list[tuple[int, int]]] = {}
        for i, a in enumerate(atoms):
            for e in a.edges:
                targets.setdefault((i, e.port), []).append(e.target)
                sources.setdefault((i, e.port), []).append((e.source, e.target))
        aux: dict[tuple[int, str], int] = {}

        def w(port: tuple[int, str]) -> int:
            nonlocal top
            if port not in aux:
                top += 1
                aux[port] = top
                for t in set(targets[port]):
                    self.clauses.append([-top, self.var[(port[0], t)]])
            return aux[port]

        seen: set[tuple] = set()
        for inter in interactions:
            ports = [(a, p) for a, p, _ in inter.ports]
            if any(p not in targets for p in ports) or len({a for a, _ in ports}) != len(ports):
                continue  # never fires (a port without edges), or not a synchronisation of distinct atoms
            key = tuple(sorted(ports))
            if key in seen:
                continue
            seen.add(key)
            for j, port in enumerate(ports):
                others = [w(q) for n, q in enumerate(ports) if n != j]
                for s, t in set(sources[port]):
                    if s == t:
                        continue
                    self.clauses.append([-self.var[(port[0], s)], self.var[(port[0], t)]] + others)
        # initially marked: every initial state of some atom is in the trap
        marks = []
        for i, a in enumerate(atoms):
            top += 1
            marks.append(top)
            for k in a.initial:
                self.clauses.append([-top, self.var[(i, k)]])
        self.clauses.append(marks)
        self.solver = Solver(name=solver, bootstrap_with=self.clauses)
        try:
            self.solver.set_phases([-v for v in self.var.values()])  # prefer small traps
        except NotImplementedError:
            pass
        self.calls = 0

    def is_trap(self, trap: set[Place]) -> bool:
        """Whether a set of places satisfies the trap clauses here (and is initially marked)."""
        inside = {self.var[p] for p in trap}
        assumptions = [v if v in inside else -v for v in self.var.values()]
        return self.solver.solve(assumptions=assumptions)

    def exclude(self, state: list[int]) -> set[Place] | None:
        """A small trap containing none of the local states of ``state`` (one per atom), or None.

        Places are dropped while it stays a trap (up to ``SHRINK`` tries):
        a smaller trap is a stronger invariant, excluding more states, so
        fewer rounds are needed.
        """
        self.calls += 1
        base = [-self.var[(i, k)] for i, k in enumerate(state)]
        if not self.solver.solve(assumptions=base):
            return None
        trap = self._trap()
        for place in sorted(trap)[:SHRINK]:
            if place not in trap or len(trap) == 1:
                continue
            outside = [-v for p, v in self.var.items() if p not in trap]
            self.calls += 1
            if self.solver.solve(assumptions=base + outside + [-self.var[place]]):
                trap = self._trap()
        return trap

    def _trap(self) -> set[Place]:
        model = set(v for v in self.solver.get_model() if v > 0)
        return {p for p, v in self.var.items() if v in model}

    def named(self, trap: set[Place]) -> Named:
        return frozenset((self.atoms[i].atom.name, self.atoms[i].describe(k)) for i, k in trap)

    def resolve(self, named: Named) -> set[Place] | None:
        """The places of a stored trap in this system (None when an atom or a local state is not here)."""
        where = {}
        for i, a in enumerate(self.atoms):
            where[a.atom.name] = i
        out = set()
        for atom, desc in named:
            i = where.get(atom)
            if i is None:
                return None
            k = next((k for k in range(len(self.atoms[i].states)) if self.atoms[i].describe(k) == desc), None)
            if k is None:
                return None
            out.add((i, k))
        return out

    def delete(self) -> None:
        self.solver.delete()
