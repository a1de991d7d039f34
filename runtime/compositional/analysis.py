"""Compositional deadlock analysis (D-Finder style): CI ∧ II ∧ DIS by SAT, then a verdict per candidate.

``analyse`` computes the component invariants (local.py), the interactions
and their enabling conditions, and the formula; then it asks the SAT solver
for a potential deadlock again and again.  Each model is decoded into a
global abstract state and judged:

* an initially marked trap that excludes it (traps.py): *unreachable*, and
  the trap's invariant joins the formula (II grows only as needed);
* a search restricted to a few atoms (restricted.py) whose projection does
  not contain it: *unreachable*, and the projection is blocked;
* otherwise it is a *candidate*, blocked in the formula so that the next
  model is another one, and later checked by the explorer (check.py).

When the formula becomes unsatisfiable every potential deadlock has been
listed: without candidates the system is deadlock-free.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import networkx as nx

from runtime.compositional.formula import Formula
from runtime.compositional.interactions import StaticInteraction, enabling, static_interactions
from runtime.compositional.local import AtomAbstraction, abstract_atom, extern_values, written_ports
from runtime.compositional.restricted import restricted_reach
from runtime.compositional.traps import TrapFinder, TrapStore
from runtime.engine.flatten import FlatSystem

from runtime.compositional.solver import DEFAULT_SOLVER
#: More candidates than this and the analysis stops listing them (verdict unknown).
MAX_CANDIDATES = 64


@dataclass
class Phase:
    name: str
    seconds: float
    note: str = ""


@dataclass
class Potential:
    """A model of the formula: one local state per atom, and what decided it."""

    state: list[int]
    verdict: str  # "unreachable", "reachable", "unknown", or "candidate" before the checks
    method: str = ""
    reason: str = ""
    trace: list = field(default_factory=list)
    waits: list[list[str]] = field(default_factory=list)  # wait-for cycles among atoms
    checked: bool = False  # not refuted by invariants: a candidate for the explorer


@dataclass
class Analysis:
    """Everything the analysis found, for the report."""

    flat: FlatSystem
    atoms: list[AtomAbstraction]
    interactions: list[StaticInteraction]
    enablings: list = field(default_factory=list)
    phases: list[Phase] = field(default_factory=list)
    potentials: list[Potential] = field(default_factory=list)
    traps: int = 0
    reused_traps: int = 0
    variables: int = 0
    clauses: int = 0
    sat_calls: int = 0
    complete: bool = True  # every model of the formula was listed
    explored: bool = False  # an exhaustive exploration saw every reachable state (it decides the unlisted ones too)
    solver: str = DEFAULT_SOLVER

    @property
    def candidates(self) -> list[Potential]:
        return [p for p in self.potentials if p.checked]

    @property
    def verdict(self) -> str:
        """``deadlock-free``, ``deadlock`` (one is reachable) or ``unknown``."""
        if any(p.verdict == "reachable" for p in self.potentials):
            return "deadlock"
        if not (self.complete or self.explored) or any(p.verdict in ("unknown", "candidate") for p in self.potentials):
            return "unknown"
        return "deadlock-free"

    def describe(self, state: list[int], only: set[int] | None = None) -> list[str]:
        """One line per atom: ``NDD.GoTo.control: ACTIVE done=true ...``."""
        return [f"{a.atom.name}: {a.describe(k)}" for i, (a, k) in enumerate(zip(self.atoms, state))
                if only is None or i in only]

    def abstract(self, engine_state: tuple) -> list[int | None]:
        """The abstract global state of a concrete engine state (None for an atom outside its invariant)."""
        out = []
        for a in self.atoms:
            off = a.atom.offset
            out.append(a.abstract(engine_state[off], engine_state[off + 1: off + a.atom.size]))
        return out


def _timed(analysis: Analysis, name: str, started: float, note: str = "",
           progress: Callable[[str], None] | None = None) -> float:
    now = time.perf_counter()
    analysis.phases.append(Phase(name, now - started, note))
    if progress:
        progress(f"{name}: {now - started:.3f} s{' (' + note + ')' if note else ''}")
    return now


def analyse(flat: FlatSystem, solver: str = DEFAULT_SOLVER, use_traps: bool = True, use_restricted: bool = True,
            store: TrapStore | None = None, max_candidates: int = MAX_CANDIDATES,
            progress: Callable[[str], None] | None = None) -> Analysis:
    """Run the analysis on a flat system; candidates are left for :func:`check.decide`."""
    t = time.perf_counter()
    externs = extern_values(flat.package)
    written = written_ports(flat)
    atoms = [abstract_atom(flat, a, externs, written) for a in flat.atoms]
    inters = static_interactions(flat)
    analysis = Analysis(flat, atoms, inters, solver=solver)
    local = sum(len(a.states) for a in atoms)
    untracked = sum(len(a.untracked) for a in atoms)
    t = _timed(analysis, "component invariants", t,
               f"{len(atoms)} atoms, {local} local states, {untracked} variables untracked", progress)

    constants = dict(flat.constants)
    enablings = analysis.enablings = [enabling(i, atoms, constants) for i in inters]
    formula = Formula(atoms, enablings, solver)
    finder = TrapFinder(atoms, inters, solver) if use_traps else None
    if finder is not None and store is not None:
        for named in store.traps:
            places = finder.resolve(named)
            if places is not None and finder.is_trap(places):
                formula.invariant(places)
                analysis.reused_traps += 1
    analysis.variables, analysis.clauses = formula.size()
    t = _timed(analysis, "formula", t, f"{len(inters)} interactions, {analysis.variables} variables, "
               f"{analysis.clauses} clauses" + (f", {analysis.reused_traps} traps reused" if store else ""), progress)

    neighbours = _neighbours(atoms, inters)
    reach_cache: dict[tuple[int, ...], set | None] = {}
    try:
        while True:
            analysis.sat_calls += 1
            state = formula.solve()
            if state is None:
                break
            trap = finder.exclude(state) if finder is not None else None
            if trap is not None:
                formula.invariant(trap)
                analysis.traps += 1
                if store is not None:
                    store.add(finder.named(trap))
                analysis.potentials.append(Potential(state, "unreachable", "interaction invariant",
                                                     _trap_text(analysis, trap)))
                continue
            subset = _refute(atoms, inters, state, neighbours, reach_cache) if use_restricted else None
            if subset is not None:
                formula.block({i: state[i] for i in subset})
                names = ", ".join(atoms[i].atom.name for i in subset)
                analysis.potentials.append(Potential(state, "unreachable", "restricted search",
                                                     f"the atoms {names} cannot be in these states together"))
                continue
            analysis.potentials.append(Potential(state, "candidate", waits=wait_cycles(analysis, state), checked=True))
            formula.block(dict(enumerate(state)))
            if sum(p.verdict == "candidate" for p in analysis.potentials) >= max_candidates:
                analysis.complete = False
                break
    finally:
        formula.delete()
        if finder is not None:
            finder.delete()
    n = len(analysis.candidates)
    _timed(analysis, "SAT", t, f"{analysis.sat_calls} calls, {analysis.traps} traps, "
           f"{len(analysis.potentials) - n} potential deadlocks refuted, {n} candidates", progress)
    return analysis


def surely_enabled(analysis: Analysis, state: list[int]) -> list[str]:
    """Labels of the interactions surely enabled at an abstract global state (DIS is false there if any)."""
    out = []
    for inter, en in zip(analysis.interactions, analysis.enablings):
        if not all(state[a] in analysis.atoms[a].certain.get(p, ()) for a, p in en.plain):
            continue
        if en.combos is None:
            ok = all(state[a] in analysis.atoms[a].certain.get(p, ()) for a, p in en.read)
        else:
            ok = any(all(state[a] in states for (a, _), states in zip(en.read, combo)) for combo in en.combos)
        if ok:
            out.append(inter.label)
    return out


def refuting_trap(analysis: Analysis, state: list[int]) -> str | None:
    """An initially marked trap that the state leaves empty, described; None when there is none."""
    finder = TrapFinder(analysis.atoms, analysis.interactions, analysis.solver)
    try:
        trap = finder.exclude(state)
        return None if trap is None else _trap_text(analysis, trap)
    finally:
        finder.delete()


def _trap_text(analysis: Analysis, trap) -> str:
    parts = [f"{analysis.atoms[i].atom.name} {analysis.atoms[i].describe(k)}" for i, k in sorted(trap)]
    shown = "; ".join(parts[:6]) + (f"; ... ({len(parts)} local states)" if len(parts) > 6 else "")
    return f"an initially marked trap stays marked, and this state leaves it empty: {shown}"


def _neighbours(atoms: list[AtomAbstraction], inters: list[StaticInteraction]) -> list[set[int]]:
    out: list[set[int]] = [set() for _ in atoms]
    for inter in inters:
        ids = set(inter.atoms)
        for a in ids:
            out[a] |= ids - {a}
    return out


def _refute(atoms, inters, state: list[int], neighbours: list[set[int]],
            cache: dict[tuple[int, ...], set | None]) -> tuple[int, ...] | None:
    """A small set of atoms whose restricted product excludes the state's projection (pairs, then neighbourhoods)."""
    tried = []
    for i in range(len(atoms)):
        for j in sorted(neighbours[i]):
            if j > i:
                tried.append((i, j))
    for i in range(len(atoms)):
        hood = tuple(sorted(neighbours[i] | {i}))
        if len(hood) > 2:
            tried.append(hood)
    by_atom: dict[int, list[int]] = {}
    for n, inter in enumerate(inters):
        for a in set(inter.atoms):
            by_atom.setdefault(a, []).append(n)
    for subset in tried:
        if subset not in cache:
            touching = sorted(set().union(*(by_atom.get(i, ()) for i in subset)))
            cache[subset] = restricted_reach(atoms, [inters[n] for n in touching], subset)
        reach = cache[subset]
        if reach is not None and tuple(state[i] for i in subset) not in reach:
            return subset
    return None


def wait_cycles(analysis: Analysis, state: list[int], limit: int = 20) -> list[list[str]]:
    """Cycles of the wait-for graph at a global state: atom A waits for B when A's possibly enabled port
    takes part in an interaction that B's port in this state cannot join."""
    g = nx.DiGraph()
    for inter in analysis.interactions:
        ready = [(a, p) for a, p, _ in inter.ports if state[a] in analysis.atoms[a].possible.get(p, ())]
        blocked = [a for a, p, _ in inter.ports if state[a] not in analysis.atoms[a].possible.get(p, ())]
        for a, _ in ready:
            for b in blocked:
                if a != b:
                    g.add_edge(analysis.atoms[a].atom.name, analysis.atoms[b].atom.name)
    out = []
    for cycle in nx.simple_cycles(g):
        out.append(cycle)
        if len(out) >= limit:
            break
    return out


def dependency_graph(analysis: Analysis) -> nx.DiGraph:
    """Atoms and the interactions between them: an edge A -> B, labelled by the interactions, when an
    interaction needs a port of A and one of B (A may wait for B there)."""
    g = nx.DiGraph()
    for a in analysis.atoms:
        g.add_node(a.atom.name)
    for inter in analysis.interactions:
        names = [analysis.atoms[a].atom.name for a in dict.fromkeys(inter.atoms)]
        for x in names:
            for y in names:
                if x != y:
                    labels = g.get_edge_data(x, y, {}).get("interactions", [])
                    if inter.label not in labels:
                        labels.append(inter.label)
                    g.add_edge(x, y, interactions=labels)
    return g
