"""SPIN and our explorer on the same models: the same number of states, the same deadlock verdicts.

CI installs SPIN (.ci/run); without it the tests that run SPIN are skipped with that reason, and those
about the Promela text and what is refused before SPIN runs still run.
"""
import shutil

import pytest

from runtime.engine import flatten
from runtime.explore import StateSpace, explore
from runtime.export import spin
from runtime.export.interactions import all_interactions
from runtime.export.monitors import build_monitor, spin_shape
from runtime.export.promela import PromelaError, write_promela
from runtime.props import read_properties, read_property_file
from tests.verifykit import FIXTURES, NDD_NO_AFTER, ndd_model, package, text_space

needs_spin = pytest.mark.skipif(shutil.which("spin") is None or shutil.which("gcc") is None,
                                reason="SPIN or gcc is not installed (Debian: apt-get install spin; .ci/run does it)")

FAST = "-O0"  # pan compiles four times faster; these models are small


def both(pkg, root, **kw):
    ours = explore(StateSpace(pkg, root, **kw))
    theirs = spin.verify_deadlocks(StateSpace(pkg, root, **kw), opt=FAST)
    return ours, theirs


@pytest.mark.parametrize("name, root, reduce", [
    ("Dining", "Table2()", True),
    ("Dining", "Table3()", True),
    ("Counters", "Pair()", True),
    ("Codel", "Main()", True),
    ("Codel", "Main()", False),
    ("Mix", "Main()", True),
    ("Server", "Main()", True),
])
@needs_spin
def test_same_states_and_deadlock_verdict(name, root, reduce):
    ours, theirs = both(package(name), root, reduce=reduce)
    assert theirs.report.states == ours.states
    assert theirs.report.errors == len(ours.deadlocks)
    assert theirs.report.complete


@needs_spin
def test_same_on_the_ndd_module():
    pkg, root = ndd_model()
    ours, theirs = both(pkg, root)
    assert ours.states == theirs.report.states == 125_440
    assert theirs.report.errors == 0 and ours.deadlocks == []


@needs_spin
def test_same_when_a_variable_dies_with_a_mission_s_last_request(tmp_path):
    """A done flag reset once the client cannot send a request that reads it (tests/test_client_liveness.py): the
    Promela model resets it after the client's steps too, and SPIN stores the states the explorer does."""
    from test_platform_responses import AFTER, FIXTURES as PLATFORMS, model_of

    model = model_of(tmp_path, AFTER, {}, "cores: 1\n", PLATFORMS / "set_then_go.yaml")
    ours, theirs = both(model.package, model.root)
    flag = next(s for s in StateSpace(model.package, model.root).slots if s.title == "After.Setup.control.done")
    assert flag.alive  # the case this test is for
    assert ours.states == theirs.report.states == 401
    assert theirs.report.errors == len(ours.deadlocks) and theirs.report.complete


@needs_spin
def test_same_when_a_flag_dies_with_the_other_flag_of_its_conjunction(tmp_path):
    """Two done flags read only together (runtime/explore/conjunctions.py): the Promela model resets one where the
    other is false for good, after the steps of either flag's atom or of the client, and SPIN stores the states
    the explorer does."""
    from test_platform_responses import AFTER_BOTH, FIXTURES as PLATFORMS, model_of

    model = model_of(tmp_path, AFTER_BOTH, {}, "cores: 1\n", PLATFORMS / "set_both_then_go.yaml")
    ours, theirs = both(model.package, model.root)
    flag = next(s for s in StateSpace(model.package, model.root).slots if s.title == "AfterBoth.SetA.control.done")
    assert flag.void  # the case this test is for
    assert ours.states == theirs.report.states == 576  # 646 when neither resets the flags
    assert theirs.report.errors == len(ours.deadlocks) and theirs.report.complete


@needs_spin
def test_same_with_a_request_budget():
    pkg, root = ndd_model()
    ours, theirs = both(pkg, root, requests=1)
    assert ours.states == theirs.report.states and theirs.report.errors == 0


@needs_spin
def test_spin_trails_are_replayed_on_the_engine():
    sp = StateSpace(package("Dining"), "Table2()")
    result = spin.verify_deadlocks(sp, opt=FAST)
    (trail,) = result.trails
    assert trail.message == "invalid end state"
    assert [s.label for s in trail.steps] == ["left0", "left1"]
    assert sp.successors(trail.end_state) == ()  # the end of SPIN's trail is a deadlock for our engine too


@needs_spin
def test_codel_outcomes_come_back_from_the_trail():
    result = spin.verify_deadlocks(StateSpace(package("Codel"), "Main()", reduce=False), opt=FAST)
    (trail,) = result.trails
    assert trail.steps[-1].outcome_names == ("plan -> throw e_fail",)


@needs_spin
def test_safety_observers_agree_with_the_explorer():
    pkg, root = ndd_model()
    items, _ = read_property_file(FIXTURES / "goto_after_setspeed.mcl", flatten(pkg, root))
    sp = StateSpace(pkg, root)
    statics = all_interactions(sp.engine)
    assert spin_shape(items[0]) == "observer" and spin_shape(items[2]) == ""
    monitor, _ = build_monitor(items[0], statics, "p0")
    result = spin.verify_safety(sp, [monitor], opt=FAST)
    assert result.report.errors == 0

    mpkg, mroot = ndd_model(str(NDD_NO_AFTER))
    items, _ = read_property_file(FIXTURES / "goto_after_setspeed.mcl", flatten(mpkg, mroot))
    msp = StateSpace(mpkg, mroot)
    monitor, _ = build_monitor(items[0], all_interactions(msp.engine), "p0")
    result = spin.verify_safety(msp, [monitor], opt=FAST)
    assert result.report.errors == 1
    labels = [s.label for s in result.trails[0].steps]
    assert labels[-1] == "NDD.GoTo:trigger" and "NDD.SetSpeed:finish" not in labels


@needs_spin
def test_invariant_observer_reads_places_and_variables():
    pkg = package("Server")
    flat = flatten(pkg, "Main()")
    items, _ = read_properties("a: invariant S.served <= 1; b: invariant not S @ DONE", "p.mcl", flat)
    observed = set().union(*(i.observed for i in items))
    for item, violated in zip(items, (False, True)):
        sp = StateSpace(pkg, "Main()", observed=observed)
        monitor, _ = build_monitor(item, all_interactions(sp.engine), "p")
        result = spin.verify_safety(sp, [monitor], opt=FAST)
        assert (result.report.errors > 0) is violated
    assert [s.label for s in result.trails[0].steps] == ["S.req", "S.work"]


def test_promela_text_has_one_atomic_step_per_interaction():
    sp = StateSpace(package("Mix"), "Main()")
    text = write_promela(sp)
    statics = all_interactions(sp.engine)
    assert text.count(":: atomic { go") == len(statics)
    assert "#define mp" in text and "#define go" in text
    assert "/* bcast */" in text and "/* kick */" in text
    assert "do\n" in text and "od\n" in text


@needs_spin
def test_multi_core_and_bitstate_modes_run():
    pkg = package("Dining")
    cores = spin.verify_deadlocks(StateSpace(pkg, "Table3()"), cores=2, opt=FAST)
    assert cores.report.errors == 1 and [s.label for s in cores.trails[0].steps][-1].startswith("left")
    full = spin.count_states(StateSpace(package("Mix"), "Main()"), cores=2, opt=FAST)
    assert full.states == 9
    bits = spin.verify_deadlocks(StateSpace(pkg, "Table3()"), bitstate=True, hash_bits=20, opt=FAST)
    assert bits.report.states == 14 and bits.report.errors == 1
    swarm = spin.swarm(StateSpace(pkg, "Table3()"), 2, hash_bits=16, opt=FAST)
    assert swarm.report.errors >= 1 and swarm.trails and swarm.trails[0].steps


def test_python_externs_cannot_be_translated():
    from tests.test_explore import EXTERN
    with pytest.raises(PromelaError, match="bound to Python code"):
        write_promela(text_space(EXTERN, externs={"measure": lambda: 1}))


@needs_spin
def test_verify_engine_spin_from_the_command_line(capsys):
    from genom2bip.cli import main
    code = main(["verify", str(FIXTURES / "Dining.bip"), "--root", "Table2()", "--engine", "spin"])
    out = capsys.readouterr().out
    assert code == 4
    assert "SPIN: 6 states" in out and "deadlocks: 1 invalid end state(s) found by SPIN" in out
    assert "       1  left0\n       2  left1" in out and "    p0: ONE" in out


def test_properties_spin_cannot_check_are_refused_before_running(capsys, tmp_path):
    from genom2bip.cli import main
    props = tmp_path / "p.mcl"
    props.write_text('reach: <true* . "S.reply"> true; ok: never "S.fail" . "S.work"')
    code = main(["verify", str(FIXTURES / "Server.bip"), "--engine", "spin", "--property", str(props)])
    captured = capsys.readouterr()
    assert code == 1 and "use --engine explore for: reach" in captured.err and "SPIN:" not in captured.out


# The engine's own fixtures for priorities and broadcasts, with their counters made finite.
BOUNDED = {
    "Priorities": [("t = t + 1;", "t = (t + 1) % 4;")],
    "AtomPriorities": [("x = x + 1;", "x = (x + 1) % 5;"), ("n = n + 1;", "n = (n + 1) % 3;")],
    "Broadcast": [("v = v + 1;", "v = (v + 1) % 3;")],
}


@pytest.mark.parametrize("name, root, states", [
    ("Priorities", "Low()", 16),  # a guarded priority, low side by containment
    ("Priorities", "High()", 16),  # high side by containment
    ("Priorities", "Star()", 4),  # *:* on the low side
    ("Priorities", "Nested()", 16),  # priorities of a sub-compound
    ("AtomPriorities", "System()", 5),  # guarded atom priorities, closure through a disabled port, '*'
    ("Broadcast", "System()", 24),
])
@needs_spin
def test_same_on_the_engines_priority_and_broadcast_fixtures(name, root, states):
    from pathlib import Path
    from runtime.bip2 import parse_text

    text = (Path(__file__).parent / "fixtures" / "engine" / f"{name}.bip").read_text()
    for old, new in BOUNDED[name]:
        text = text.replace(old, new)
    ours, theirs = both(parse_text(text, f"{name}.bip"), root)
    assert ours.states == theirs.report.states == states
    assert theirs.report.errors == len(ours.deadlocks)


IDLE = """package Z
  port type Port()
  atom type A()
    place S
    initial to S
  end
  compound type Main()
    component A a()
  end
end
"""


@needs_spin
def test_a_model_without_interactions_is_one_deadlocked_state():
    assert explore(text_space(IDLE)).deadlocks == [0]
    result = spin.verify_deadlocks(text_space(IDLE), opt=FAST)
    assert result.report.states == 1 and result.report.errors == 1


@needs_spin
def test_pan_progress_lines_are_streamed():
    import io

    from runtime.explore import Progress

    run = spin.SpinRun(StateSpace(ndd_model()[0], ndd_model()[1]), opt=FAST)
    stream = io.StringIO()
    try:
        run.build(extra=("-DFREQ=10000",))  # a progress line every 10,000 states instead of every million
        report = run.pan(["-E", "-n"], progress=Progress(stream, force=True, delay=0))
    finally:
        run.cleanup()
    assert report.states == 125_440
    shown = stream.getvalue()
    assert "states 10,000" in shown and "depth " in shown and "states/s" in shown
