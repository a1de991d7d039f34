"""Missions on the generated DALA controller with its real codels, in ir-sim worlds, through the services client."""
from __future__ import annotations

import math
from itertools import pairwise
from pathlib import Path

import pytest
import yaml

from genom2bip.mission import report
from genom2bip.mission.session import run_mission
from genom2bip.mission.spec import read_mission
from tests.runkit import ROOT, dala

MISSIONS = ROOT / "descriptions" / "dala" / "missions"
CODELS = str(ROOT / "descriptions" / "dala" / "codels")


def _bringup() -> str:
    """The default mission's steps up to its first goal, without the GoTo it sends too early (YAML, indented)."""
    steps = yaml.safe_load((MISSIONS / "corridor.yaml").read_text())["steps"]
    first = next(i for i, s in enumerate(steps) if s.get("send") == "NDD.GoTo" and s.get("expect") == "ok")
    text = yaml.safe_dump([s for s in steps[:first] if s.get("send") != "NDD.GoTo"], sort_keys=False)
    return "".join(f"  {line}\n" for line in text.splitlines())


BRINGUP = _bringup()


def _run(path: Path):
    mission = read_mission(path)
    return run_mission(mission, dala(), CODELS, mission.world)


def _report(run, service: str, index: int = 0) -> dict:
    """The final report of the index-th request to ``service`` (from the controller's events)."""
    outs = [o for o in run.outcomes if o.step.kind == "send" and o.step.target == service]
    rid = outs[index].request
    finals = [e for e in run.events if e["event"] == "report" and e["request"] == rid and e["final"]]
    return finals[-1] if finals else outs[index].report


@pytest.fixture(scope="module")
def corridor(tmp_path_factory):
    """One drive down the corridor, past the two boxes, to (10, 1.5)."""
    path = tmp_path_factory.mktemp("mission") / "corridor_short.yaml"
    path.write_text(f"mission: corridor_short\nworld: {ROOT / 'descriptions/dala/worlds/corridor.yaml'}\nsteps:\n"
                    + BRINGUP + "  - send: NDD.GoTo\n    with: {goal: {x: 10.0, y: 1.5, theta: 0.0}}\n"
                                "    expect: ok\n    timeout: 60\n")
    return _run(path)


def test_corridor_goal_reached_without_collision(corridor):
    assert corridor.ok, [o.problem for o in corridor.outcomes if not o.ok]
    assert _report(corridor, "NDD.GoTo")["status"] == "ok"
    world = corridor.world
    end = world.trajectory[-1]
    assert math.hypot(end.x - 10.0, end.y - 1.5) < 0.3
    assert world.collisions == 0
    # the robot (radius 0.3 m) never touched an obstacle: every sample of its path keeps clear of them
    from shapely.geometry import Point

    clearance = min(g.distance(Point(s.x, s.y)) for s in world.trajectory for g in world.obstacles())
    assert clearance > 0.3
    # and it went round the boxes: below box_high (x 8.1..8.9, y 2..4) on its way
    assert any(8.1 <= s.x <= 8.9 and s.y < 1.7 for s in world.trajectory)


def test_trajectory_png_shows_the_path_from_start_to_goal(corridor, tmp_path):
    from matplotlib.image import imread

    from genom2bip.mission.picture import draw

    png = tmp_path / "corridor.png"
    to_pixel = draw(corridor, png)
    image = imread(png)[:, :, :3]
    blue = (
        (abs(image[:, :, 0] - 0.12) < 0.05) & (abs(image[:, :, 1] - 0.47) < 0.05) & (abs(image[:, :, 2] - 0.71) < 0.05)
    )
    assert blue.sum() > 300  # the trajectory's pixels

    def near(xy, colour, radius=6):
        col, row = to_pixel(*xy)
        patch = image[max(0, row - radius):row + radius, max(0, col - radius):col + radius]
        return (abs(patch - colour).max(axis=2) < 0.08).any()

    assert near((1.0, 2.0), (0.17, 0.63, 0.17))  # start marker (green) where the world puts the robot
    assert near((10.0, 1.5), (0.0, 0.0, 0.0))  # end marker (black) at the goal
    assert not near((14.0, 3.5), (0.12, 0.47, 0.71))  # no path where the robot never went


def test_goto_before_pom_run_is_rejected_with_the_rule_then_served():
    run = _run(MISSIONS / "goto_before_pom.yaml")
    assert run.ok, [o.problem for o in run.outcomes if not o.ok]
    refused = _report(run, "NDD.GoTo", 0)
    assert (refused["status"], refused["reason"], refused["rule"]) == ("rejected", "rule", "goto-after-pom-run")
    assert refused["status_of"]["POM.Run"]["ok"] is False
    assert _report(run, "NDD.GoTo", 1)["status"] == "ok"
    # the report: the rejected request with its rule, the one goal of the drive, every request's end
    from genom2bip.mission.report import text

    lines = text(run).splitlines()
    rejected = next(o.request for o in run.outcomes if o.report.get("status") == "rejected")
    assert f"  rejected by rules: [{rejected}] NDD.GoTo by goto-after-pom-run" in lines
    assert [line.split(":")[0] for line in lines if line.startswith("  goal ")] == ["  goal (3, 2)"]
    assert next(line for line in lines if line.startswith("  goal ")).startswith("  goal (3, 2): reached at ")
    assert f"    [{rejected}] NDD.GoTo: rejected goto-after-pom-run" in lines
    assert any(line.endswith("RFLEX.TrackSpeed: started (ran until the controller stopped)") for line in lines)
    assert lines[-1] == "  every expectation met"


def test_stop_interrupts_goto_and_the_robot_stops_within_a_bounded_distance():
    run = _run(MISSIONS / "stop_during_goto.yaml")
    assert run.ok, [o.problem for o in run.outcomes if not o.ok]
    drive = _report(run, "NDD.GoTo", 0)
    assert (drive["status"], drive["by"]) == ("interrupted", "NDD.Stop")
    stopped_at = _report(run, "NDD.Stop")["time"]
    samples = run.world.trajectory
    before = [s for s in samples if s.t <= stopped_at]
    assert before[-1].x > 2.5  # it was driving when Stop came
    after = [s for s in samples if stopped_at <= s.t <= stopped_at + 2.0]
    moved = sum(math.hypot(b.x - a.x, b.y - a.y) for a, b in pairwise(after))
    assert moved < 0.1
    assert abs(after[-1].v) < 1e-6
    assert _report(run, "NDD.GoTo", 1)["status"] == "ok"  # and the next GoTo is served


def test_dead_end_goto_fails_with_e_blocked_then_a_new_goto_is_served():
    run = _run(MISSIONS / "dead_end.yaml")
    assert run.ok, [o.problem for o in run.outcomes if not o.ok]
    blocked = _report(run, "NDD.GoTo", 0)
    assert blocked["status"] == "failed" and blocked["exception"] == "NDD::e_blocked"
    assert blocked["codel"] == "nddPlan"
    where = blocked["detail"]["where"]
    assert where["x"] < 8.0 - 0.3  # in front of the wall, not through it
    back = _report(run, "NDD.GoTo", 1)
    assert back["status"] == "ok"
    end = run.world.trajectory[-1]
    assert math.hypot(end.x - 2.0, end.y - 6.5) < 0.3
    assert run.world.collisions == 0


def _goto_seconds(run, index: int) -> float:
    """Robot seconds from the index-th GoTo's start to its final report."""
    outs = [o for o in run.outcomes if o.step.kind == "send" and o.step.target == "NDD.GoTo"]
    rid = outs[index].request
    started = next(e["time"] for e in run.events if e["event"] == "report" and e["request"] == rid
                   and e["status"] == "started")
    return _report(run, "NDD.GoTo", index)["time"] - started


def _with_map_cells(mission: Path, resolution: float, folder: Path) -> Path:
    """The mission with Aspect's cells set to ``resolution`` m before its map runs, written under ``folder``."""
    spec = yaml.safe_load(mission.read_text())
    spec["world"] = str((mission.parent / spec["world"]).resolve())
    run = next(i for i, s in enumerate(spec["steps"]) if s.get("send") == "Aspect.Run")
    spec["steps"].insert(run, {"send": "Aspect.SetParams", "with": {"resolution": resolution, "decay": 0.6},
                               "expect": "ok"})
    path = folder / f"{mission.stem}_{resolution:g}.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


@pytest.mark.parametrize("resolution", [None, 0.15], ids=["default_map", "cells_of_0.15m"])
def test_doorway_goto_goes_through_the_door_to_the_far_room(resolution, tmp_path):
    mission = MISSIONS / "doorway.yaml"
    run = _run(mission if resolution is None else _with_map_cells(mission, resolution, tmp_path))
    assert run.ok, [o.problem for o in run.outcomes if not o.ok]
    assert _report(run, "NDD.GoTo")["status"] == "ok"
    world = run.world
    end = world.trajectory[-1]
    assert math.hypot(end.x - 11.0, end.y - 3.0) < 0.3 and world.collisions == 0
    crossing = next(s for a, s in pairwise(world.trajectory) if a.x < 6.0 <= s.x)
    assert 4.35 + 0.3 < crossing.y < 6.25 - 0.3  # through the door, clear of its edges
    from shapely.geometry import Point

    assert min(g.distance(Point(s.x, s.y)) for s in world.trajectory for g in world.obstacles()) > 0.3


def test_u_trap_goto_ends_in_e_blocked_with_its_reason_within_its_bound():
    """A U open towards the robot is a local minimum: GoTo fails with its reason within NDD's bound, unharmed."""
    from runtime.controller.codels import load_codels

    ndd = load_codels(CODELS, ["NDD"]).modules["NDD"]
    run = _run(MISSIONS / "u_trap.yaml")
    assert run.ok, [o.problem for o in run.outcomes if not o.ok]
    blocked = _report(run, "NDD.GoTo", 0)
    assert blocked["status"] == "failed" and blocked["exception"] == "NDD::e_blocked"
    reasons = (f"no navigable gap towards the goal for {ndd.NO_WAY_TIMEOUT:g} s",
               f"no progress of {ndd.PROGRESS:g} m towards the goal in {ndd.PROGRESS_TIMEOUT:g} s")
    assert blocked["detail"]["reason"].startswith(reasons), blocked["detail"]
    distance = math.dist((2.0, 5.0), (11.0, 5.0))
    bound = (distance / ndd.PROGRESS + 1) * ndd.PROGRESS_TIMEOUT + ndd.NO_WAY_TIMEOUT
    assert _goto_seconds(run, 0) <= bound  # robot time: the virtual clock's, whatever the machine's speed
    assert read_mission(MISSIONS / "u_trap.yaml").steps[-2].timeout >= bound  # the mission waits that long
    where = blocked["detail"]["where"]
    assert where["x"] < 8.0 and run.world.collisions == 0  # before the U's bottom, touching nothing
    assert blocked["detail"]["reason"] in report.text(run)  # the report says why
    assert _report(run, "NDD.GoTo", 1)["status"] == "ok"  # and the next GoTo is served


def test_the_trace_has_every_report_and_the_path_in_time_order(corridor, tmp_path):
    import json

    from genom2bip.mission.session import write_trace

    path = tmp_path / "trace.jsonl"
    write_trace(corridor, path)
    lines = [json.loads(line) for line in path.read_text().splitlines()]
    times = [e["time"] for e in lines]
    assert times == sorted(times)
    reports = [e for e in lines if e["event"] == "report" and e["final"]]
    assert [e["status"] for e in reports if e["service"] == "GoTo"] == ["ok"]
    # every request ends with a final report: the activities still running, when the controller stops
    assert {e["request"] for e in reports} == {o.request for o in corridor.outcomes if o.request is not None}
    track = [e for e in reports if e["service"] == "TrackSpeed"]
    assert [(e["status"], e["by"]) for e in track] == [("interrupted", None)]
    poses = [e for e in lines if e["event"] == "pose"]
    assert len(poses) == len(corridor.world.trajectory)
    assert (poses[0]["x"], poses[0]["y"]) == (1.0, 2.0)


def _short_mission(tmp_path: Path) -> Path:
    """The bring-up, then a 2 m drive in the open field."""
    path = tmp_path / "live_short.yaml"
    path.write_text(f"mission: live_short\nworld: {ROOT / 'descriptions/dala/worlds/open_field.yaml'}\nsteps:\n"
                    + BRINGUP + "  - send: NDD.GoTo\n    with: {goal: {x: 3.0, y: 2.0, theta: 0.0}}\n"
                                "    expect: ok\n    timeout: 30\n")
    return path


def _mission_cli(args: list[str], env: dict[str, str]):
    import os
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "genom2bip", "mission", *args], cwd=ROOT, capture_output=True,
                          text=True, timeout=300, env={**os.environ, "PYTHONPATH": str(ROOT), **env})


@pytest.mark.skipif(not __import__("os").environ.get("DISPLAY"), reason="--live needs a display (e.g. xvfb-run)")
def test_live_shows_the_simulation_in_a_window_in_real_time(tmp_path):
    import re

    done = _mission_cli([str(_short_mission(tmp_path)), "--live", "--quiet", "--out", str(tmp_path / "out")], {})
    assert done.returncode == 0, done.stdout + done.stderr
    shown = re.search(r"shown live: (\d+) frames in a (\w+) window", done.stdout)
    assert shown, done.stdout
    assert int(shown.group(1)) > 10 and shown.group(2).lower() != "agg"
    robot, wall = (float(x) for x in re.search(r"in ([\d.]+) s of robot time \(([\d.]+) s wall", done.stdout).groups())
    assert wall >= 0.9 * robot  # live means in real time
    assert (tmp_path / "out" / "live_short.png").is_file()


def test_live_without_a_display_is_refused_and_writes_nothing(tmp_path):
    out = tmp_path / "out"
    done = _mission_cli([str(_short_mission(tmp_path)), "--live", "--out", str(out)],
                        {"DISPLAY": "", "WAYLAND_DISPLAY": ""})
    assert done.returncode == 1
    assert "--live needs a display (DISPLAY is not set)" in done.stderr
    assert not out.exists()


def _counting(counted: dict[str, int], name: str, fn):
    """``fn``, counting its calls under ``name`` (the codel times' own count is checked against it)."""
    import functools

    @functools.wraps(fn)
    def call(*args, **kwargs):
        counted[name] = counted.get(name, 0) + 1
        return fn(*args, **kwargs)

    return call


def test_shutdown_stops_every_module_and_its_codel_times_hold_every_codel_that_ran(monkeypatch):
    from runtime.controller.codel_times import declared
    from runtime.controller.codels import load_codels

    package = dala()
    names = declared(package.INTERFACE)  # Module.Owner.codel of every codel of the level
    # the codels package the run imports (it keeps it by its path), each codel counting its calls
    source = load_codels(CODELS, list(package.INTERFACE["components"]))
    counted: dict[str, int] = {}
    for comp, module in source.modules.items():
        for codel in {n.split(".")[2] for n in names if n.startswith(f"{comp}.")}:
            monkeypatch.setattr(module, codel, _counting(counted, f"{comp}.{codel}", getattr(module, codel)))
    mission = read_mission(MISSIONS / "shutdown.yaml")
    run = run_mission(mission, package, CODELS, mission.world, times=True)
    assert run.ok, [o.problem for o in run.outcomes if not o.ok]
    assert _report(run, "NDD.GoTo")["status"] == "ok"
    for activity, stop in (("NDD.GoTo", "NDD.Stop"), ("RFLEX.TrackSpeed", "RFLEX.Stop"),
                           ("LaserRF.Start", "LaserRF.Stop"), ("Aspect.Run", "Aspect.Stop"),
                           ("Planner.Run", "Aspect.Stop")):
        ended = _report(run, activity, 1 if activity == "NDD.GoTo" else 0)
        assert (ended["status"], ended["by"]) == ("interrupted", stop), activity
    stopped_at = _report(run, "RFLEX.Stop")["time"]
    assert all(abs(s.v) < 1e-6 for s in run.world.trajectory if s.t > stopped_at + 0.1)  # the base braked
    assert _report(run, "POM.Reset")["status"] == "ok" and _report(run, "Planner.Plan")["status"] == "ok"
    # every codel a request can reach ran, and the times hold each of them with the calls it had
    times = run.codel_times
    assert times["clock"] == "virtual"
    recorded: dict[str, int] = {}
    for name, figures in times["codels"].items():
        comp, _, codel = name.split(".")
        recorded[f"{comp}.{codel}"] = recorded.get(f"{comp}.{codel}", 0) + figures["calls"]
        assert figures["task"] == names[name].task and 0 <= figures["cpu"]["p99"] <= figures["cpu"]["max"]
    assert recorded == counted
    assert times["not_run"] == ["NDD.motion.nddShutdown", "POM.fusion.pomEnd", "RFLEX.servo.rflexClose"]
    assert set(times["codels"]) | set(times["not_run"]) == set(names)


def test_with_the_planner_the_u_trap_goal_is_reached_where_nd_alone_ends_in_e_blocked():
    """u_trap_planned.yaml is u_trap.yaml with the Planner brought up: the first GoTo reaches the goal behind the U."""
    plain, planned = (yaml.safe_load((MISSIONS / m).read_text()) for m in ("u_trap.yaml", "u_trap_planned.yaml"))
    same = [s for s in planned["steps"] if not s["send"].startswith("Planner.")]
    assert same[:-2] == plain["steps"][:-2] and same[-2]["with"] == plain["steps"][-2]["with"]  # only the Planner
    run = _run(MISSIONS / "u_trap_planned.yaml")
    assert run.ok, [o.problem for o in run.outcomes if not o.ok]
    first = _report(run, "NDD.GoTo", 0)
    assert first["status"] == "ok"
    at = next(s for s in run.world.trajectory if s.t >= first["time"])
    assert math.dist((at.x, at.y), (11.0, 5.0)) < 0.3 and run.world.collisions == 0
    # it drove into the U (what was never seen counts as free), saw its bottom, and went round an arm
    assert any(s.x > 5.0 and 3.6 < s.y < 6.4 for s in run.world.trajectory)
    assert any(6.0 < s.x < 8.5 and not 3.0 < s.y < 7.0 for s in run.world.trajectory)
    assert _report(run, "NDD.GoTo", 1)["status"] == "ok"


def test_a_closed_world_removes_its_logging_sinks_at_once(monkeypatch):
    # ir-sim gives each environment loguru sinks, removed when the environment is garbage collected unless it was
    # closed.  Collected while loguru's ``add`` runs for the next world, the removal takes the lock ``add`` holds and
    # the process hangs (a test run stopped so): closing a session removes them then and there.
    from loguru import logger

    from runtime.controller.codels import load_codels

    package = dala()
    source = load_codels(CODELS, list(package.INTERFACE["components"]))
    world = __import__(f"{next(iter(source.modules.values())).__package__}.world", fromlist=["load"])
    session = world.load(MISSIONS.parent / "worlds" / "corridor.yaml")
    removed = []
    monkeypatch.setattr(logger, "remove", lambda sink=None: removed.append(sink))
    session.close()
    assert removed and None not in removed  # this session's sinks, by their numbers, not every sink
    monkeypatch.undo()
    again = world.load(MISSIONS.parent / "worlds" / "corridor.yaml")
    assert again.pose() and session.pose()  # both stay readable (a run's pictures read the closed one)
