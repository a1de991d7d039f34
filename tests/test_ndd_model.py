"""The NDD module of the paper as generated: its structure (Fig. 7) and its behaviour on the engine."""
from __future__ import annotations

from pathlib import Path

import pytest

from genom2bip.build import build_package
from genom2bip.parser import parse_paths
from genomkit import engine_for, labels, places, walk
from runtime.model import Binary, PortData

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def package():
    return build_package(parse_paths([ROOT / "descriptions/dala/NDD.gen"]), "NDD")


@pytest.fixture
def run(package):
    return engine_for(package, "NDD()")


# --------------------------------------------------------------------------- structure (Fig. 7)


def test_six_services_a_control_task_and_their_posters(package):
    """The paper's structure, with the Nav poster beside Speed (the goal NDD drives to, for the Planner)."""
    module = next(c for c in package.compound_types if c.name == "NDD_Module")
    assert [c.name for c in module.components] == [
        "requests", "Speed", "Nav", "motion", "control", "SetParams", "SetSpeed", "SetDataSource", "GoTo", "Stop"]
    motion = next(c for c in package.compound_types if c.name == "NDD_motion_Task")
    assert [(c.type, c.name) for c in motion.components] == [
        ("Timer", "timer"), ("Scheduler", "scheduler"), ("NDD_motion_Activity", "permanent")]
    goto = next(c for c in package.compound_types if c.name == "NDD_GoTo_Service")
    assert [(c.type, c.name) for c in goto.components] == [
        ("NDD_GoTo_Control", "control"), ("NDD_GoTo_Activity", "activity")]


def _labelled(package, label):
    for compound in package.compound_types:
        for c in compound.connectors:
            if any(a.name == "label" and a.arguments.get("name") == label for a in c.annotations):
                return compound, c
    raise AssertionError(f"no connector labelled {label}")


def _compound(package, name):
    return next(c for c in package.compound_types if c.name == name)


def test_interruption_connector_joins_stop_start_and_goto_abort(package):
    """Stop's start aborts GoTo: the ports of each service meet in a sub-connector, bound once from the module."""
    module, stop_start = _labelled(package, "NDD.Stop:start")
    assert module.name == "NDD_Module"
    assert [str(p) for p in stop_start.ports] == ["Stop.start", "GoTo.Stop_start"]
    define = package.connector_type(stop_start.type).define.items
    # (p1)' p2: Stop's own start is the trigger; GoTo's abort or cancel joins when it can
    assert define[0].trigger and [d.name for d in define[0].items] == ["p1"]
    assert [(d.name, d.trigger) for d in define[1:]] == [("p2", False)]
    stop, goto = _compound(package, "NDD_Stop_Service"), _compound(package, "NDD_GoTo_Service")
    start = next(c for c in stop.connectors if c.name == "start")
    assert [str(p) for p in start.ports] == ["control.start", "activity.start"]
    assert not package.connector_type(start.type).define.items[0].trigger  # both, or nothing
    victim = next(c for c in goto.connectors if c.name == "Stop_start")
    assert [str(p) for p in victim.ports] == ["activity.abort", "control.cancel"]
    assert all(d.trigger for d in package.connector_type(victim.type).define.items)  # whichever can
    assert [(str(e.targets[0]), e.name) for e in goto.ports if e.name == "Stop_start"] == [
        ("Stop_start.ep", "Stop_start")
    ]


def test_goto_constraint_connector_reads_the_three_status_ports(package):
    _, trigger = _labelled(package, "NDD.GoTo:trigger")
    assert [str(p) for p in trigger.ports] == [
        "requests.GoTo", "GoTo.control_trigger",
        "SetParams.control_status", "SetSpeed.control_status", "SetDataSource.control_status"]
    guard = package.connector_type(trigger.type).interactions[0].guard
    done = [PortData(f"p{i}", "done") for i in (3, 4, 5)]
    assert guard == Binary("&&", Binary("&&", done[0], done[1]), done[2])


# --------------------------------------------------------------------------- behaviour


def _ready_for_goto(engine):
    """Complete SetParams, SetSpeed (attributes) and SetDataSource (a function run by the control task)."""
    s = engine.initial_state()
    s = walk(engine, s, "NDD.SetParams:trigger", "NDD.SetParams:start", "NDD.SetParams:finish",
             "NDD.SetSpeed:trigger", "NDD.SetSpeed:start", "NDD.SetSpeed:finish",
             "NDD.SetDataSource:trigger", "NDD.SetDataSource:start", "NDD.control:period",
             "NDD.SetDataSource:exec_start", "NDD.SetDataSource:finish")
    return s


def test_goto_is_refused_until_its_three_constraints_have_completed(run):
    engine, _ = run
    s = engine.initial_state()
    assert "NDD.GoTo:refuse" in labels(engine, s) and "NDD.GoTo:trigger" not in labels(engine, s)
    s = walk(engine, s, "NDD.SetParams:trigger", "NDD.SetParams:start", "NDD.SetParams:finish",
             "NDD.SetSpeed:trigger", "NDD.SetSpeed:start", "NDD.SetSpeed:finish")
    assert "NDD.GoTo:refuse" in labels(engine, s), "SetDataSource has not completed yet"
    s = _ready_for_goto(engine)
    assert "NDD.GoTo:trigger" in labels(engine, s) and "NDD.GoTo:refuse" not in labels(engine, s)
    refusal = engine.find(engine.initial_state(), "NDD.GoTo:refuse")
    assert refusal.ports[1] == "NDD.GoTo.control.refuse"


def test_validate_codel_rejects_bad_parameters(run):
    engine, codels = run
    s = _ready_for_goto(engine)
    codels.next["nddCheckGoal"] = 1  # throws e_no_goal
    s = walk(engine, s, "NDD.GoTo:trigger")
    assert "NDD.GoTo:reject" in labels(engine, s) and "NDD.GoTo:start" not in labels(engine, s)
    s = walk(engine, s, "NDD.GoTo:reject")
    assert places(engine, s, "NDD.GoTo.control") == ["IDLE"]
    assert codels.calls[-1] == "nddCheckGoal"


def _goto_planning(engine):
    s = _ready_for_goto(engine)
    s = walk(engine, s, "NDD.GoTo:trigger", "NDD.GoTo:start", "NDD.motion:period", "NDD.motion:exec_start",
             "NDD.GoTo:exec_start")
    assert places(engine, s, "NDD.GoTo.activity") == ["PLAN"]
    return s


def test_pause_waits_for_the_next_period_and_the_period_ends_only_when_no_codel_can_run(run):
    engine, codels = run
    s = _goto_planning(engine)
    assert "NDD.motion:sleep" not in labels(engine, s), "a codel can still run in this period"
    s = walk(engine, s, "NDD.GoTo:exec_plan")  # yields pause::plan (outcome 0)
    assert places(engine, s, "NDD.GoTo.activity") == ["PLAN_PAUSED"]
    s = walk(engine, s, "NDD.motion:exec_publish")  # the permanent activity pauses too
    assert "NDD.motion:sleep" in labels(engine, s)
    s = walk(engine, s, "NDD.motion:sleep")
    period = engine.find(s, "NDD.motion:period")
    assert set(period.ports) == {"NDD.motion.timer.trigger", "NDD.motion.scheduler.period",
                                 "NDD.motion.permanent.wake", "NDD.GoTo.activity.wake"}
    s = engine.fire(s, period)
    assert places(engine, s, "NDD.GoTo.activity") == ["PLAN"]


def test_stop_interrupts_a_running_goto_before_it_runs_another_codel(run):
    engine, codels = run
    s = _goto_planning(engine)
    s = walk(engine, s, "NDD.Stop:trigger")
    enabled = labels(engine, s)
    assert "NDD.Stop:start" in enabled and "NDD.GoTo:exec_plan" not in enabled  # priority
    start = engine.find(s, "NDD.Stop:start")
    assert "NDD.GoTo.activity.abort" in start.ports
    s = engine.fire(s, start)
    assert places(engine, s, "NDD.GoTo.activity") == ["STOP"]
    s = walk(engine, s, "NDD.GoTo:exec_stop")
    assert codels.calls[-1] == "nddStopGoTo"
    assert "NDD.GoTo:interrupted" in labels(engine, s) and "NDD.GoTo:finish" not in labels(engine, s)
    s = walk(engine, s, "NDD.GoTo:interrupted")
    assert places(engine, s, "NDD.GoTo.control") == ["IDLE"]


def test_stop_without_a_running_goto_starts_alone(run):
    engine, _ = run
    s = walk(engine, engine.initial_state(), "NDD.Stop:trigger")
    start = engine.find(s, "NDD.Stop:start")
    assert start.ports == ("NDD.Stop.control.start", "NDD.Stop.activity.start")


def test_thrown_exception_fails_the_service_and_the_status_says_so(run):
    engine, codels = run
    s = _goto_planning(engine)
    codels.next["nddPlan"] = 2  # yields are pause::plan, arrived; 2 = first exception (e_no_goal)
    s = walk(engine, s, "NDD.GoTo:exec_plan")
    assert "NDD.GoTo:fail" in labels(engine, s)
    s = walk(engine, s, "NDD.GoTo:fail")
    control = engine.describe_state(s)["NDD.GoTo.control"]
    assert control["places"] == ["IDLE"] and control["data"]["ok"] is False and control["data"]["done"] is False


def test_undeclared_outcome_fails_instead_of_blocking(run):
    engine, codels = run
    s = _goto_planning(engine)
    codels.next["nddPlan"] = -1
    s = walk(engine, s, "NDD.GoTo:exec_plan")
    assert places(engine, s, "NDD.GoTo.activity") == ["FAILED"]


def test_goto_arrives_and_reports_finish(run):
    engine, codels = run
    s = _goto_planning(engine)
    codels.next["nddPlan"] = 1  # arrived
    s = walk(engine, s, "NDD.GoTo:exec_plan", "NDD.GoTo:exec_arrived", "NDD.GoTo:finish")
    control = engine.describe_state(s)["NDD.GoTo.control"]
    assert control["data"]["done"] is True and control["data"]["ok"] is True


def test_stop_cancels_a_goto_accepted_but_not_started(run):
    engine, _ = run
    s = walk(engine, _ready_for_goto(engine), "NDD.GoTo:trigger", "NDD.Stop:trigger")
    assert places(engine, s, "NDD.GoTo.control") == ["CHECK"]
    start = engine.find(s, "NDD.Stop:start")
    assert "NDD.GoTo.control.cancel" in start.ports and "NDD.GoTo.activity.abort" not in start.ports
    s = engine.fire(s, start)
    assert places(engine, s, "NDD.GoTo.control") == ["IDLE"]
    assert "NDD.GoTo:start" not in labels(engine, s)
    assert engine.describe_state(s)["NDD.GoTo.control"]["data"]["running"] is False
