"""The partial-order reduction where time cannot pass (runtime/zones/reduction.py): it leaves orders of
commuting steps out, and nothing a search reports changes: the states where time passes, maxima, violations,
reachability verdicts."""
from __future__ import annotations

from pathlib import Path

import pytest

from test_platform_responses import CASES, model_of
from runtime.tchecker.reach import _Goal, load
from runtime.zones.csearch import library
from runtime.zones.search import ZoneExplorer

TCK = Path(__file__).parent / "fixtures" / "tchecker"
ENGINES = ["python"] + (["c"] if library() is not None else [])


def _search(package, root, engine, reduce, goal=None, tr=None):
    z = ZoneExplorer(package, root, engine=engine, reduce=reduce)
    if goal:
        z.goal = _Goal(z, tr, goal).need
    return z, z.explore()


def _timed_states(z) -> set:
    """The discrete states where time passes (what the next delay starts from)."""
    return {n.state for n in z.nodes if n.grown}


@pytest.mark.parametrize("engine", ENGINES)
def test_independent_urgent_steps_fire_in_one_order(engine):
    _, tr = load(TCK / "independent.tck")
    z0, full = _search(tr.package, tr.root, engine, False)
    z1, reduced = _search(tr.package, tr.root, engine, True)
    assert (full.states, reduced.states) == (81, 9)  # 3 places in each of 4 processes; one chain of 8 steps
    assert full.complete and reduced.complete
    assert _timed_states(z1) == _timed_states(z0) != set()


@pytest.mark.skipif("c" not in ENGINES, reason="the C zone search needs a C compiler (apt-get install gcc)")
@pytest.mark.parametrize("reduce", [False, True], ids=["full", "reduced"])
def test_a_search_set_up_before_it_starts_stores_what_one_set_up_by_explore_stores(reduce):
    """prepare() builds the C search ahead (a benchmark times the search alone): the reduction's sets and the goal
    go with it, so the same nodes are stored and the same verdict comes out."""
    _, tr = load(TCK / "independent.tck")
    z0, r0 = _search(tr.package, tr.root, "c", reduce)
    z1 = ZoneExplorer(tr.package, tr.root, engine="c", reduce=reduce)
    z1.prepare()
    r1 = z1.explore()
    assert (r1.states, r1.transitions, r1.complete) == (r0.states, r0.transitions, r0.complete)
    assert r1.states == (9 if reduce else 81)
    assert [(n.state, n.parent, n.via) for n in z1.nodes] == [(n.state, n.parent, n.via) for n in z0.nodes]


@pytest.mark.parametrize("engine", ENGINES)
def test_steps_writing_a_shared_integer_keep_every_order_between_them(engine):
    _, tr = load(TCK / "shared.tck")
    z0, full = _search(tr.package, tr.root, engine, False)
    z1, reduced = _search(tr.package, tr.root, engine, True)
    assert 9 < reduced.states < full.states == 81
    assert _timed_states(z1) == _timed_states(z0)


@pytest.mark.parametrize("case", [None] + CASES[:3], ids=["shared.tck"] + [c[0] for c in CASES[:3]])
def test_the_c_and_python_searches_reduce_alike(tmp_path, case):
    if library() is None:
        pytest.skip("the C zone search needs a C compiler (apt-get install gcc)")
    if case is None:
        _, tr = load(TCK / "shared.tck")
        package, root = tr.package, tr.root
    else:
        model = model_of(tmp_path, *case[1:])
        package, root = model.package, model.root
    zp, rp = _search(package, root, "python", True)
    zc, rc = _search(package, root, "c", True)
    assert (rc.states, rc.transitions, rc.maxima) == (rp.states, rp.transitions, rp.maxima)
    assert [(n.state, n.parent, n.via) for n in zc.nodes] == [(n.state, n.parent, n.via) for n in zp.nodes]


@pytest.mark.parametrize("name,labels,reachable", [
    ("independent.tck", ["done0", "done1", "done2", "done3"], True),
    ("fischer2.tck", ["cs1", "cs2"], False),
    ("urgent.tck", ["late"], False),
])
def test_reachability_verdicts_do_not_change(name, labels, reachable):
    _, tr = load(TCK / name, grid=2)
    for reduce in (False, True):
        _, r = _search(tr.package, tr.root, ENGINES[-1], reduce, labels, tr)
        assert bool(r.violations) is reachable, (name, reduce)


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_platform_maxima_and_violations_do_not_change(tmp_path, case):
    _, gen, defines, platform, mission = case
    model = model_of(tmp_path, gen, defines, platform, mission)
    z0, full = _search(model.package, model.root, ENGINES[-1], False)
    z1, reduced = _search(model.package, model.root, ENGINES[-1], True)
    # the zones kept at the end: those stored on the way depend on the order zones arrive in, which the reduction
    # changes (after-client: 109 stored with it, 100 without, the same 87 kept)
    assert (~z1.graph().covered).sum() <= (~z0.graph().covered).sum()
    assert {c: v for c, (v, _) in reduced.maxima.items()} == {c: v for c, (v, _) in full.maxima.items()}
    assert set(reduced.violations) == set(full.violations)
    assert _timed_states(z1) == _timed_states(z0)
