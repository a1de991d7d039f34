"""A zone trace replayed on the tick model: by its compiled step or by the Python engine, the same steps, ticks
and codel outcomes; a step or a tick the tick model does not allow is refused either way."""
from __future__ import annotations

import copy
import re

import pytest

from genom2bip.verify.zones import ResponseResult, check_timing
from runtime.explore import StateSpace
from runtime.native.build import compiler
from runtime.native.compiled import CompiledSpace, compile_space
from runtime.zones import trace as trace_module
from runtime.zones.csearch import library
from runtime.zones.search import ZoneExplorer
from runtime.zones.tickstep import TickSteps
from runtime.zones.trace import ConcretizeError, paths_to, replay
from test_platform_responses import CASES, model_of

needs_cc = pytest.mark.skipif(compiler() is None or library() is None,
                              reason="the compiled step needs a C compiler (apt-get install gcc)")


def _traces(model, compiled: bool, monkeypatch) -> list:
    """Every result of check_timing with its trace, the tick model replayed by its compiled step or by Python."""
    made = []

    def steps(space, externs=None):
        got = getattr(space, "tick_steps", None)
        if got is None:
            got = space.tick_steps = TickSteps(space, externs, compiled=compiled)
            made.append(got)
        return got

    monkeypatch.setattr(trace_module, "tick_steps", steps)
    results = check_timing(model, ("overrun",), responses=True)
    assert made and all((m.compiled() is not None) == compiled for m in made), [m.note for m in made]
    out = []
    for r in results:
        t = r.trace
        out.append((r.subject, r.verdict, getattr(r, "value_ticks", None), r.message,
                    None if t is None else ([(s.label, s.index, s.outcomes, s.outcome_names) for s in t.steps],
                                            t.loop, t.ticks)))
    return out


@needs_cc
@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_the_compiled_tick_step_replays_the_traces_the_python_engine_replays(tmp_path, case, monkeypatch):
    _, gen, defines, platform, mission = case
    model = model_of(tmp_path, gen, defines, platform, mission)
    by_python = _traces(model, False, monkeypatch)
    by_c = _traces(model, True, monkeypatch)
    assert by_c == by_python
    assert any(t is not None and t[0] for *_, t in by_c), "the case is meant to have a trace"


@needs_cc
@pytest.mark.parametrize("case", CASES[:4], ids=[c[0] for c in CASES[:4]])
def test_tick_successors_are_the_python_engines_in_its_order(tmp_path, case):
    _, gen, defines, platform, mission = case
    model = model_of(tmp_path, gen, defines, platform, mission)
    space = StateSpace(model.package, model.root, {}, None, True, set())
    steps = TickSteps(space)
    assert steps.compiled() is not None, steps.note
    seen, todo = set(), [space.state(space.initial_ids[0])]
    while todo and len(seen) < 300:
        state = todo.pop()
        if state in seen:
            continue
        seen.add(state)
        python = space._fire_all(state)
        got = steps.successors(state)
        assert [(i.index, space.canonical(n)) for i, n in got] == \
            [(i.index, space.canonical(n)) for i, n, _ in python]
        for inter, nxt in got:
            made = [m for i, n, m in python if i is inter and space.canonical(n) == space.canonical(nxt)]
            step = steps.step(state, inter, nxt)
            assert (step.label, step.index) == (inter.label, inter.index)
            assert step.outcomes == tuple((c.name, p) for c, p in made[0])
            todo.append(nxt)
    assert len(seen) > 20


def _a_path(tmp_path):
    """A response trace's path of the first case (Python search: its nodes are plain Node objects)."""
    _, gen, defines, platform, mission = CASES[0]
    model = model_of(tmp_path, gen, defines, platform, mission)
    z = ZoneExplorer(model.package, model.root, engine="python")
    result = z.explore()
    clock, (top, node) = next(iter(result.maxima.items()))
    goal = [(0, clock, -int(top))]
    path = next(paths_to(z, node, goal))
    space = StateSpace(model.package, model.root, {}, None, True, set())
    return z, path, goal, space


@pytest.mark.parametrize("compiled", [pytest.param(True, marks=needs_cc), False], ids=["compiled", "python"])
def test_a_step_the_tick_model_does_not_take_there_is_refused(tmp_path, compiled):
    z, path, goal, space = _a_path(tmp_path)
    space.tick_steps = TickSteps(space, compiled=compiled)
    steps, _ = replay(z, path, goal, space)  # the path itself replays
    assert len(steps) >= len(path) - 1
    # a zero-time step said to stay where it was: its interaction changes the state on the tick model
    k = next(k for k in range(1, len(path)) if not path[k].grown and path[k].state != path[k - 1].state)
    wrong = copy.copy(path[k])
    wrong.state = path[k - 1].state
    label = re.escape(z.interaction(path[k].via)[2])
    with pytest.raises(ConcretizeError, match=rf"step {k} \({label}\) has no counterpart on the tick model"):
        replay(z, path[:k] + [wrong] + path[k + 1:], goal, space)


@pytest.mark.parametrize("compiled", [pytest.param(True, marks=needs_cc), False], ids=["compiled", "python"])
def test_time_passing_where_the_tick_model_lets_none_pass_is_refused(tmp_path, compiled, monkeypatch):
    z, path, goal, space = _a_path(tmp_path)
    space.tick_steps = TickSteps(space, compiled=compiled)
    real = trace_module.times

    def late(z, path, goal):  # every step from the first one on a thousand ticks later
        at, end = real(z, path, goal)
        return [at[0]] + [t + 1000 for t in at[1:]], end + 1000

    monkeypatch.setattr(trace_module, "times", late)
    with pytest.raises(ConcretizeError, match="time cannot pass where the zones said it could"):
        replay(z, path, goal, space)


@needs_cc
def test_where_time_passes_is_read_from_the_c_searchs_programs_as_python_computes_it(tmp_path):
    compared = 0
    for name, gen, defines, platform, mission in CASES:
        model = model_of(tmp_path, gen, defines, platform, mission)
        z = ZoneExplorer(model.package, model.root)
        z.explore()
        python = ZoneExplorer(model.package, model.root, engine="python")
        for state in {n.state for n in z.nodes}:
            got = z.search.passing(state)
            if got is False:
                continue
            enabled = sorted({i for i, _ in python.successors(state)})
            assert got == python._passing_at(state, python.blocking(state, enabled)), name
            compared += 1
    assert compared > 200


@needs_cc
def test_a_step_with_wide_fields_is_built_once_and_steps_as_the_narrow_one(tmp_path, monkeypatch):
    widened = []
    real = CompiledSpace._widen
    monkeypatch.setattr(CompiledSpace, "_widen", lambda self, slot: widened.append(slot) or real(self, slot))
    _, gen, defines, platform, mission = CASES[5]
    model = model_of(tmp_path, gen, defines, platform, mission)
    z = ZoneExplorer(model.package, model.root)
    z.explore()
    assert widened == []
    narrow, _ = compile_space(z.space)
    for state in list({n.state for n in z.nodes})[:200]:
        assert z.compiled.successors(state) == narrow.successors(state)


def test_lassos_of_one_search_for_several_watches_are_those_of_fresh_searches(tmp_path):
    from runtime.zones.search import lassos

    _, gen, defines, platform, mission = next(c for c in CASES if c[0] == "endless")
    model = model_of(tmp_path, gen, defines, platform, mission)

    def cycles(z, fa) -> list:
        return [(e, [(n.state, n.via) for n in loop]) for e, loop in lassos(z, fa.offset, fa.place_mask(["WATCH"]))]

    shared = ZoneExplorer(model.package, model.root)
    shared.explore()
    watched = [fa for fa in shared.flat.atoms if "WATCH" in fa.places]
    assert len(watched) >= 2
    found = []
    for fa in watched:
        fresh = ZoneExplorer(model.package, model.root)
        fresh.explore()
        found.append(cycles(shared, fa))
        assert found[-1] == cycles(fresh, fa)
    assert any(found)


def test_check_timing_results_do_not_depend_on_earlier_checks(tmp_path):
    # what the replay keeps per tick model and the lassos per search are not carried to another check
    _, gen, defines, platform, mission = next(c for c in CASES if c[0] == "endless")
    model = model_of(tmp_path, gen, defines, platform, mission)

    def shown(results):
        return [(r.subject, r.verdict, r.message, None if r.trace is None else [str(s) for s in r.trace.steps])
                for r in results if isinstance(r, ResponseResult)]

    first = shown(check_timing(model, (), responses=True))
    assert first == shown(check_timing(model, (), responses=True))


@needs_cc
def test_states_with_more_successors_than_the_first_room_step_alike(tmp_path):
    _, gen, defines, platform, mission = CASES[2]
    model = model_of(tmp_path, gen, defines, platform, mission)
    z = ZoneExplorer(model.package, model.root)
    z.explore()
    states = list({n.state for n in z.nodes})[:100]
    roomy = [z.compiled.successors(s) for s in states]
    assert max(len(s) for s in roomy) > 1
    small, _ = compile_space(z.space, wide_fields=True)
    small._cap = 1  # grown as states need
    assert [small.successors(s) for s in states] == roomy
    assert small._cap > 1


def test_a_check_keeps_nothing_once_it_returns(tmp_path, monkeypatch):
    # the tick model's steps, the erased states and the lassos' graph go with the check's explorer and tick model
    import gc
    import weakref

    import genom2bip.verify.zones as zones

    _, gen, defines, platform, mission = next(c for c in CASES if c[0] == "endless")
    model = model_of(tmp_path, gen, defines, platform, mission)
    kept = []
    real_explorer, real_steps = zones.explorer, trace_module.tick_steps

    def explorer(*args):
        z = real_explorer(*args)
        kept.append(weakref.ref(z))
        return z

    def steps(space, externs=None):
        kept.append(weakref.ref(space))
        return real_steps(space, externs)

    monkeypatch.setattr(zones, "explorer", explorer)
    monkeypatch.setattr(trace_module, "tick_steps", steps)
    results = check_timing(model, (), responses=True)
    assert any(r.trace is not None for r in results) and len(kept) > 1
    del results
    gc.collect()
    assert [r() for r in kept] == [None] * len(kept)


@pytest.mark.parametrize("name", ["shared-slow", "zeno-services"])
def test_a_step_into_a_zone_whose_coverer_was_covered_in_turn_gets_its_times(tmp_path, name):
    # A step into a covered zone points at the node that covered it; a larger zone may cover that node in turn
    # before it is expanded, and its zone is then let go.  The times of a path through such a step come from the
    # zone up the chain of covers (this raised AttributeError on the None zone, in the README's two-core check).
    from runtime.zones.search import ZoneExplorer
    from runtime.zones.trace import ConcretizeError, paths_to, replay, times
    from test_platform_responses import CASES, model_of

    _, gen, defines, platform, mission = next(c for c in CASES if c[0] == name)
    model = model_of(tmp_path, gen, defines, platform, mission)
    z = ZoneExplorer(model.package, model.root)
    z.explore()
    space = z.space
    steps = [step for edges in z.out for _, step in edges
             if step.stored is None and z.nodes[step.by].stored is None]
    assert steps, "no step into a zone let go: the test says nothing"
    for step in steps:
        path = next(paths_to(z, step.parent)) + [step]
        at, _ = times(z, path, [])
        assert len(at) == len(path) and at == sorted(at)
        try:
            replay(z, path, [], space)
        except ConcretizeError:
            pass  # a path the tick model does not take is refused with its reason, as any other


def _least(n: int, edges: list[tuple[int, int, float]]) -> list[float] | None:
    """The least solution of ``u - w <= d`` for every edge (0 at most for each variable), by Floyd–Warshall on
    the bounds' matrix; None when they have none (a cycle of negative weight)."""
    inf = float("inf")
    m = [[0.0 if i == j else inf for j in range(n)] for i in range(n)]
    for w, u, d in edges:
        m[w][u] = min(m[w][u], d)
    for k in range(n):
        for i in range(n):
            for j in range(n):
                m[i][j] = min(m[i][j], m[i][k] + m[k][j])
    if any(m[i][i] < 0 for i in range(n)):
        return None
    return [min(0.0, *(m[i][j] for i in range(n))) for j in range(n)]


def test_a_paths_clock_bounds_get_their_least_times_or_are_refused_when_they_have_none():
    import random

    rng = random.Random(7)
    solved = refused = 0
    for _ in range(300):
        n = rng.randint(1, 9)
        edges = [(rng.randrange(n), rng.randrange(n), float(rng.randint(-4, 9))) for _ in range(rng.randint(0, 3 * n))]
        want = _least(n, edges)
        if want is None:
            with pytest.raises(ConcretizeError, match="the path's clock bounds have no solution"):
                trace_module._shortest(n, edges)
            refused += 1
        else:
            assert trace_module._shortest(n, edges) == want, (n, edges)
            solved += 1
    assert solved > 100 and refused > 20, (solved, refused)
