"""Verdicts for the candidates the formula leaves: reachable (with a trace) or unreachable, by exploration.

First a breadth-first exploration with a state budget (the compiled
explorer where it takes the model, 2,000,000 states; else the Python one,
20,000): every deadlock it meets is mapped onto the abstract states; a candidate it meets is
*reachable* with a shortest trace, and when the exploration is complete the
others are *unreachable*.  Candidates still open then get a guided search:
best-first on the number of atoms whose place differs from the candidate's,
which reaches deep deadlocks (100 philosophers each holding a fork) that
breadth-first cannot; its trace is real but not necessarily shortest.
What is left is *unknown*, with the budget that ran out.

A deadlock the exploration finds that is not among the potential deadlocks
would mean the analysis is unsound: it is reported as such, never hidden.
"""
from __future__ import annotations

import heapq
import time
from typing import Callable

from runtime.compositional.analysis import Analysis, Potential
from runtime.engine.errors import EngineError
from runtime.explore import LimitReached, StateSpace, explore

#: States the breadth-first check may number (with the compiled explorer, with the Python one), then each
#: guided search.
COMPILED_BFS_BUDGET = 2_000_000
BFS_BUDGET = 20_000
GUIDED_BUDGET = 50_000


def decide(analysis: Analysis, package, root: str, externs=None, bfs_budget: int | None = None,
           guided_budget: int = GUIDED_BUDGET, progress: Callable[[str], None] | None = None,
           compiled: bool = True) -> None:
    """Give each candidate of ``analysis`` its verdict (in place), timing the checks as phases; ``compiled``
    False keeps the breadth-first search in Python (small models, where compiling would cost more)."""
    open_ = [p for p in analysis.potentials if p.verdict == "candidate"]
    if not open_:
        return
    started = time.perf_counter()
    by_state = {tuple(p.state): p for p in open_}
    try:
        space = StateSpace(package, root, externs)
    except EngineError as err:
        for p in open_:
            p.verdict, p.method, p.reason = "unknown", "", f"the explorer cannot run this model: {err}"
        return
    searched, result, bfs_budget = _breadth_first(space, externs, bfs_budget, compiled)
    found = 0
    for sid in result.deadlocks:
        trace = searched.trace_to(sid)
        abstract = tuple(analysis.abstract(space.concrete(trace)))
        p = by_state.get(abstract)
        if p is None:  # unlisted: past a cut listing, else a flaw of the analysis, never hidden
            why = ("a reachable deadlock the listing did not reach (it stopped at its limit)" if not analysis.complete
                   else "UNSOUND ANALYSIS: a reachable deadlock that is not among the potential deadlocks")
            p = Potential(list(abstract), "reachable", "exploration", why, trace, checked=True)
            analysis.potentials.append(p)
            by_state[abstract] = p
        elif p.verdict == "candidate":
            p.verdict, p.method, p.trace = "reachable", "exploration (shortest trace)", trace
            found += 1
    for p in open_:
        if p.verdict == "candidate" and result.complete:
            p.verdict, p.method = "unreachable", "exhaustive exploration"
            p.reason = f"not among the deadlocks of all {result.states:,} reachable states"
    analysis.explored = result.complete
    how = "compiled" if searched is not space else "Python"
    note = f"breadth-first ({how}), {result.states:,} states, {'complete' if result.complete else 'budget spent'}"
    analysis.phases.append(_phase("check: exploration", started, note, progress))
    for p in open_:
        if p.verdict != "candidate":
            continue
        started = time.perf_counter()
        _guided(analysis, p, package, root, externs, guided_budget, bfs_budget)
        analysis.phases.append(_phase(f"check: candidate {open_.index(p) + 1}", started,
                                      p.verdict + (f" ({p.method})" if p.method else ""), progress))


def _breadth_first(space: StateSpace, externs, budget: int | None, use_compiled: bool):
    """(the space searched, its ExploreResult, the budget used): the compiled search where it takes the model
    (2,000,000 states unless ``budget``), else the Python one (20,000)."""
    from runtime.native.compiled import Diverged, compile_space

    compiled = compile_space(space, externs, search=True)[0] if use_compiled else None
    if compiled is not None:
        limit = COMPILED_BFS_BUDGET if budget is None else budget
        try:
            return compiled, compiled.explore(max_states=limit), limit
        except Diverged:
            pass
    limit = BFS_BUDGET if budget is None else budget
    space.max_states = limit
    result = explore(space)
    space.max_states = None
    return space, result, limit


def _phase(name: str, started: float, note: str, progress):
    from runtime.compositional.analysis import Phase
    seconds = time.perf_counter() - started
    if progress:
        progress(f"{name}: {seconds:.3f} s ({note})")
    return Phase(name, seconds, note)


def _guided(analysis: Analysis, p: Potential, package, root: str, externs, budget: int, bfs: int) -> None:
    """Best-first search towards the candidate's places; a deadlock in exactly its abstract state decides it."""
    space = StateSpace(package, root, externs, max_states=budget)
    target = [analysis.atoms[i].states[k].marking for i, k in enumerate(p.state)]
    offsets = [a.atom.offset for a in analysis.atoms]

    def distance(sid: int) -> int:
        s = space.engine_state(sid)
        return sum(1 for off, m in zip(offsets, target) if s[off] != m)

    heap = [(distance(s), 0, s) for s in space.initial_ids]
    heapq.heapify(heap)
    expanded = set()
    try:
        while heap:
            _, depth, sid = heapq.heappop(heap)
            if sid in expanded:
                continue
            expanded.add(sid)
            succ = space.successors(sid)
            if not succ:
                trace = space.trace_to(sid)
                if analysis.abstract(space.concrete(trace)) == p.state:
                    p.verdict, p.method, p.trace = "reachable", "guided search (a trace, not necessarily shortest)", \
                        trace
                    return
                continue
            for t in succ[1::2]:
                if t not in expanded:
                    heapq.heappush(heap, (distance(t), depth + 1, t))
    except LimitReached:
        p.verdict, p.method = "unknown", ""
        p.reason = (f"breadth-first exploration stopped at {bfs:,} states and a guided search at {budget:,} "
                    "without reaching it; neither traps nor restricted searches exclude it")
        return
    except EngineError as err:
        p.verdict, p.method, p.reason = "unknown", "", f"the explorer stopped on a model error: {err}"
        return
    p.verdict, p.method = "unreachable", "exhaustive exploration"
    p.reason = f"the guided search visited all {len(space):,} reachable states without reaching it"
