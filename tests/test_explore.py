"""The explorer: hand-computed state counts, shortest deadlock traces, limits, choices, packing and reduction."""
import io

import pytest

from runtime.engine import Engine
from runtime.explore import Choice, ExploreError, Progress, StateSpace, explore
from runtime.explore.codec import Codec
from tests.verifykit import package, space, text_space


# --- hand-computed counts ---------------------------------------------------------------------------

@pytest.mark.parametrize("name, root, states, transitions, deadlocks", [
    # philosophers 0/1 in THINK/ONE/EAT with no fork held twice: TT TO TE OT OO ET
    ("Dining", "Table2()", 6, 8, 1),
    # cyclic words over {T,O,E} where E is followed by T: trace(M^3) = 14; 27 transitions
    ("Dining", "Table3()", 14, 27, 1),
    # x in 0..2, y in 0..1: 6 states, 2 increments each, plus the reset at (2, 1)
    ("Counters", "Pair()", 6, 13, 0),
    # IDLE, DONE, FAILED (the codel's last outcome is dead): run -> 3 outcomes, reset
    ("Codel", "Main()", 3, 4, 1),
    # IDLE/BUSY/DONE x served in {0, 1}
    ("Server", "Main()", 6, 8, 0),
])
def test_hand_counted_state_spaces(name, root, states, transitions, deadlocks):
    result = explore(space(name, root))
    assert (result.states, result.transitions, len(result.deadlocks)) == (states, transitions, deadlocks)
    assert result.complete and result.error is None


def test_without_reduction_dead_values_make_states_distinct():
    # IDLE with outcome 0 (initial) and IDLE with outcome 1 (after done, reset) are two states:
    # IDLE/0 -> IDLE/0, DONE/1, FAILED/2; DONE/1 -> IDLE/1; IDLE/1 -> the same three.
    result = explore(space("Codel", "Main()", reduce=False))
    assert (result.states, result.transitions) == (4, 7)


def test_deadlock_traces_are_shortest_label_by_label():
    sp = space("Dining", "Table3()")
    result = explore(sp)
    (dead,) = result.deadlocks
    assert [s.label for s in sp.trace_to(dead)] == ["left0", "left1", "left2"]
    sp2 = space("Dining", "Table2()")
    (dead2,) = explore(sp2).deadlocks
    assert [s.label for s in sp2.trace_to(dead2)] == ["left0", "left1"]


def test_codel_outcomes_are_choice_points_named_in_traces():
    sp = space("Codel", "Main()")
    (dead,) = explore(sp).deadlocks
    (step,) = sp.trace_to(dead)
    assert step.label == "run"
    assert step.outcomes == (("plan", 2),)
    assert str(step) == "run  [plan -> throw e_fail]"


def test_deadlocked_state_per_atom_comes_from_the_engine():
    sp = space("Dining", "Table2()")
    (dead,) = explore(sp).deadlocks
    state = sp.concrete(sp.trace_to(dead))
    text = sp.engine.format_state(state)
    assert text.splitlines() == ["p0: ONE", "p1: ONE", "f0: BUSY", "f1: BUSY"]


def test_concrete_state_keeps_what_the_reduction_resets():
    sp = space("Codel", "Main()")
    explore(sp)
    done = next(i for i in range(len(sp)) if sp.engine.describe_state(sp.engine_state(i))["a"]["places"] == ["DONE"])
    trace = sp.trace_to(done)
    assert sp.engine_state(done)[1] == 0  # reset: outcome is dead in DONE
    assert sp.concrete(trace)[1] == 1  # the engine's own value after `plan -> done`


# --- limits and orders --------------------------------------------------------------------------------

def test_max_states_stops_and_says_so():
    result = explore(space("Dining", "Table3()", max_states=5))
    assert result.states == 5 and not result.complete and result.stopped_by == "max-states"


def test_max_depth_bounds_breadth_first_levels():
    result = explore(space("Dining", "Table3()"), max_depth=1)
    # the initial state and its three successors (one philosopher took the left fork)
    assert result.states == 4 and result.stopped_by == "max-depth" and result.deadlocks == []


def test_depth_first_finds_the_same_states():
    bfs = explore(space("Dining", "Table3()"))
    dfs = explore(space("Dining", "Table3()"), dfs=True)
    assert (dfs.states, dfs.transitions, len(dfs.deadlocks)) == (bfs.states, bfs.transitions, 1)


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_line_rewritten_in_place_on_a_terminal():
    err = _Terminal()
    progress = Progress(stream=err, delay=0.0)
    explore(space("Dining", "Table3()"), progress=progress)
    text = err.getvalue()
    assert text.startswith("\r") and "states/s" in text and "frontier" in text and "memory" in text
    assert "\n" not in text and text.endswith("\r")  # cleared for the results


def test_progress_forced_into_a_file_writes_one_line_per_report():
    err = io.StringIO()
    progress = Progress(stream=err, force=True, delay=0.0)
    for n in (10, 20):
        progress.tick(n, 2 * n, 1, lambda: 2048, depth=3)
        progress.next = 0  # due again
    progress.done()
    lines = err.getvalue().split("\n")
    assert "\r" not in err.getvalue() and lines[-1] == ""
    assert [line.split()[1] for line in lines[:-1]] == ["10", "20"]
    assert all("states/s" in line and "depth 3" in line and "memory 2.0 KB" in line for line in lines[:-1])


def test_progress_silent_without_a_terminal():
    err = io.StringIO()
    explore(space("Dining", "Table3()"), progress=Progress(stream=err, delay=0.0))
    assert err.getvalue() == ""


def test_memory_per_state_is_reported():
    result = explore(space("Dining", "Table3()"))
    assert 40 < result.bytes_per_state < 400
    assert result.bits == 3 * 3 + 3 * 2  # three 3-place philosophers, three 2-place forks
    assert "bytes/state" in result.summary()


# --- packing -----------------------------------------------------------------------------------------

COUNTER = """package C
  port type Port()
  atom type Count()
    data int n
    export port Port inc()
    place RUN
    initial to RUN do { n = 0; }
    on inc from RUN to RUN provided (n < 40) do { n = n + 3; }
  end
  connector type One(Port p)
    define p
  end
  compound type Main()
    component Count c()
    connector One inc(c.inc)
  end
end
"""


def test_interned_field_widens_and_states_stay_exact():
    sp = text_space(COUNTER)
    result = explore(sp)
    assert result.states == 15  # n = 0, 3, ..., 42
    assert sorted(sp.state(i)[1] for i in range(len(sp))) == list(range(0, 43, 3))
    assert sp.codec.widths[1] >= 4


def test_canonical_keeps_values_that_widen_the_codec():
    # States the explorer has not met (a tick model's, replayed against zones) may hold values its codec has no
    # room for: packing widens it, and the packed number must be read by the codec that packed it (reading it
    # with the one before gave wrong states, or an IndexError).
    sp = space("Mix", "Main()")
    explore(sp)
    start = sp.state(sp.initial_ids[0])
    for v in range(100, 140):
        wide = start[:1] + (v,) + start[2:]
        assert sp.canonical(wide) == wide
    assert sp.codec.widths[1] > 2
    assert sp.canonical(start) == start


def test_pack_unpack_round_trip_on_every_state():
    sp = space("Mix", "Main()")
    explore(sp)
    for i in range(len(sp)):
        assert sp.codec.pack(sp.state(i)) == sp.packed[i]
    assert "def pack" in sp.codec.source and "def unpack" in sp.codec.source


def test_declared_domain_is_checked():
    text = COUNTER.replace("    data int n", '    @domain(range="0..30")\n    data int n')
    sp = text_space(text)
    result = explore(sp)
    assert result.error is not None and "left its declared domain 0..30: value 33" in result.error.message
    assert [s.label for s in result.error.trace] == ["inc"] * 10


def test_domain_annotation_must_be_a_range():
    text = COUNTER.replace("    data int n", '    @domain(range="zero to ten")\n    data int n')
    with pytest.raises(ExploreError, match="range=\"lo..hi\""):
        text_space(text)


def test_codec_without_reduction_packs_every_variable():
    sp = space("Codel", "Main()", reduce=False)
    codec = Codec.build(sp.slots)
    assert 1 in codec.widths  # outcome has a field


# --- externs and the environment ---------------------------------------------------------------------

EXTERN = """package E
  port type Port()
  extern function int measure()
  atom type A()
    data int x
    export port Port go()
    place S, T
    initial to S
    on go from S to T do { x = measure(); }
  end
  connector type One(Port p)
    define p
  end
  compound type Main()
    component A a()
    connector One go(a.go)
  end
end
"""


def test_unbound_extern_is_refused_with_a_reason():
    with pytest.raises(ExploreError, match="measure.*neither codels.*--externs"):
        text_space(EXTERN)


def test_user_bound_extern_and_user_choice():
    assert explore(text_space(EXTERN, externs={"measure": lambda: 7})).states == 2
    sp = text_space(EXTERN, externs={"measure": Choice("measure", (1, 2, 3))}, reduce=False)
    assert explore(sp).states == 4  # x is never read: with the reduction the three successors would merge
    assert {sp.state(i)[1] for i in range(1, 4)} == {1, 2, 3}


def test_choice_in_a_guard_is_refused():
    text = EXTERN.replace("on go from S to T do { x = measure(); }", "on go from S to T provided (measure() > 0)")
    sp = text_space(text, externs={"measure": Choice("measure", (0, 1))})
    result = explore(sp)
    assert result.error is not None and "called in a guard" in result.error.message


def test_initial_transitions_may_branch():
    text = EXTERN.replace("initial to S\n", "initial to S do { x = measure(); }\n")
    sp = text_space(text, externs={"measure": Choice("measure", (4, 5))}, reduce=False)
    result = explore(sp)
    assert len(sp.initial_ids) == 2 and result.states == 4


def test_request_budget_bounds_the_environment():
    from tests.verifykit import ndd_model

    pkg, root = ndd_model()
    budget0 = explore(StateSpace(pkg, root, requests=0))
    budget1 = explore(StateSpace(pkg, root, requests=1))
    assert budget0.complete and budget1.complete
    # no request at all: only the task's periods and the permanent activity move
    assert budget0.states < budget1.states < 55_680


def test_explorer_reuses_the_engines_compiled_step():
    sp = space("Dining", "Table2()")
    assert isinstance(sp.engine, Engine)
    assert "_enabled(base)" in sp.expand_source and "_FIRE[I.source]" in sp.expand_source
    assert sp.engine.namespace["enabled"] is not None


def test_package_fixture_parses():
    assert package("Mix").name == "Mix"
