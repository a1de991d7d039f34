"""The mission report tells the truth: real time held or not, per task; "reached" within the tolerance; no goal
invented for a refused request.  The overrunning run is deterministic: a codel takes time on the virtual clock."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from genom2bip.cli.command import main
from genom2bip.mission import report
from genom2bip.mission.runner import Outcome
from genom2bip.mission.session import Run, load_package, run_mission
from genom2bip.mission.spec import read_mission
from runtime.controller.timing import VirtualClock

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
SLOW = 3  # the sense task's read codel is slow this many times, then never again
TAKES = 0.11  # s on the virtual clock: more than two 50 ms periods (the period overruns, the next one is missed)

MISSION = """
mission: slow
steps:
  - send: thermo.SetLimit
    with: {limit: 25.0}
    expect: ok
  - wait: 5
"""


@pytest.fixture(scope="module")
def thermo(tmp_path_factory):
    """The thermo example generated into a fresh folder, and its codels module."""
    out = tmp_path_factory.mktemp("gen")
    assert main([str(EXAMPLES / "thermo.gen"), "-I", str(EXAMPLES / "include"), "-D", "SIM=1", "-o", str(out)]) == 0
    spec = importlib.util.spec_from_file_location("thermo_codels_for_report", EXAMPLES / "codels" / "thermo.py")
    codels = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(codels)
    return load_package(out / "thermo"), codels


def _slow_codels(codels, clock: VirtualClock) -> dict:
    """The example's codels, its read codel taking TAKES s of virtual time at its 10th, 20th, ... call, SLOW times."""
    functions = {name: getattr(codels, name) for name in dir(codels) if name.startswith("thermo")}
    calls = {"n": 0}

    def thermoRead(now, Room):
        calls["n"] += 1
        if calls["n"] % 10 == 0 and calls["n"] <= 10 * SLOW:
            clock.advance(clock.now() + TAKES)
        return codels.thermoRead(now=now, Room=Room)

    functions["thermoRead"] = thermoRead
    return {"thermo": functions}


def test_a_run_whose_codel_outlasts_its_period_reports_each_overrun_and_fails(thermo, tmp_path):
    package, codels = thermo
    path = tmp_path / "slow.yaml"
    path.write_text(MISSION)
    clock = VirtualClock()
    run = run_mission(read_mission(path), package, _slow_codels(codels, clock), None, clock=clock)
    assert run.expectations_met and not run.real_time_held and not run.ok
    (sense,) = run.timing
    assert (sense["task"], sense["missed"], sense["overruns"]) == ("thermo.sense", SLOW, SLOW)
    assert sense["periods"] + sense["missed"] >= 5 / 0.05  # the 5 s wait: at least 100 periods were due
    text = report.text(run)
    row = next(line for line in text.splitlines() if line.strip().startswith("thermo.sense"))
    assert row.split()[1:] == ["50", "ms", str(sense["periods"] + sense["missed"]), str(SLOW), str(SLOW), "0"]
    assert f"real time NOT held: {SLOW} period(s) missed, {SLOW} overran, 0 codel(s) late" in text
    assert "every expectation met" not in text
    assert text.splitlines()[-1].startswith("  every step ended as expected, but real time did not hold")


def test_the_same_run_without_the_slow_codel_holds_real_time(thermo, tmp_path):
    package, codels = thermo
    path = tmp_path / "slow.yaml"
    path.write_text(MISSION)
    run = run_mission(read_mission(path), package, {"thermo": {n: getattr(codels, n) for n in dir(codels)
                                                                if n.startswith("thermo")}}, None)
    assert run.ok and run.timing[0]["missed"] == run.timing[0]["overruns"] == 0
    text = report.text(run)
    assert "real time held: no period missed or overrun, no codel late (1 task(s))" in text
    assert text.splitlines()[-1] == "  every expectation met"


def test_codels_late_are_counted_per_task_from_the_controllers_events(thermo, tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text(MISSION)
    timing = [{"task": "thermo.sense", "period_ms": 50.0, "periods": 40, "missed": 0, "overruns": 0}]
    events = [{"event": "codel_overrun", "codel": "thermoRead", "task": "thermo.sense"}] * 2 + [
        {"event": "codel_overrun", "codel": "thermoCheckLimit", "task": None, "service": "thermo.SetLimit"}]
    run = Run(read_mission(path), None, [], events, sim_time=2.0, timing=timing, clock="real")
    text = report.text(run)
    assert "  timing over 2.0 s of controller time (real clock):" in text
    assert [line.split() for line in text.splitlines() if "thermo.sense " in line] == [
        ["thermo.sense", "50", "ms", "40", "0", "0", "2"]]
    assert "    thermo.SetLimit: 1 codel(s) past their bound" in text
    assert "real time NOT held: 0 period(s) missed, 0 overran, 3 codel(s) late" in text


GOALS = """
mission: goals
steps:
  - send: NDD.SetParams
    with: {params: {robot_radius: 0.35, security_distance: 0.3, goal_tolerance: 0.15}}
    expect: ok
  - send: NDD.GoTo
    with: {goal: {x: 7.0, y: 2.4, theta: 0.0}}
  - send: NDD.GoTo
    with: {goal: {x: 3.0, y: 1.0, theta: 0.0}}
  - send: NDD.GoTo
  - send: NDD.GoTo
    with: {goal: {x: 1.0, y: 1.0, theta: 0.0}}
"""


def _goal_run(tmp_path) -> Run:
    path = tmp_path / "goals.yaml"
    path.write_text(GOALS)
    mission = read_mission(path)
    reports = [{"status": "ok", "component": "NDD", "service": "SetParams"},
               {"status": "ok", "component": "NDD", "service": "GoTo", "time": 30.0, "final": True},
               {"status": "ok", "component": "NDD", "service": "GoTo", "time": 40.0, "final": True},
               {"status": "rejected", "component": "NDD", "service": "GoTo", "exception": "NDD::e_no_goal",
                "final": True},
               {"status": "rejected", "component": "NDD", "service": "GoTo", "exception": "NDD::e_no_goal",
                "final": True}]
    outcomes = [Outcome(step, request=i + 1, report=r) for i, (step, r) in enumerate(zip(mission.steps, reports))]
    return Run(mission, None, outcomes, goal_ends={2: (5.5, 1.6), 3: (3.1, 1.0), 5: (9.0, 9.0)})


def test_a_goal_is_reached_only_within_the_tolerance_it_was_given(tmp_path):
    lines = report.text(_goal_run(tmp_path)).splitlines()
    goals = [line for line in lines if line.startswith("  goal ")]
    assert goals[0] == "  goal (7, 2.4): not reached: GoTo ended ok at 30.0 s, but 1.70 m from it, beyond " \
                       "goal_tolerance 0.15 m"
    assert goals[1] == "  goal (3, 1): reached at 40.0 s, 0.10 m from it (within goal_tolerance 0.15 m)"


def test_a_refused_goto_has_no_invented_goal_and_no_distance(tmp_path):
    lines = report.text(_goal_run(tmp_path)).splitlines()
    goals = [line for line in lines if line.startswith("  goal ")]
    assert len(goals) == 3 and not any("(0, 0)" in line for line in goals)  # the GoTo sent without a goal: none
    assert goals[2] == "  goal (1, 1): refused: NDD::e_no_goal"
    refused = report.goals(_goal_run(tmp_path))[2]
    assert refused["distance_left"] is None and not refused["reached"]  # where the robot was is not its distance


def test_the_picture_counts_as_reached_only_the_goals_within_their_tolerance(tmp_path):
    reached = [g["reached"] for g in report.goals(_goal_run(tmp_path))]
    assert reached == [False, True, False]  # the first GoTo ended ok 1.70 m away: not reached
