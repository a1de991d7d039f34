"""The boolean formula CI ∧ II ∧ DIS over "atom i is in local state k" variables.

CI: each atom is in exactly one of its reachable local states.  DIS: no
interaction is surely enabled, i.e. for each interaction some port is in a
local state where it is not surely enabled, or no combination of the values
its guards read makes them surely true.  Priorities do not enter DIS: when
some interaction is enabled, the priority filter always leaves one (a cycle
of priorities is a model error the engine reports), so a global state is a
deadlock exactly when no interaction is enabled before priorities.  Atom
priorities, which can hide a port, are folded into "surely enabled"
(local.py).  II clauses (traps) and blocking clauses are added as the
analysis learns them.
"""
from __future__ import annotations

from pysat.card import CardEnc, EncType
from pysat.solvers import Solver

from runtime.compositional.interactions import Enabling
from runtime.compositional.local import AtomAbstraction


class Formula:
    """The SAT instance, kept in one incremental solver."""

    def __init__(self, atoms: list[AtomAbstraction], enablings: list[Enabling], solver: str) -> None:
        self.atoms = atoms
        self.var: list[list[int]] = []
        top = 0
        for a in atoms:
            self.var.append(list(range(top + 1, top + 1 + len(a.states))))
            top += len(a.states)
        self.top = top
        self.clauses: list[list[int]] = []
        self._ci()
        for en in enablings:
            self._dis(en)
        self.solver = Solver(name=solver, bootstrap_with=self.clauses)
        self.learned = 0

    def _fresh(self) -> int:
        self.top += 1
        return self.top

    def _ci(self) -> None:
        for vs in self.var:
            self.clauses.append(list(vs))
            if len(vs) > 1:
                enc = CardEnc.atmost(vs, 1, top_id=self.top, encoding=EncType.seqcounter if len(vs) > 8
                                     else EncType.pairwise)
                self.clauses.extend(enc.clauses)
                self.top = max(self.top, enc.nv)

    def _not_in(self, atom: int, states) -> list[int]:
        """Literals saying atom is in a local state outside ``states``."""
        return [v for k, v in enumerate(self.var[atom]) if k not in states]

    def _dis(self, en: Enabling) -> None:
        base: list[int] = []
        for a, p in en.plain:
            base.extend(self._not_in(a, self.atoms[a].certain.get(p, set())))
        if en.combos is None:
            base.extend(lit for a, p in en.read for lit in self._not_in(a, self.atoms[a].certain.get(p, set())))
            self.clauses.append(base)
            return
        if not en.combos:
            return  # never surely enabled: no constraint
        g = self._fresh()
        self.clauses.append(base + [g])
        for combo in en.combos:
            clause = [-g]
            for (a, _), states in zip(en.read, combo):
                clause.extend(self._not_in(a, states))
            self.clauses.append(clause)

    def add(self, clause: list[int]) -> None:
        self.solver.add_clause(clause)
        self.learned += 1

    def invariant(self, places) -> None:
        """Some atom is in one of these (atom, local state) places: a trap's invariant."""
        self.add([self.var[i][k] for i, k in places])

    def block(self, assignment: dict[int, int]) -> None:
        """Exclude every global state that agrees with ``assignment`` (atom -> local state)."""
        self.add([-self.var[i][k] for i, k in assignment.items()])

    def solve(self) -> list[int] | None:
        """A potential deadlock (one local state per atom), or None when the formula is unsatisfiable."""
        if not self.solver.solve():
            return None
        model = self.solver.get_model()
        positive = {v for v in model if v > 0}
        out = []
        for vs in self.var:
            out.append(next(k for k, v in enumerate(vs) if v in positive))
        return out

    def size(self) -> tuple[int, int]:
        return self.top, len(self.clauses) + self.learned

    def delete(self) -> None:
        self.solver.delete()
