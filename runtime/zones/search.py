"""Symbolic-time exploration: the erased model's discrete states, each with zones of clock values.

A symbolic state is ``(D, Z)``: a state of the erased model (runtime/zones/model.py)
and a zone of the clocks (runtime/zones/dbm.py).  Its successors come from the
engine's successors of ``D`` (the compiled step when it compiles): for each
interaction, ``Z`` meets the clock guards of the transitions it fires and the
priorities the engine no longer applies (EDF, urgency), the clocks it resets
are set, the clocks no guard reads any more are forgotten, and time passes as
far as every timed atom's tick allows and no urgent interaction is enabled.
Zones of one discrete state that another includes are not kept.

What the tick semantics reaches, this reaches: every bound is an integer, so a
zone's integer points are the clock values of the discrete-time states it
stands for (docs/verification/platform.md, *Clock zones*).
"""
from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from runtime.engine.errors import ModelError
from runtime.engine.support import RuleSides, rule_edges, top_connectors
from runtime.explore.progress import Progress, null_progress
from runtime.explore.space import StateSpace
from runtime.zones import dbm
from runtime.zones.model import NO_BOUND, Atom, Diagonal, TimedModel, Unsupported, analyse, holds as _holds, value
from runtime.zones.node import GOAL, Node


def _flat(bounds) -> list[int]:
    """Bounds ``(i, j, c)`` as the C search reads them: their count, then each triple."""
    out = [len(bounds)]
    for i, j, c in bounds:
        out += [i, j, int(c)]
    return out


@dataclass
class ZoneResult:
    states: int  # symbolic states kept
    discrete: int  # distinct discrete states
    transitions: int
    seconds: float
    complete: bool
    stopped: str = ""
    violations: dict[int, int] = field(default_factory=dict)  # observer atom -> node of its first violation
    maxima: dict[int, tuple[float, int]] = field(default_factory=dict)  # clock -> (largest value, node)
    merged: int = 0  # zones merged into another of their discrete state (their union being one zone)
    pruned: int = 0  # nodes left unexpanded below a covered node (ZoneExplorer.prune)
    revived: int = 0  # pruned nodes brought back, each because it covered a newcomer


#: Bytes of discrete states' programs the C search holds before it lets go of those of the states whose nodes
#: were all expanded (written again from the state's words if a new zone of the state arrives; 0: never).
PROGRAM_BYTES = 1 << 30


class ZoneExplorer:
    """Explores a timed model with zones; ``watch`` clocks get their largest value while their atom watches.

    ``engine``: ``c`` runs the search in C (runtime/zones/csearch.py) where a compiler is, ``python`` the
    reference loop below; both store the same nodes in the same order.
    """

    def __init__(self, package, root: str, externs=None, watch: dict[int, str] | None = None,
                 merge: bool = True, engine: str = "c", local_ceilings: bool = False, reduce: bool = False,
                 program_bytes: int = PROGRAM_BYTES, invariants: bool = False, grow_only: bool = True,
                 prune: bool = True) -> None:
        self.model: TimedModel = analyse(package, root)
        self.externs = externs  # the tick model's replay compiles its step with them (runtime/zones/tickstep.py)
        self.space = StateSpace(self.model.erased, root, externs, None, True, self.model.discrete_reads())
        from runtime.native.compiled import compile_space

        # its step is only called one state at a time (the C search keeps words): fields of 64 bits never widen
        self.compiled, self.note = compile_space(self.space, externs, wide_fields=True)
        flat = self.space.engine.flat
        self.flat = flat
        self.n = len(self.model.clocks)
        original = {fc.path: fc.id for fc in self.model.flat.connectors}
        self.connector_id = {fc.id: original[fc.path] for fc in flat.connectors}
        self.atom_index = {fa.name: fa.index for fa in flat.atoms}
        self.watch = watch or {}
        self.ceiling = np.array([float(c) if c else np.inf for c in self.model.ceilings])
        self.ceiling[0] = 0
        self._inter: dict[int, tuple] = {}
        self._succ: dict[tuple, list] = {}
        self._rules: dict[int, tuple[list[int], list[int]]] = {}
        self._blocks: dict[tuple, Blocking] = {}
        self._guards: dict[tuple, tuple] = {}
        self._passing: dict[tuple, tuple | None] = {}
        self._idle: dict[tuple, list[int]] = {}
        self.nodes: list[Node] = []
        self.out: list[list[tuple[int, Node]]] = []  # per node: (node that holds the successor, the step into it)
        tops = {}
        for c, srcs in top_connectors(self.space.engine.sources).items():
            tops[self.connector_id[c]] = set(srcs)
        tick = next(fc.id for fc in self.model.flat.connectors if fc.label == "tick")
        tops[tick] = {-1}
        self._feasible: dict[tuple, bool] = {}
        self.edges = self.useful_edges(rule_edges([(r.low, r.high) for r in self.model.rules], tops))
        self.sides = RuleSides([(r.low, r.high) for r in self.model.rules])
        self.tick_rules = [r for r, rule in enumerate(self.model.rules) if any(c == tick for c, _ in rule.low)]
        self.merge = merge
        # Extra_LU with each place's bounds (model.py's _local_ceilings), off by default: measured, it changes nothing
        # on DALA and RobNav (their clocks are read by priorities or observers) and stores more on Fischer 6
        self.local_ceilings = local_ceilings
        self.program_bytes = program_bytes
        #: Invariants are part of a state (a TChecker location's): where time may pass, the points of a zone past a
        #: place's invariant (kept by extrapolation, which forgets bounds no guard ahead reads) are left out, as
        #: tck-reach intersects every successor with the invariant; off, they stay as a piece where time cannot pass.
        self.invariants = invariants
        #: The clocks read only for how large they grow keep their upper bounds only (model.py's grow_only): zones
        #: that differ only in how small such a clock can be are one.
        self.grow_only = list(self.model.grow_only) if grow_only else []
        #: A node expanded before a larger zone of its state came is covered then; what lies below it is pruned: the
        #: nodes there not expanded yet are not (``dead``), unless one covers a newcomer (docs/verification/platform.md,
        #: *What lies below a covered node is pruned*).
        self.prune = prune
        self.current = -1  # the last node expanded (a node revived is expanded after nodes stored after it)
        self.dropped = 0  # nodes whose zone was let go (covered before they were expanded)
        self.engine = engine
        self.states: list[tuple] = []  # discrete states by number (the C search knows them so)
        self._ids: dict[tuple, int] = {}
        self._intern = None  # while a C search keeps the states: its numbering
        self.search = None  # the C search that ran (runtime/zones/csearch.py), if one did
        self.result: ZoneResult | None = None  # the last search's result, as far as it went (also when it raised)
        self.lasso_graph = None  # the graph lassos walk, made once per search (runtime/zones/lassos.py)
        #: A goal (reachability of places): groups of ``(state offset, place mask)``, the goal holding at a discrete
        #: state where each group has one alternative marked; its first node goes into violations under GOAL.
        self.goal: list[list[tuple[int, int]]] | None = None
        #: Told the live ZoneResult as the search goes (after each expanded state in Python; every 1,024 and at
        #: each violation found in C, the nodes so far readable); it may raise to stop the search.
        self.watcher = None
        self._ready = None  # the C search prepare() set up
        #: Partial-order reduction where time cannot pass (runtime/zones/reduction.py), built when a search starts.
        self.reduce = reduce
        self.por = None

    # -- the discrete side ------------------------------------------------------------------------
    def successors(self, state: tuple) -> list[tuple[int, tuple]]:
        got = self._succ.get(state)
        if got is None:
            if self.compiled is not None:
                got = self.compiled.successors(state)
            else:
                got = self._python_successors(state)
            self._succ[state] = got
        return got

    def _python_successors(self, state: tuple) -> list[tuple[int, tuple]]:
        space = self.space
        return [(inter.index, nxt) for inter, nxt, _ in space._fire_all(state)]

    def interaction(self, index: int) -> tuple:
        """``(parts in the original model's connector ids, [(atom, port)])`` of an interaction of the erased engine."""
        got = self._inter.get(index)
        if got is None:
            inter = self.space.interaction(index)
            parts = tuple((self.connector_id[c], m) for c, m in inter.parts)
            ports = []
            for p in inter.ports:
                atom, _, port = p.rpartition(".")
                ports.append((self.atom_index[atom], port))
            got = self._inter[index] = (parts, ports, inter.label)
        return got

    def place_bit(self, state: tuple, atom: int) -> int:
        return int(state[self.flat.atoms[atom].offset])

    # -- clock constraints ------------------------------------------------------------------------
    def bounds(self, atoms: list[Atom], atom: int, state: tuple) -> list[tuple[int, int, float]]:
        fa = self.flat.atoms[atom]
        out = []
        for a in atoms:
            v = value(a.rhs, fa, state)
            k = a.clock
            if a.op in ("<", "<="):
                out.append((k, 0, v - 1 if a.op == "<" else v))
            elif a.op in (">", ">="):
                out.append((0, k, -(v + 1) if a.op == ">" else -v))
            else:
                out += [(k, 0, v), (0, k, -v)]
        return out

    @staticmethod
    def diagonal_bounds(ds: list[Diagonal]) -> list[tuple[int, int, float]]:
        out = []
        for d in ds:
            if d.op in ("<", "<="):
                out.append((d.i, d.j, d.k - 1 if d.op == "<" else d.k))
            elif d.op in (">", ">="):
                out.append((d.j, d.i, -(d.k + 1) if d.op == ">" else -d.k))
            else:
                out += [(d.i, d.j, d.k), (d.j, d.i, -d.k)]
        return out

    def guard(self, index: int, state: tuple) -> tuple[list, list]:
        """The clock bounds an interaction needs at ``state`` and the clock resets it makes."""
        got = self._guards.get((index, state))
        if got is None:
            got = self._guards[(index, state)] = self._guard(index, state)
        return got

    def _guard(self, index: int, state: tuple) -> tuple[list, list]:
        _, ports, _ = self.interaction(index)
        need, resets = [], []
        for atom, port in ports:
            step = self.model.steps.get((atom, port, self.place_bit(state, atom)))
            if step is None:
                continue
            need += self.bounds(step.atoms, atom, state)
            fa = self.flat.atoms[atom]
            resets += [(k, value(e, fa, state)) for k, e in step.resets]
        return need, resets

    # -- priorities ------------------------------------------------------------------------------
    def feasible(self, bounds: tuple) -> bool:
        """Some clock values meet every bound (any discrete state): chains of priorities that can hold at once."""
        got = self._feasible.get(bounds)
        if got is None:
            got = self._feasible[bounds] = dbm.constrain_all(dbm.free_all(self.n), list(bounds)) is not None
        return got

    def useful_edges(self, edges: list[list[int]]) -> list[list[int]]:
        """The chains of priorities that can say more than a single rule: ``r -> r2`` is dropped when the two
        guards never hold together, or when a rule from r's low side to r2's high side already holds
        wherever both do (EDF's ``a < b < c`` next to ``a < c``; ``tick < a < b`` next to ``tick < b``)."""
        rules = self.model.rules

        def bounds(rule) -> tuple | None:
            if rule.guard is None:
                return ()
            return tuple(self.diagonal_bounds(rule.guard)) if isinstance(rule.guard, list) else None

        out = []
        for r, targets in enumerate(edges):
            kept = []
            for r2 in targets:
                g1, g2 = bounds(rules[r]), bounds(rules[r2])
                if g1 is not None and g2 is not None:
                    both = tuple(sorted(set(g1) | set(g2)))
                    if not self.feasible(both):
                        continue
                    implied = False
                    for r3 in rules:
                        g3 = bounds(r3)
                        if r3.low != rules[r].low or r3.high != rules[r2].high or g3 is None:
                            continue
                        zone = dbm.constrain_all(dbm.free_all(self.n), list(both))
                        if all(zone[i, j] <= c for i, j, c in g3):
                            implied = True
                            break
                    if implied:
                        continue
                kept.append(r2)
            out.append(kept)
        return out

    def rules_of(self, index: int) -> tuple[list[int], list[int]]:
        """The compound priorities an interaction is low in, and those it is high in."""
        got = self._rules.get(index)
        if got is None:
            got = self._rules[index] = self.sides.of(self.interaction(index)[0])
        return got

    def blocking(self, state: tuple, enabled: list[int]) -> "Blocking":
        """Where each compound priority blocks its low side at ``state`` (computed as asked, kept per state)."""
        got = self._blocks.get(state)
        if got is None:
            got = self._blocks[state] = Blocking(self, state, enabled)
        return got

    def allowed(self, zone: np.ndarray, index: int, blocks: "Blocking") -> list[tuple[np.ndarray, list]]:
        """Where the interaction may fire within ``zone``: the zones the priorities leave, each with its bounds."""
        pieces = [(zone, [])]
        for r in self.rules_of(index)[0]:
            for b in blocks.region(r):
                if not b:
                    return []
                block = dbm.constrain_all(zone, b)
                if block is None:
                    continue
                pieces = [(q, cut + more) for p, cut in pieces for q, more in dbm.subtract_bounds(p, block)]
                if not pieces:
                    return []
        return pieces

    def passing(self, state: tuple, blocks: "Blocking") -> tuple[list, list, list] | None:
        """Where time may pass at ``state``, whatever the zone: the invariants' bounds before a tick and after it,
        and the urgent priorities' regions ``(bounds, clock, lower bound)`` that stop time once reached; None when
        time cannot pass at all (kept per state)."""
        if state in self._passing:
            return self._passing[state]
        got = self._passing[state] = self._passing_at(state, blocks)
        return got

    def _passing_at(self, state: tuple, blocks: "Blocking") -> tuple[list, list, list] | None:
        before, after = [], []
        for atom in self.model.timed_atoms:
            place = self.model.places[(atom, self.place_bit(state, atom))]
            if not place.ticks:
                return None
            fa = self.flat.atoms[atom]
            if place.discrete is not None and not value(place.discrete, fa, state):
                return None
            for k, j, c in self.bounds(place.atoms, atom, state):
                if j != 0:
                    raise Unsupported(f"atom {fa.name}: time is bounded from below in one of its places")
                before.append((k, 0, c))
                after.append((k, 0, c + 1))
        if any(not b for r in self.tick_rules for b in blocks.region(r)):
            return None  # something urgent can happen now: no time passes
        waits = []
        for r in self.tick_rules:
            for b in blocks.region(r):
                lower = [(j, c) for i, j, c in b if i == 0]
                waits.append((b, r, lower[0] if len(b) == 1 and lower else None))
        return before, after, waits

    def limits(self, state: tuple, zone: np.ndarray) -> tuple[list, list] | None:
        """Bounds before a tick and after it at ``state`` from ``zone``: invariants, and urgent priorities that
        ``zone`` can reach as time passes; None when time cannot pass at all."""
        fixed = self._passing.get(state, False)
        if fixed is False and self.search is not None:  # after a C search: what its program for the state said
            fixed = self.search.passing(state)
            if fixed is not False:
                self._passing[state] = fixed
        if fixed is False:
            enabled = sorted({i for i, _ in self.successors(state)})
            fixed = self.passing(state, self.blocking(state, enabled))
        if fixed is None:
            return None
        before, after, waits = fixed
        if not waits:
            return before, after
        before, after = list(before), list(after)
        reach = dbm.constrain_all(dbm.up(zone), before)
        for b, r, lower in waits:
            if reach is None or dbm.constrain_all(reach, b) is None:
                continue  # time never passes from where this holds (an invariant stops it first)
            if lower is None:
                raise Unsupported(f"priority {self.model.rules[r].name}: time waits for a clock condition that "
                                  "is not one lower bound")
            k, c = lower
            before.append((k, 0, -c - 1))  # blocked from x >= -c on: time passes while x <= -c - 1
            after.append((k, 0, -c))
        return before, after

    def elapse(self, zone: np.ndarray, state: tuple) -> list[tuple[np.ndarray, bool]]:
        """The zone after time passes at ``state``, as far as it can: pieces, True for the one where it may have."""
        limits = self.limits(state, zone)
        if limits is None:
            return [(zone, False)]
        if self.invariants:  # a point past an invariant is no state (``invariants``): nothing of it is stored
            zone = dbm.constrain_all(zone, self._passing[state][1])
            if zone is None:
                return []
            limits = self.limits(state, zone)
        # A tick needs x <= c - 1 before it (``before``), so after any number of them x <= c (``after``): from the
        # points that meet ``after``, time reaches exactly up(Z & after) & after, as a dense-time invariant would.
        _, after = limits
        start = dbm.constrain_all(zone, after)
        if start is None:
            return [(zone, False)]
        grown = dbm.constrain_all(dbm.up(start), after)
        return [(grown, True)] + [(z, False) for z in dbm.subtract(zone, grown)]

    def ceilings(self, state: tuple) -> list[tuple[int, int, int]]:
        """``(clock, L, U)`` of the clocks whose ceilings at ``state`` are their place's rather than the model's
        (model.py's _local_ceilings), ascending."""
        if not self.local_ceilings:
            return []
        idle = self.idle(state)
        out = []
        for k, (atom, _) in enumerate(self.model.clocks, 1):
            if k in idle:  # no guard reads it before its next reset: no bound on either side, as TChecker's ExtraLU+
                out.append((k, NO_BOUND, NO_BOUND))
                continue
            got = self.model.places[(atom, self.place_bit(state, atom))].ceilings.get(k)
            if got is not None:
                out.append((k, *got))
        return out

    def extrapolate(self, zone: np.ndarray, state: tuple) -> np.ndarray:
        """``zone`` forgetting what no guard ahead of ``state`` tells apart (Extra_M; Extra_LU+ between the clocks
        whose ceilings are their place's), its idle clocks free again (time passing since they were freed related
        them to the others; no guard reads them before their next reset, and every zone of the state is then the same
        function of its active clocks, which the C search stores alone)."""
        over = self.ceilings(state)
        if not over:
            return self.forget(dbm.forget_below(dbm.extrapolate(zone, self.ceiling), self.grow_only), state)
        lower, upper = self.ceiling.copy(), self.ceiling.copy()
        plus = np.zeros(len(lower), dtype=bool)
        for k, low, up in over:
            lower[k], upper[k], plus[k] = low, up, True
        return self.forget(dbm.forget_below(dbm.extrapolate_lu_plus(zone, lower, upper, plus), self.grow_only), state)

    def forget(self, zone: np.ndarray, state: tuple) -> np.ndarray:
        """Clocks no guard reads before their next reset become free (so that zones that differ only there merge)."""
        idle = self.idle(state)
        return dbm.free_many(zone, idle) if idle else zone

    def idle(self, state: tuple) -> list[int]:
        """The clocks no guard reads at ``state`` before their next reset."""
        idle = self._idle.get(state)
        if idle is None:
            idle = self._idle[state] = [k for k, (atom, _) in enumerate(self.model.clocks, 1)
                                        if k not in self.model.places[(atom, self.place_bit(state, atom))].active]
        return idle

    # -- the search -------------------------------------------------------------------------------
    def _c_search(self):
        """The reduction's sets, which both searches use, then a C search of this model set up (its context and
        the model's tables), or None: no compiler, or too many clocks (the C operations keep a row or column of a
        zone on the stack)."""
        if self.reduce and self.por is None:
            from runtime.zones.reduction import PartialOrder

            self.por = PartialOrder(self)
        if self.engine != "c" or self.n >= 256:
            return None
        from runtime.zones.csearch import CSearch, library

        lib = library()
        return CSearch(self, lib) if lib is not None else None

    def prepare(self) -> None:
        """Set the C search up now, once the goal and the options are set, so that :meth:`explore` times the search
        alone (a benchmark's)."""
        self._ready = self._c_search()

    def explore(self, max_states: int | None = None, progress: Progress | None = None,
                stop_at_violation: bool = False) -> ZoneResult:
        """Breadth-first over symbolic states; observers checked and watched clocks maximised on the way."""
        progress = progress or null_progress()
        start = time.perf_counter()
        search, self._ready = self._ready or self._c_search(), None
        if search is not None:
            self.search = search
            self.result = ZoneResult(0, 0, 0, 0.0, True)
            result = self.search.run(self.result, max_states, progress, stop_at_violation)
            progress.done()
            result.seconds = time.perf_counter() - start
            return result
        passed: dict[tuple, list[int]] = {}
        waiting: deque[int] = deque()
        self.current = -1
        result = self.result = ZoneResult(0, 0, 0, 0.0, True)

        def add(state: tuple, zone: np.ndarray, parent: int, via: int, guard: list, grown: bool) -> bool:
            """Store the node; False when a stored zone covers it."""
            zone = self.extrapolate(zone, state)
            kept = passed.setdefault(state, [])
            step = Node(state, zone, parent, via, guard, grown)
            if kept:
                stack = np.stack([self.nodes[k].stored for k in kept])
                bigger = np.flatnonzero((stack >= zone).all(axis=(1, 2)))
                if len(bigger):
                    by = kept[bigger[0]]
                    if self.nodes[by].dead:
                        revive(by)
                    self.nodes[by].covers = True
                    if parent >= 0:  # the step is kept for cycles (lassos), its zone not: the covering node's stands
                        step.zone, step.by = None, by
                        self.out[parent].append((by, step))
                    return False
                for i in np.flatnonzero((stack <= zone).all(axis=(1, 2))):
                    old = self.nodes[kept[i]]
                    old.covered, old.by = True, len(self.nodes)  # a larger zone came: no need to expand this one
                    if old.expanded and self.prune:
                        prune_below(kept[i])
                    if not old.expanded:
                        old.zone = None  # no path goes through it: the larger zone stands for it
                        self.dropped += 1
            kept[:] = [k for k in kept if not self.nodes[k].covered]
            if self.merge and kept:
                result.merged += self.merge_into(step, kept)
            self.nodes.append(step)
            self.out.append([])
            if parent >= 0:
                self.out[parent].append((len(self.nodes) - 1, step))
            kept.append(len(self.nodes) - 1)
            waiting.append(len(self.nodes) - 1)
            return True

        def below(k: int) -> list[int]:
            """The children of node ``k`` in the search's tree."""
            return [t for t, step in self.out[k] if step is self.nodes[t]]

        def prune_below(k: int) -> None:
            """Node ``k`` was expanded and a larger zone covers it now: the nodes below it die, down through those
            expanded (as zsearch.c's prune_below), but for a node that covered a newcomer and what is below it."""
            todo = [k]
            while todo:
                for c in below(todo.pop()):
                    n = self.nodes[c]
                    if not (n.dead or n.covered or n.covers):
                        n.dead = True
                        if n.expanded:
                            todo.append(c)

        def revive(k: int) -> None:
            """Node ``k`` is dead and covers a newcomer: it and the dead nodes below it live again, those passed over
            while dead queued again in the order they were stored (as zsearch.c's revive)."""
            todo, back = [k], []
            while todo:
                u = todo.pop()
                n = self.nodes[u]
                n.dead = False
                result.revived += 1
                if n.skipped:
                    n.skipped = False
                    back.append(u)
                if n.expanded:
                    todo += [c for c in below(u) if self.nodes[c].dead]
            waiting.extend(sorted(back))

        for sid in self.space.initial_ids:
            state = self.space.state(sid)
            zone = self.forget(self.initial_zone(), state)
            for z, grown in self.elapse(zone, state):
                add(state, z, -1, -1, [], grown)
        popped, level_end, depth = 0, 0, -1  # breadth-first levels: the queue's entries before level_end at depth
        while waiting:
            if popped >= level_end:
                depth, level_end = depth + 1, popped + len(waiting)
            k = waiting.popleft()
            popped += 1
            node = self.nodes[k]
            if node.covered:
                continue
            if node.dead:
                node.skipped = True
                result.pruned += 1
                continue
            node.expanded = True
            self.current = max(self.current, k)
            self.check(k, result)
            if self.watcher is not None:
                self.watcher(result)
            if result.violations and stop_at_violation:
                result.complete, result.stopped = False, "violated"
                break
            succ = self.successors(node.state)
            enabled = sorted({i for i, _ in succ})
            blocks = self.blocking(node.state, enabled)
            here = node.zone
            keep = None  # the reduction's set, fired first; the others when one of its steps reaches a stored zone
            if self.por is not None and self.passing(node.state, blocks) is None:
                keep = self.ample(node.state, here)
            old, fired = False, result.transitions  # the rest too when none of the set fires in this zone
            for first in ((True, False) if keep is not None else (True,)):
                if not first and not old and result.transitions > fired:
                    break
                for index, nxt in succ:
                    if keep is not None and (index in keep) != first:
                        continue
                    need, resets = self.guard(index, node.state)
                    met = dbm.constrain_all(here, need)
                    if met is None:
                        continue
                    for piece, cut in self.allowed(met, index, blocks):
                        zone = piece
                        for c, v in resets:
                            zone = dbm.reset(zone, c, v)
                        zone = self.forget(zone, nxt)
                        result.transitions += 1
                        for z, grown in self.elapse(zone, nxt):
                            old |= not add(nxt, z, k, index, need + cut, grown)
            if max_states is not None and len(self.nodes) >= max_states:
                result.complete, result.stopped = False, "max-states"
                break
            progress.tick(len(self.nodes), result.transitions, len(waiting), self.memory, depth)
        progress.done()
        result.states = len(self.nodes)
        result.discrete = len(passed)
        result.seconds = time.perf_counter() - start
        return result

    def ample(self, state: tuple, zone: np.ndarray, forget: bool = False) -> set[int] | None:
        """The reduction's set at a node where time cannot pass (runtime/zones/reduction.py), None for every
        step; ``forget`` lets the state's caches go (the C search keeps what it needs)."""
        succ = self.successors(state)
        blocks = self.blocking(state, sorted({i for i, _ in succ}))
        keep = self.por.ample(state, succ, lambda i: self._fires(zone, i, state, blocks))
        if forget:
            self._succ.pop(state, None)
            self._blocks.pop(state, None)
            for index, _ in succ:
                self._guards.pop((index, state), None)
        return keep

    def _fires(self, zone: np.ndarray, index: int, state: tuple, blocks: "Blocking"):
        """Whether an enabled interaction fires from ``zone``: ``fires``; ``guard`` when its clock guard fails
        there; else the compound priorities each of which alone blocks it everywhere in the zone."""
        met = dbm.constrain_all(zone, self.guard(index, state)[0])
        if met is None:
            return "guard"
        if self.allowed(met, index, blocks):
            return "fires"
        alone = set()
        for r in self.rules_of(index)[0]:
            pieces = [met]
            for b in blocks.region(r):
                block = dbm.constrain_all(met, b) if b else met
                if block is None:
                    continue
                pieces = [q for p in pieces for q in dbm.subtract(p, block)]
            if not pieces:
                alone.add(r)
        return alone

    def initial_zone(self) -> np.ndarray:
        """Every clock at its first value."""
        zone = dbm.zero(self.n)
        for k, v in self.model.initial.items():
            zone = dbm.reset(zone, k, v)
        return zone

    def state_id(self, state: tuple) -> int:
        """The number of a discrete state (given on first sight)."""
        if self._intern is not None:
            return self._intern(state)
        got = self._ids.get(state)
        if got is None:
            got = self._ids[state] = len(self.states)
            self.states.append(state)
        return got

    def program(self, state: tuple, observers: dict[int, int]) -> list[int]:
        """What the C search needs of a discrete state, flat (layout: zsearch.c's header): the clocks idle there,
        where time may pass, the observers and response clocks it watches (``observers``: atom -> slot) and each
        successor with its guard, resets and the regions where priorities block it (a successor blocked
        everywhere is left out: it never fires).  Computed once per state; the caches it fills are let go."""
        out: list[int] = []
        idle = self.idle(state)
        out += [len(idle), *idle]
        over = self.ceilings(state)
        out.append(len(over))
        for k, low, up in over:
            out += [k, low, up]
        succ = self.successors(state)
        blocks = self.blocking(state, sorted({i for i, _ in succ}))
        fixed = self.passing(state, blocks)
        if fixed is None:
            out.append(0)
        else:
            before, after, waits = fixed
            out += [1, *_flat(before), *_flat(after), len(waits)]
            for b, r, lower in waits:
                out += [*_flat(b), int(lower is not None), *(lower or (0, 0)), r]
        checks: list[int] = []
        for atom, (watching, clock, bound) in self.model.observers.items():
            fa = self.flat.atoms[atom]
            if self.place_bit(state, atom) == fa.place_mask([watching]):
                checks += [0, observers[atom], clock, value(bound, fa, state)]
        for atom, (place, clock) in self.model.measures.items():
            if self.place_bit(state, atom) == self.flat.atoms[atom].place_mask([place]):
                checks += [1, 0, clock, 0]
        if self.at_goal(state):
            checks += [2, 0, 0, 0]
        out += [len(checks) // 4, *checks]
        steps: list[int] = []
        count = 0
        for index, nxt in succ:
            regions: list = []
            blocked = False
            for r in self.rules_of(index)[0]:
                for b in blocks.region(r):
                    if not b:
                        blocked = True
                        break
                    regions.append(b)
                if blocked:
                    break
            if blocked:
                continue
            need, resets = self.guard(index, state)
            steps += [self.state_id(nxt), index, *_flat(need), len(resets)]
            for c, v in resets:
                steps += [c, v]
            steps.append(len(regions))
            for b in regions:
                steps += _flat(b)
            count += 1
        out += [count, *steps]
        self._succ.pop(state, None)
        self._blocks.pop(state, None)
        self._passing.pop(state, None)
        for index, _ in succ:
            self._guards.pop((index, state), None)
        return out

    def graph(self):
        """The search's nodes and steps as arrays (runtime/zones/lassos.py's Graph)."""
        from runtime.zones.lassos import python_graph

        return self.search.graph() if self.search is not None else python_graph(self)

    def node_words(self, offset: int) -> np.ndarray:
        """Word ``offset`` of each node's discrete state."""
        if self.search is not None:
            return self.search.node_words(offset)
        return np.array([n.state[offset] for n in self.nodes], dtype=np.int64)

    def memory(self) -> int:
        """Bytes the search holds: in C, its zones, states, programs and nodes (csearch.py); in Python, the kept
        zones (the bulk of a long search; the caches of discrete states come beside)."""
        if self.search is not None:
            return self.search.memory()
        return (len(self.nodes) - self.dropped) * (self.n + 1) ** 2 * 4

    def merge_into(self, step: Node, kept: list[int]) -> int:
        """``step``'s zone grown by every kept zone of its discrete state stored after the last node expanded (not
        taken from the queue yet) that makes one zone with it: orders of independent zero-time steps reset clocks at
        different instants and cut one zone into pieces."""
        index, zone = len(self.nodes), step.zone
        grew = True
        while grew:
            grew = False
            for k in kept:
                if k <= self.current:
                    continue  # expanded, or passed over while dead: its successors are there, or its coverer's
                hull = dbm.union(zone, self.nodes[k].zone)
                if hull is not None:
                    zone = hull
                    step.members.append(k)
                    self.nodes[k].covered, self.nodes[k].by = True, index
                    grew = True
            kept[:] = [k for k in kept if not self.nodes[k].covered]
        if step.members:
            step.own, step.zone = step.zone, zone
        return len(step.members)

    def at_goal(self, state: tuple) -> bool:
        return self.goal is not None and all(any(state[off] == mask for off, mask in group) for group in self.goal)

    def check(self, k: int, result: ZoneResult) -> None:
        """Observers in error, the goal, and the largest values of watched clocks at node ``k``."""
        node = self.nodes[k]
        if GOAL not in result.violations and self.at_goal(node.state):
            result.violations[GOAL] = k
        for atom, (watching, clock, bound) in self.model.observers.items():
            fa = self.flat.atoms[atom]
            if self.place_bit(node.state, atom) != fa.place_mask([watching]):
                continue
            if dbm.upper(node.stored, clock) > value(bound, fa, node.state) and atom not in result.violations:
                result.violations[atom] = k
        for atom, (place, clock) in self.model.measures.items():
            fa = self.flat.atoms[atom]
            if self.place_bit(node.state, atom) != fa.place_mask([place]):
                continue
            top = dbm.upper(node.stored, clock)
            if clock not in result.maxima or top > result.maxima[clock][0]:
                result.maxima[clock] = (top, k)


class Blocking:
    """Where the compound priorities block at one discrete state, as lists of clock bounds (one zone each).

    BIP's semantics (runtime.engine.support.Priorities): a rule ``L < H`` whose guard holds blocks L
    while an interaction matching H is enabled, or while a rule reachable from it (its high side
    overlapping the next one's low side) blocks.  A rule's guard over clocks and the clock guards of
    H make that a region of clock values; chains whose guards contradict each other are dropped.
    ``[[]]`` is "everywhere".
    """

    def __init__(self, explorer: ZoneExplorer, state: tuple, enabled: list[int]) -> None:
        self.x, self.state = explorer, state
        self.highs: dict[int, list[int]] = {}
        for h in enabled:
            for r in explorer.rules_of(h)[1]:
                self.highs.setdefault(r, []).append(h)
        self.memo: dict[tuple, list] = {}

    def region(self, r: int) -> list:
        return self._region(r, (), ())

    def _region(self, r: int, acc: tuple, path: tuple) -> list:
        got = self.memo.get((r, acc))
        if got is not None:
            return got
        x = self.x
        rule = x.model.rules[r]
        key = (r, acc)
        if isinstance(rule.guard, list):
            acc = tuple(sorted(set(acc) | set(x.diagonal_bounds(rule.guard))))
            if not x.feasible(acc):
                self.memo[key] = []
                return []  # this chain of rules is never active at once
        elif rule.guard is not None and not _holds(rule.guard, self.state):
            self.memo[key] = []
            return []
        if r in path:
            raise ModelError("priority cycle between compound priorities "
                             + ", ".join(x.model.rules[y].name for y in path + (r,)))
        out = []
        for h in self.highs.get(r, ()):
            need = list(acc) + x.guard(h, self.state)[0]
            if not need:
                self.memo[key] = [[]]
                return [[]]  # blocked everywhere: nothing down the chain can say more
            out.append(need)
        for r2 in x.edges[r]:
            for b in self._region(r2, acc, path + (r,)):
                if not b:
                    self.memo[key] = [[]]
                    return [[]]
                out.append(b)
        out = [b for b in out if x.feasible(tuple(sorted(set(b))))]
        self.memo[key] = out
        return out


def lassos(z: ZoneExplorer, offset: int, value: int, limit: int = 200):
    """Reachable cycles of symbolic states whose word ``offset`` is ``value`` (an observer watching a request), in
    which time passes.

    Yields each cycle's entry node and the steps once round it; nothing when every such run ends
    (runtime/zones/trace.py's ``paths_to`` gives the ways to the entry).  Cycles down the search's own tree come
    first, shortest first: from the entry to a descendant whose step goes back into a zone the entry's covers,
    every step but the last taken from the zone it reached, so one round of it is a run of the model.  Then
    the cycles of the graph where a covered zone stands for the zone covering it (a cycle that closes on
    another branch of the tree): each is a cycle of the model's zones, though one round of it may need, after
    a step into a covered zone, clock values only the covering zone holds (runtime/zones/lassos.py).
    """
    from runtime.zones.lassos import find

    return find(z, z.node_words(offset) == value, limit)
