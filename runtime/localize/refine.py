"""Safety properties by localization reduction and counterexample-guided refinement (Kurshan).

Round by round: keep a set K of atoms exact and the others free
(:mod:`runtime.localize.abstraction`), check the property's observer on that
over-approximation with the compiled search, and

* if it holds there, it holds on the model;
* if the abstract counterexample replays on the model (a best-first search
  of the model that follows the counterexample's kept interactions in order,
  any number of dropped ones in between), it is a real counterexample;
* otherwise K grows by the dropped atoms that withheld the interaction the
  replay could not reach (else by those the counterexample used), and again.

When K is every atom the round is the exact search.  Only properties whose
observer ignores every interaction it does not name can be localized: they
are the ones a dropped interaction cannot change (``[R] false``, ``[R] {P}``
with R written with ``*`` over the other interactions, as ``never``,
``precedes`` and the interruption patterns are).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from types import SimpleNamespace

from runtime.engine.flatten import FlatSystem, flatten
from runtime.explore.space import StateSpace, Step
from runtime.explore.timed import TICK
from runtime.export.monitors import build_monitor, equivalent_states, spin_shape
from runtime.export.promela_base import PromelaError
from runtime.localize.abstraction import CHAOS, Abstraction, abstract, always_ready, close, optional_leaves
from runtime.localize.timed import observer_seed
from runtime.props.check import Checkable, Verdict, _preds, check, model_labels
from runtime.props.formulas import Property, Regular, RSeq, RStar, SBox, SConst, SDia, SFix, SOr, SVar
from runtime.props.normal import normalize, positive
from runtime.props.predicates import atoms_read

METHOD = "localization"
#: States the search for a concrete counterexample may visit before the round counts the abstract one as spurious.
CONCRETE_BUDGET = 20_000
#: A label no interaction carries: a property that reacts to it counts the interactions it does not name.
UNNAMED = "\x00unnamed interaction"


class NotLocalizable(Exception):
    """The property is not a safety property the abstraction preserves (the message says why)."""


@dataclass
class Round:
    """One abstraction checked: how many atoms were kept, the states it had, what it answered."""

    kept: int
    atoms: int
    states: int
    seconds: float
    outcome: str  # "holds", "violated", "spurious", "inconclusive", "model error"
    chaos: int = 0
    concrete_states: int = 0


@dataclass
class Localized:
    """The verdict (as the other checkers give it) and the rounds that led to it."""

    verdict: Verdict
    rounds: list[Round] = field(default_factory=list)


def as_reachability(item: Checkable) -> Checkable | None:
    """``<R> true``, or ``mu X.(<A> true or <B> X)`` (which is ``<B*.A> true``), as ``[R] false``: its
    counterexamples are the witnesses of the possibility.  None for other shapes."""
    path = _reach_path(positive(item.property.formula))
    if path is None:
        return None
    prop = Property(item.name, SBox(path, SConst(False), item.property.span), item.property.span, "",
                    item.property.text)
    return Checkable(prop, normalize(prop.formula, []), set(item.observed))


def _reach_path(f) -> Regular | None:
    if isinstance(f, SDia):
        if isinstance(f.operand, SConst) and f.operand.value:
            return f.path
        rest = _reach_path(f.operand)
        return RSeq(f.path, rest) if rest is not None else None
    if isinstance(f, SFix) and f.sign == "mu" and isinstance(f.body, SOr):
        for loop, exit_ in ((f.body.left, f.body.right), (f.body.right, f.body.left)):
            if isinstance(loop, SDia) and isinstance(loop.operand, SVar) and loop.operand.name == f.var:
                rest = _reach_path(exit_)
                if rest is not None and f.var not in repr(exit_):
                    return RSeq(RStar(loop.path), rest)
    return None


def localizable(item: Checkable) -> str:
    """Why the localized method cannot take ``item`` ("" when it can)."""
    if item.property.pattern == "deadlock free":
        return "deadlock freedom is not preserved by the abstraction (the compositional analysis decides it)"
    if spin_shape(item) != "observer" and as_reachability(item) is None:
        return ("neither a safety property of the shape [R] false or [R] {P} (never, precedes, invariant) nor a "
                "possibility <R> true; liveness needs every infinite path of the model, which the abstraction does "
                "not preserve")
    return ""


def visible_labels(item: Checkable, labels: list[str]) -> set[str]:
    """The labels on which the property's observer moves from some state; raises NotLocalizable if it would
    move on an interaction it does not name."""
    statics = [SimpleNamespace(label=lab) for lab in [*labels, UNNAMED]]
    try:
        monitor, _ = build_monitor(item, statics, "p")
    except PromelaError as exc:
        raise NotLocalizable(str(exc)) from None
    block = equivalent_states(monitor)
    n = len(statics)

    def step(q: int, k: int) -> int:
        return monitor.delta[k].get(q, q)

    # an interaction k may be dropped when it never makes R match where it did not already, and what follows it
    # leads where it would have led without it
    moves = [any((step(q, k) in monitor.accepting and q not in monitor.accepting)
                 or any(block[step(step(q, k), j)] != block[step(q, j)] for j in range(n))
                 for q in range(monitor.states))
             for k in range(n)]
    if moves[-1]:
        raise NotLocalizable("the property counts interactions it does not name (its observer moves on any "
                             "interaction): dropping interactions would change its verdict")
    return {lab for lab, moved in zip(labels, moves) if moved}


def initial_kept(flat: FlatSystem, item: Checkable, visible: set[str]) -> set[int]:
    """The atoms that take part in a visible interaction by a port that changes them, the atoms P reads, and for a
    timing observer among them the atoms that force its close event in time."""
    kept = set()
    for fc in flat.connectors:
        if fc.top and fc.label in visible:
            optional = optional_leaves(flat, fc)  # e.g. the victims of an interruption: refinement adds them
            kept |= {flat.ports[p].atom for p in flat.leaves(fc) if not _read_only(flat, p) and p not in optional}
    kept |= {fp.atom for fp in flat.ports if not fp.decl.exported and fp.path in visible}
    names = {a.name: a.index for a in flat.atoms}
    kept |= {names[atom] for atom, _ in item.observed if atom in names}
    for p in _preds(item.property.formula):
        kept |= atoms_read(flat, p)
    for atom in list(kept):  # a timing observer: what forces its close event in time (runtime.localize.timed)
        kept |= observer_seed(flat, atom)
    return kept


def _read_only(flat: FlatSystem, port: int) -> bool:
    """A port whose transitions change nothing (a status port): its atom only lends data, which havoc covers."""
    fp = flat.ports[port]
    ts = [t for t in flat.atoms[fp.atom].type.transitions if t.port == fp.name]
    return bool(ts) and all(sorted(t.sources) == sorted(t.targets) and not t.action and t.guard is None for t in ts)


def check_localized(package, root: str, item: Checkable, externs=None, *, max_states: int | None = None,
                    max_bytes: int | None = None, concrete_budget: int = CONCRETE_BUDGET, on_round=None,
                    progress=None) -> Localized:
    """The verdict of safety property ``item`` on the model, by rounds of abstraction and refinement.

    ``on_round(Round)`` is called as each round ends; raises NotLocalizable for a property it cannot take.
    """
    why = localizable(item)
    if why:
        raise NotLocalizable(why)
    if spin_shape(item) != "observer":  # a possibility: the witnesses are the counterexamples of its negation
        def said(r: Round) -> None:  # the rounds speak of runs of the possibility, not of violations
            r.outcome = {"violated": "run found", "holds": "no run", "spurious": "spurious run"}.get(r.outcome,
                                                                                                    r.outcome)
            if on_round:
                on_round(r)

        dual = check_localized(package, root, as_reachability(item), externs, max_states=max_states,
                               max_bytes=max_bytes, concrete_budget=concrete_budget, on_round=said,
                               progress=progress)
        v = dual.verdict
        holds = None if v.holds is None else not v.holds
        verdict = Verdict(item.property, holds, v.trace, "witness" if v.trace else "", method=v.method,
                          states=v.states, seconds=v.seconds, note=v.note, error=v.error)
        return Localized(verdict, dual.rounds)
    flat = flatten(package, root)
    visible = visible_labels(item, model_labels(flat))
    kept = initial_kept(flat, item, visible)
    rounds: list[Round] = []
    concrete: StateSpace | None = None
    started = time.perf_counter()
    while True:
        kept = close(flat, kept)
        exact = len(kept) == len(flat.atoms)
        t0 = time.perf_counter()
        if exact:
            a = None
            space = StateSpace(package, root, externs, None, True, item.observed)
        else:
            a = abstract(package, root, flat, kept)
            space = StateSpace(a.package, a.root, externs, None, True, item.observed)
            visible_labels(item, model_labels(space.engine.flat))  # chaos interactions are unnamed too
        verdict = _search(space, item, externs, max_states, max_bytes, progress)
        rnd = Round(len(kept), len(flat.atoms), verdict.states, 0.0, verdict.word, len(a.chaos) if a else 0)
        rounds.append(rnd)
        if verdict.holds is True or verdict.holds is None or exact:
            rnd.seconds = time.perf_counter() - t0
            if on_round:
                on_round(rnd)
            return Localized(_final(verdict, rounds, started), rounds)
        used = _used(space, verdict.trace, kept, flat)
        if concrete is None:
            concrete = StateSpace(package, root, externs, None, True, item.observed)
        steps, visited, blockers = concretize(concrete, item, verdict.trace, a, concrete_budget, space)
        rnd.concrete_states = visited
        rnd.seconds = time.perf_counter() - t0
        if steps is not None:
            rnd.outcome = "violated"
            if on_round:
                on_round(rnd)
            real = Verdict(item.property, False, steps, "counterexample", method=METHOD)
            return Localized(_final(real, rounds, started), rounds)
        rnd.outcome = "spurious"
        if on_round:
            on_round(rnd)
        grow = blockers - kept or used - kept or {flat.atom_of(p).index for p in _offered(flat, kept)}
        kept = kept | (grow or {a.index for a in flat.atoms})


def _search(space: StateSpace, item: Checkable, externs, max_states, max_bytes, progress) -> Verdict:
    """The property on one abstraction: the compiled observer search, or the Python checker where it cannot."""
    from runtime.native.properties import compiled_check

    verdict = compiled_check(space, item, externs, progress, max_states, max_bytes)
    if verdict is None:
        space.max_states = max_states
        verdict = check(space, item, progress)
    return verdict


def _final(verdict: Verdict, rounds: list[Round], started: float) -> Verdict:
    last = rounds[-1]
    exact = last.kept == last.atoms
    verdict.method = (f"{METHOD}, {len(rounds)} round{'s' if len(rounds) != 1 else ''}, "
                      + ("every atom kept: the exact search" if exact else f"{last.kept} of {last.atoms} atoms kept"))
    verdict.states = sum(r.states for r in rounds)
    verdict.seconds = time.perf_counter() - started
    return verdict


def _offered(flat: FlatSystem, kept: set[int]) -> set[int]:
    """Ports of dropped atoms that a connector touching K binds (the boundary)."""
    out = set()
    for fc in flat.connectors:
        leaves = flat.leaves(fc)
        if fc.top and any(flat.ports[p].atom in kept for p in leaves):
            out |= {p for p in leaves if flat.ports[p].atom not in kept}
    return out


def _used(space: StateSpace, trace: list[Step], kept: set[int], flat: FlatSystem) -> set[int]:
    """The dropped atoms an abstract counterexample used: their ports took part, or their toggles and havocs fired.

    A port the atom offers in every state (a poster's ``write``, an observer's) does not count: its chaos atom
    offered it no more than the atom would have, so keeping the atom cannot rule the counterexample out.
    """
    names = {a.name: a.index for a in flat.atoms}
    ports = {fp.path: fp.id for fp in flat.ports}
    out = set()
    for step in trace:
        if step.label == TICK:  # every timed atom lets time pass in turn (no time-lock): the tick blames none
            continue
        for port in space.interaction(step.index).ports:
            atom = names.get(port.rpartition(".")[0])
            if atom is not None and atom not in kept and not (port in ports and always_ready(flat, ports[port])):
                out.add(atom)
    return out


def concretize(space: StateSpace, item: Checkable, trace: list[Step], a: Abstraction | None,
               budget: int, abstract_space: StateSpace | None = None) -> tuple[list[Step] | None, int, set[int]]:
    """A path of the model that takes the abstract trace's kept interactions in order and dropped ones in between.

    Segment by segment: from where the previous kept interaction led, a
    best-first search over dropped interactions to a state where the next
    kept one fires, guided towards the values the abstract trace gave the
    free booleans (``abstract_space``: the abstraction it came from), so the
    dropped atoms catch up with a short detour.  The path must end where the property's observer has matched
    and its predicate fails.  None when a segment finds nothing within
    ``budget`` states: the abstract trace then counts as spurious (a real
    counterexample is found again after refinement; soundness never depends
    on this search), and the third value names the atoms that withheld the
    interaction the search could not reach: the ones whose ports it lacked in
    the state closest to it.
    """
    flat = space.engine.flat
    wanted = [s.label for s in trace if not _chaos_label(s.label)]
    free = a.free_labels if a is not None else frozenset()
    accept, pred = _acceptor(item, flat)
    goals = _goals(space, trace, abstract_space) if abstract_space is not None else [{} for _ in wanted]
    needs = {label: _needed_ports(flat, label) for label in set(wanted)}
    visited = 0
    blockers: set[int] = set()
    for start in space.initial_ids:
        states, labels = [start], []
        for label, goal in zip(wanted, goals):
            got, seen, lacking = _segment(space, states[-1], label, needs[label], free, budget, goal)
            visited += seen
            if got is None:
                blockers |= {flat.ports[p].atom for p in lacking}
                break
            states += got[0]
            labels += got[1]
        else:
            if accept(labels) and not pred(space.engine_state(states[-1])):
                return space.steps_along(states, labels), visited, set()
    return None, visited, blockers


def _goals(space: StateSpace, trace: list[Step], abstract_space: StateSpace) -> list[dict[int, object]]:
    """Per kept step of the trace: model slot -> the value its free boolean had in the abstraction just before."""
    names = {a.name: a for a in space.engine.flat.atoms}
    havocs = []
    for fa in abstract_space.engine.flat.atoms:
        for port in fa.ports:
            if port.startswith(f"{CHAOS}havoc_") and fa.name in names:
                var = next(v.name for v in fa.variables if port == f"{CHAOS}havoc_{v.name}" or
                           port.startswith(f"{CHAOS}havoc_{v.name}_"))
                havocs.append((fa.slot(var), names[fa.name].slot(var)))
    out = []
    for k, step in enumerate(trace):
        if not _chaos_label(step.label):
            state = abstract_space.concrete(trace[:k])
            out.append({model: state[slot] for slot, model in havocs})
    return out


def _segment(space: StateSpace, sid: int, label: str, needs: list[list[int]], free, budget: int,
             goal: dict[int, object]):
    """(states after sid, their labels) of a path of dropped interactions then ``label`` (None if none is found),
    the states visited, and the ports ``label`` lacked in the state the search came closest from.

    Best first: states where the fewest atom ports that ``label`` needs (``needs``, from :func:`_needed_ports`)
    are missing and whose free booleans differ least from ``goal``, then the shallowest.
    """
    import heapq

    def distance(node: int) -> int:
        state = space.engine_state(node)
        return len(_missing(space, state, needs)) + sum(state[slot] != value for slot, value in goal.items())

    parent: dict[int, tuple[int, int] | None] = {sid: None}
    heap = [(distance(sid), 0, sid)]
    closest = heap[0]
    while heap and len(parent) < budget:
        closest = min(closest, heap[0])
        _, depth, node = heapq.heappop(heap)
        succ = space.successors(node)
        for k in range(0, len(succ), 2):
            name = space.labels[succ[k]]
            if name == label:
                states, labels = [succ[k + 1]], [name]
                cur = node
                while parent[cur] is not None:
                    prev, lab = parent[cur]
                    states.append(cur)
                    labels.append(space.labels[lab])
                    cur = prev
                return (states[::-1], labels[::-1]), len(parent), []
            if name in free and succ[k + 1] not in parent:
                parent[succ[k + 1]] = (node, succ[k])
                heapq.heappush(heap, (distance(succ[k + 1]), depth + 1, succ[k + 1]))
    return None, len(parent), _missing(space, space.engine_state(closest[2]), needs)


def _missing(space: StateSpace, state: tuple, needs: list[list[int]]) -> list[int]:
    """The atom ports an interaction needs (``needs``: per source, from :func:`_needed_ports`) that are not offered
    at engine state ``state``, for the source that lacks the fewest."""
    ready = space.engine.ready(state)
    lacks = [[p for p in ports if not ready[p]] for ports in needs]
    return min(lacks, key=len, default=[])


def _needed_ports(flat: FlatSystem, label: str) -> list[list[int]]:
    """Per interaction source labelled ``label`` (a top connector, or a lone atom port): the atom ports every one
    of its interactions needs."""
    out = []
    for fc in flat.connectors:
        if fc.top and fc.label == label:
            optional = optional_leaves(flat, fc)
            out.append([p for p in flat.leaves(fc) if p not in optional])
    return out + [[fp.id] for fp in flat.ports if fp.path == label and not fp.decl.exported]


def _acceptor(item: Checkable, flat: FlatSystem):
    """(labels -> the observer has matched R at the end, engine state -> P holds)."""
    from runtime.props.actions import matcher
    from runtime.props.formulas import SBox, SPred
    from runtime.props.normal import positive
    from runtime.props.predicates import bind
    from runtime.props.safety import automaton

    top = positive(item.property.formula)
    assert isinstance(top, SBox)
    auto = automaton(top.path)
    matches = [matcher(x) for x in auto.actions]

    def accept(labels: list[str]) -> bool:
        qs = auto.closure([auto.start])
        for lab in labels:
            qs = auto.closure([q2 for q in qs for (k, q2) in auto.moves[q] if matches[k](lab)])
        return auto.accept in qs

    pred = bind(flat, top.operand.pred, []) if isinstance(top.operand, SPred) else (lambda state: False)
    return accept, pred


def _chaos_label(label: str) -> bool:
    return label.rpartition(".")[2].startswith(CHAOS)
