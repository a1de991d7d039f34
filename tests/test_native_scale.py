"""The compiled search on two threads and with lossy stores answers as the exact one-thread search does."""
from __future__ import annotations

import math
import re

import pytest
from hypothesis import HealthCheck, given, settings

from runtime.bip2 import parse_text
from runtime.engine import flatten
from runtime.engine.errors import EngineError
from runtime.explore import StateSpace
from runtime.native.properties import compiled_check
from runtime.native.stores import lossiness
from runtime.props import read_properties
from tests import enginekit, verifykit
from tests.nativekit import compiled, models, needs_cc
from tests.test_native import ENGINE_CASES, VERIFY_CASES
from tests.test_native_por import ring

pytestmark = needs_cc

#: Bound on the fixtures whose state space is infinite (a counter that grows).
BOUND = 20_000
#: Search settings compared with the exact one-thread search.
VARIANTS = [{"workers": 2}, {"store": "compact"}, {"store": "compact", "workers": 2}, {"store": "bitstate", "bits": 26}]


def outcome(space_factory, bound: int | None = BOUND, **kw) -> dict:
    """What a search answers, independent of state numbers: counts, deadlock states and their trace lengths."""
    cs = compiled(space_factory())
    result = cs.explore(max_states=bound, **kw)
    dead = {cs.state(sid): len(cs.trace_to(sid)) for sid in result.deadlocks}
    out = {"stopped_by": result.stopped_by, "deadlocks": dead}
    if result.error is not None:
        out["error"] = (result.error.message, len(result.error.trace))
        return out
    out["counts"] = (result.states, result.transitions, result.depth, result.complete)
    return out


def assert_agree(space_factory, variants=VARIANTS, bound: int | None = BOUND) -> dict:
    exact = outcome(space_factory, bound)
    for kw in variants:
        got = outcome(space_factory, bound, **kw)
        if "error" in exact:  # another error of the same level may be met first: same length of trace
            assert "error" in got and got["error"][1] == exact["error"][1], kw
            continue
        if exact["stopped_by"] == "max-states":
            assert got["stopped_by"] == "max-states" and got["counts"][0] == BOUND, kw
            continue
        assert got == exact, kw
    return exact


@pytest.mark.parametrize("name, root", ENGINE_CASES)
def test_engine_fixtures_agree(name, root):
    assert_agree(lambda: StateSpace(enginekit.package(name), root))


@pytest.mark.parametrize("name, root", VERIFY_CASES)
def test_verify_fixtures_agree(name, root):
    assert_agree(lambda: verifykit.space(name, root))


def test_ndd_on_two_threads_and_compact():
    pkg, root = verifykit.ndd_model()
    exact = assert_agree(lambda: StateSpace(pkg, root), [{"workers": 2}, {"store": "compact", "workers": 2}],
                         bound=None)
    assert exact["counts"] == (125_440, 992_672, 32, True)


def test_two_threads_keep_shortest_deadlock_traces_on_a_ring():
    exact = assert_agree(lambda: verifykit.text_space(ring(7)))
    assert len(exact["deadlocks"]) == 1 and list(exact["deadlocks"].values()) == [7]


def test_two_threads_stop_at_the_state_limit_exactly():
    pkg, root = verifykit.ndd_model()
    cs = compiled(StateSpace(pkg, root))
    for kw in ({"workers": 2}, {"workers": 2, "store": "compact"}):
        result = cs.explore(max_states=3000, **kw)
        assert (result.states, result.stopped_by) == (3000, "max-states")
        depth = cs.explore(max_depth=10, **kw)
        assert (depth.states, depth.stopped_by) == (cs.explore(max_depth=10).states, "max-depth")


DIVIDE = """package Divide
  port type Port()
  atom type Count()
    data int x, y
    export port Port p()
    place A
    initial to A do { x = 3; }
    on p from A to A provided (x > -5) do { x = x - 1; y = 12 / x; }
  end
  atom type Spin()
    data int k
    export port Port q()
    place A
    initial to A
    on q from A to A provided (k < 6) do { k = k + 1; }
  end
  connector type One(Port a)
    define a
  end
  compound type Main()
    component Count c()
    component Spin s()
    connector One p(c.p)
    connector One q(s.q)
  end
end
"""


def test_a_model_error_on_two_threads_has_the_shortest_trace():
    exact = assert_agree(lambda: verifykit.text_space(DIVIDE))
    assert exact["error"][1] == 2, exact  # x: 3, 2, 1, then 12 / 0
    assert "division" in exact["error"][0], exact


def test_a_small_bitstate_array_misses_states_and_says_how_likely():
    pkg, root = verifykit.ndd_model()
    cs = compiled(StateSpace(pkg, root))
    result = cs.explore(store="bitstate", bits=16)
    assert result.states < 125_440  # 65,536 bits for 125,440 states: many are taken as visited
    loss = cs.lossiness
    assert loss.hash_factor == pytest.approx(65_536 / result.states)
    assert loss.expected_missed > 100 and loss.probability == 1.0
    assert f"hash factor {65_536 / result.states:,.1f} (SPIN: best if > 100)" in loss.line()


def test_lossiness_figures():
    compact = lossiness("compact", 10**8, 1 << 30)
    assert compact.probability == pytest.approx(10**8 * (10**8 - 1) / 2 / 2**64)
    assert "probability that a state was missed <= 0.00027 (n^2/2^65)" in compact.line()
    assert lossiness("exact", 10, 16) is None
    bit = lossiness("bitstate", 1000, 1 << 20)
    direct = sum((1 - math.exp(-3 * i / 2**20)) ** 3 for i in range(1000))
    assert bit.expected_missed == pytest.approx(direct, rel=0.01)
    assert bit.hash_factor == pytest.approx(1048.576)
    assert re.search(r"bitstate: 1,000 states in 2\^20 bits, 3 bits per state; hash factor 1,048.6", bit.line())


def test_threaded_build_keeps_every_mutable_global_per_thread():
    """The step's scratch globals must be per thread (TL) for the threaded build: the generated text says so."""
    pkg, root = verifykit.ndd_model()
    cs = compiled(StateSpace(pkg, root))
    mutable = [line for line in cs.source.splitlines()
               if re.match(r"static (?!const|inline|int \w+\(|void|V \w+\(|uint64_t \w+\(|TL)\w[\w ]*[\w\]]+;", line)]
    assert mutable == []


#: Written with the two-thread search and the compact store; no bug is recorded as found by it.  Each drawn
#: model is searched three times (one thread, two, two over the compact store): what it guards is that
#: threads and compaction never change states, deadlocks or shortest traces; 20 examples.
@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(models(atoms_range=(2, 5), connectors_range=(1, 5)))
def test_random_models_agree(text):
    try:
        StateSpace(parse_text(text, "Random.bip"), "Main()")
    except EngineError:
        return
    assert_agree(lambda: StateSpace(parse_text(text, "Random.bip"), "Main()"),
                 [{"workers": 2}, {"store": "compact", "workers": 2}])


# -- properties: observers with the reduction, two threads and the compact store --------------------

def verdicts(pkg, root, text: str, **kw) -> list[tuple[str, bool | None, int]]:
    """(name, verdict, trace length) of each property by the compiled observer search with settings ``kw``."""
    items, _ = read_properties(text, "p.mcl", flatten(pkg, root))
    observed = set().union(*(i.observed for i in items))
    out = []
    for item in items:
        v = compiled_check(StateSpace(pkg, root, observed=observed), item, **kw)
        assert v is not None, item.name
        out.append((item.name, v.holds, len(v.trace)))
    return out


RING_PROPS = ("a: invariant not (p0 @ EAT and p1 @ EAT); b: invariant not (p0 @ EAT and p2 @ EAT); "
              "c: deadlock free; d: invariant not p3 @ ONE")


def test_ring_verdicts_with_reduction_threads_and_compact_store():
    pkg = parse_text(ring(6), "Ring.bip")
    full = verdicts(pkg, "Main()", RING_PROPS)
    assert [(n, h) for n, h, _ in full] == [("a", True), ("b", False), ("c", False), ("d", False)]
    assert verdicts(pkg, "Main()", RING_PROPS, workers=2) == full  # shortest counterexamples still
    assert verdicts(pkg, "Main()", RING_PROPS, store="compact") == full
    for kw in ({"por": True, "workers": 2}, {"por": True, "store": "compact", "workers": 2},
               {"por": True, "dfs": True}):
        reduced = verdicts(pkg, "Main()", RING_PROPS, **kw)
        assert [(n, h) for n, h, _ in reduced] == [(n, h) for n, h, _ in full]
        assert all(r >= f for (_, _, r), (_, _, f) in zip(reduced, full))


# -- the command line ----------------------------------------------------------------------------------

def _explored(out: str) -> str:
    """The counts of the 'explored:' line, without the timing."""
    return next(line for line in out.splitlines() if line.startswith("explored: ")).split(";")[0]


def test_verify_compact_states_its_lossiness(capsys, tmp_path):
    from genom2bip.cli import main

    model = tmp_path / "Ring.bip"
    model.write_text(ring(6), encoding="utf-8")
    assert main(["verify", str(model), "--quiet"]) == 4
    exact = capsys.readouterr().out
    assert main(["verify", str(model), "--quiet", "--store", "compact", "--workers", "2"]) == 4
    out = capsys.readouterr().out
    assert _explored(out) == _explored(exact)
    assert "deadlocks: 1 reachable state without enabled interaction" in out
    assert re.search(r"note: hash compaction: [0-9,]+ states stored as 64-bit fingerprints; probability that a "
                     r"state was missed <= [0-9.e-]+ \(n\^2/2\^65\); traces are shortest among the states stored", out)
    assert main(["verify", str(model), "--quiet", "--store", "bitstate", "--bits", "20"]) == 4
    out = capsys.readouterr().out
    assert re.search(r"note: bitstate: [0-9,]+ states in 2\^20 bits, 3 bits per state; hash factor [0-9,.]+ "
                     r"\(SPIN: best if > 100\); expected states missed <= ", out)


@pytest.mark.parametrize("argv, message", [
    (["--workers", "2", "--dfs"], "--workers search breadth-first: drop --dfs"),
    (["--store", "compact", "--dfs"], "--store search breadth-first: drop --dfs"),
    (["--store", "bitstate", "--engine", "python"], "--store belong to the compiled explorer (--engine compiled)"),
    (["--workers", "2", "--engine", "spin"], "--workers belong to the compiled explorer (--engine compiled)"),
    (["--workers", "-1"], "--workers must be >= 0"),
    (["--store", "bitstate", "--bits", "50"], "--bits must be between 9 and 40"),
])
def test_bad_search_options_are_refused(capsys, tmp_path, argv, message):
    from genom2bip.cli import main

    model = tmp_path / "Ring.bip"
    model.write_text(ring(3), encoding="utf-8")
    before = sorted(p.name for p in tmp_path.iterdir())
    code = main(["verify", str(model), *argv])
    out, err = capsys.readouterr()
    assert code == 2
    assert message in err
    assert "explored" not in out
    assert sorted(p.name for p in tmp_path.iterdir()) == before
