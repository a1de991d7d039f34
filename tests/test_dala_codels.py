"""The algorithms of the DALA codels on their own: nearness diagram, obstacle grid, odometry, base, position."""
from __future__ import annotations

import importlib
import math

import pytest

from runtime.controller.codels import load_codels
from runtime.genom import Ref, Throw
from tests.runkit import ROOT

_codels = load_codels(str(ROOT / "descriptions" / "dala" / "codels"), ["NDD", "RFLEX", "POM", "LaserRF", "Aspect"])
_package = _codels.modules["NDD"].__package__
nd = importlib.import_module(f"{_package}.nd")
grid = importlib.import_module(f"{_package}.grid")
odometry = importlib.import_module(f"{_package}.odometry")
memory = importlib.import_module(f"{_package}.memory")
RFLEX, POM, LaserRF, NDD, Aspect = (_codels.modules[c] for c in ("RFLEX", "POM", "LaserRF", "NDD", "Aspect"))

P = nd.Params(radius=0.35, security=0.3, dmax=3.2, vmax=0.5, wmax=1.0, cell=0.1)


# -- nearness diagram (the situations: tests/test_dala_nd.py) -------------------------------------------------


def test_a_cell_fills_every_sector_it_covers():
    d = nd.distances([(0.4, 0.0)], 144, size=0.1)
    assert sum(r < math.inf for r in d) == 6  # 0.1 m at 0.4 m spans 14.3 degrees: 6 sectors of 2.5 degrees...
    assert sum(r < math.inf for r in nd.distances([(0.4, 0.0)], 144)) == 1  # ...a point without size, one


def test_gaps_are_where_nearness_jumps_by_more_than_the_diameter():
    d = [math.inf] * 144
    for k in range(60, 80):
        d[k] = 1.0
    d[70] = 1.5  # a step of 0.5 m: less than 2R, no gap
    d[75] = 2.0  # a step of 1 m: more than 2R, a gap on each side
    assert nd.gaps(d, P) == [59, 74, 75, 79]
    assert nd.regions(d, P) == [(60, 74), (75, 75), (76, 79), (80, 59)]


# -- NDD's memory of what the laser saw ---------------------------------------------------------------------


def _map(points, seq, stamp, size=0.1):
    cells = [0] * (64 * 64)
    for x, y in points:
        cells[grid.cell_of(x, y, size, 64)] = grid.OCCUPIED
    return {"resolution": size, "origin": {"x": 0.0, "y": 0.0, "theta": 0.0}, "cells": cells, "seq": seq,
            "stamp": stamp}


def _pos(x, y, theta, stamp):
    return {"estimate": {"x": x, "y": y, "theta": theta}, "covariance": [0.0] * 3, "stamp": stamp}


def test_the_pose_of_a_sweep_is_interpolated_between_poses_and_extrapolated_a_little_past_them():
    poses = [(1.0, {"x": 0.0, "y": 0.0, "theta": 0.0}), (1.1, {"x": 0.1, "y": 0.0, "theta": 0.2})]
    assert memory.pose_at(poses, 1.05) == pytest.approx({"x": 0.05, "y": 0.0, "theta": 0.1})
    assert memory.pose_at(poses, 1.15) == pytest.approx({"x": 0.15, "y": 0.0, "theta": 0.3})
    assert memory.pose_at(poses, 5.0) == pytest.approx({"x": 0.3, "y": 0.0, "theta": 0.6})  # 0.2 s at most
    assert memory.pose_at(poses, 0.0) == poses[0][1]
    across = [(0.0, {"x": 0.0, "y": 0.0, "theta": 3.1}), (1.0, {"x": 0.0, "y": 0.0, "theta": -3.1})]
    assert abs(memory.pose_at(across, 0.5)["theta"]) == pytest.approx(math.pi)  # the short way round


def test_ndd_remembers_what_left_the_laser_s_field_in_the_world_frame_for_a_while():
    """A return placed at the sweep's pose comes back in the robot's new frame, until it is too old or too far."""
    m = memory.Memory()
    seen = memory.update(m, _map([(1.0, 0.0)], seq=1, stamp=0.0), _pos(0.0, 0.0, 0.0, 0.0), 64, keep=2.0, reach=6.4)
    assert seen == [pytest.approx((1.05, 0.05))]
    # the robot turned round and moved 0.5 m: the obstacle is now 1.55 m behind it, no sweep shows it any more
    later = memory.update(m, _map([], seq=2, stamp=1.0), _pos(-0.5, 0.0, math.pi, 1.0), 64, keep=2.0, reach=6.4)
    assert later == [pytest.approx((-1.55, -0.05))]
    assert memory.update(m, _map([], seq=3, stamp=2.5), _pos(-0.5, 0.0, math.pi, 2.5), 64, keep=2.0, reach=6.4) == []
    # a sweep is placed at the pose the robot had when it was taken, not at the latest one
    m = memory.Memory()
    memory.update(m, None, _pos(0.0, 0.0, 0.0, 0.0), 64, keep=2.0, reach=6.4)
    memory.update(m, None, _pos(1.0, 0.0, 0.0, 0.2), 64, keep=2.0, reach=6.4)
    seen = memory.update(m, _map([(1.0, 0.0)], seq=1, stamp=0.1), _pos(1.0, 0.0, 0.0, 0.2), 64, keep=2.0, reach=6.4)
    assert seen == [pytest.approx((0.55, 0.05))]  # taken 0.5 m back: the obstacle is at 1.55 m in the world
    assert memory.update(m, None, _pos(9.0, 0.0, 0.0, 0.3), 64, keep=2.0, reach=6.4) == []  # out of reach: gone


# -- Aspect's grid, LaserRF's sweep ---------------------------------------------------------------------------


def test_a_beam_marks_the_cell_of_its_end_and_old_cells_decay():
    scan = {"angle_min": 0.0, "angle_step": math.pi / 2, "range_max": 5.0, "ranges": [1.0, 5.0]}
    cells = grid.fuse(scan, None, 0.1, 64, 0.6)
    assert grid.points(cells, 0.1, 64) == [(1.05, 0.05)]  # the beam along x; the second one hit nothing
    later = grid.fuse({**scan, "ranges": [5.0, 5.0]}, cells, 0.1, 64, 0.6)
    assert grid.points(later, 0.1, 64) == [(1.05, 0.05)]  # missed once, it stays one sweep
    assert grid.points(grid.fuse({**scan, "ranges": [5.0, 5.0]}, later, 0.1, 64, 0.6), 0.1, 64) == []


def test_aspect_builds_its_map_with_the_setparams_cell_size_and_decay():
    scan = {"angle_min": 0.0, "angle_step": math.pi / 2, "range_max": 5.0, "ranges": [1.0, 5.0], "seq": 1,
            "stamp": 0.5}
    obs, last = Ref(None), Ref(0)
    assert Aspect.aspReset(0.0, obs) == "fuse"  # before SetParams: 0.1 m cells
    Aspect.aspFuse(scan, 0.0, 0.0, last, obs)
    assert obs.value["resolution"] == 0.1 and grid.points(obs.value["cells"], 0.1, 64) == [(1.05, 0.05)]
    assert obs.value["stamp"] == 0.5  # the sweep's: where NDD places it
    Aspect.aspFuse({**scan, "seq": 2}, 0.25, 0.0, last, obs)  # SetParams(resolution=0.25, decay=0): a new map
    assert obs.value["resolution"] == 0.25 and grid.points(obs.value["cells"], 0.25, 64) == [(1.125, 0.125)]
    assert last.value == 2
    Aspect.aspFuse({**scan, "ranges": [5.0, 5.0], "seq": 3}, 0.25, 0.0, last, obs)
    assert grid.points(obs.value["cells"], 0.25, 64) == []  # decay 0: a return missed once is gone
    Aspect.aspFuse({**scan, "seq": 4}, 0.25, 0.9, last, obs)
    Aspect.aspFuse({**scan, "ranges": [5.0, 5.0], "seq": 5}, 0.25, 0.9, last, obs)
    Aspect.aspFuse({**scan, "ranges": [5.0, 5.0], "seq": 6}, 0.25, 0.9, last, obs)
    assert grid.points(obs.value["cells"], 0.25, 64) == [(1.125, 0.125)]  # decay 0.9: it stays for sweeps
    with pytest.raises(Throw):
        Aspect.aspCheckParams(0.0, 0.5)


def test_sweep_keeps_the_configured_beams_and_range():
    raw = {"angle_min": -1.0, "angle_step": 0.5, "range_max": 6.0, "ranges": [1.0, 7.0, 2.0, 6.0, 3.0]}
    got = LaserRF.sweep(raw, beams=3, max_range=4.0)
    assert got["ranges"] == [1.0, 2.0, 3.0] and got["angle_step"] == 1.0 and got["range_max"] == 4.0
    assert LaserRF.sweep(raw, beams=10, max_range=4.0)["ranges"] == [1.0, 4.0, 2.0, 4.0, 3.0]


# -- odometry, base, position ------------------------------------------------------------------------------------


def test_integration_on_an_arc_and_poses_between_frames():
    quarter = odometry.integrate({"x": 0.0, "y": 0.0, "theta": 0.0}, v=math.pi / 2, w=math.pi / 2, dt=1.0)
    assert quarter == pytest.approx({"x": 1.0, "y": 1.0, "theta": math.pi / 2})
    a, b = {"x": 1.0, "y": 2.0, "theta": 0.5}, {"x": -0.5, "y": 0.3, "theta": -1.0}
    assert odometry.between(a, odometry.compose(a, b)) == pytest.approx(b)


def test_the_base_speeds_up_under_its_acceleration_limit_and_brakes_at_once():
    still = {"v": 0.0, "w": 0.0}
    up = RFLEX.limited(still, {"v": 0.5, "w": 0.3}, acceleration_max=0.4, dt=0.025)
    assert up == pytest.approx({"v": 0.01, "w": 0.3})
    assert RFLEX.limited({"v": 0.5, "w": 0.0}, still, 0.4, 0.025) == still


def test_pom_anchors_odometry_at_the_origin_and_follows_it():
    estimate, initialised, pos = Ref({"covariance": [0.0] * 3}), Ref(False), Ref(None)
    odo = {"position": {"x": 0.5, "y": 0.0, "theta": math.pi / 2}, "stamp": 1.0}
    assert POM.pomFix({"x": 1.0, "y": 2.0, "theta": 0.0}, odo, estimate, initialised, pos) == "ether"
    assert pos.value["estimate"] == pytest.approx({"x": 1.0, "y": 2.0, "theta": 0.0})
    moved = {"position": {"x": 0.5, "y": 1.0, "theta": math.pi / 2}, "stamp": 2.0}  # 1 m along the odometry's y
    POM.pomUpdate(True, moved, estimate, pos)
    assert pos.value["estimate"] == pytest.approx({"x": 2.0, "y": 2.0, "theta": 0.0})  # = 1 m ahead in the world
    assert pos.value["covariance"][0] > 0


def test_ndd_blocked_after_no_way_or_no_progress():
    progress = {"best": math.inf, "since": None, "no_way_since": None}
    assert NDD.blocked(progress, 5.0, True, 0.0) is None
    assert NDD.blocked(progress, 4.0, False, 1.0) is None
    assert "no navigable gap" in NDD.blocked(progress, 4.0, False, 1.0 + NDD.NO_WAY_TIMEOUT + 0.1)
    progress = {"best": math.inf, "since": None, "no_way_since": None}
    NDD.blocked(progress, 5.0, True, 0.0)
    assert NDD.blocked(progress, 4.9, True, NDD.PROGRESS_TIMEOUT - 1) is None
    assert "no progress" in NDD.blocked(progress, 4.9, True, NDD.PROGRESS_TIMEOUT + 0.1)


def test_ndd_gives_up_within_its_bound_whatever_the_robot_does():
    """A GoTo starting d m from its goal ends within (d / PROGRESS + 1) * PROGRESS_TIMEOUT s."""
    start = 6.0
    bound = (start / NDD.PROGRESS + 1) * NDD.PROGRESS_TIMEOUT
    step = 0.1  # NDD's period

    def creeping(t: float) -> float:  # just enough progress, just in time, every time
        return start - (NDD.PROGRESS + 0.01) * math.floor(t / (NDD.PROGRESS_TIMEOUT - 0.1))

    def wandering(t: float) -> float:
        return start + 0.5 * math.sin(t)

    for distance in (creeping, wandering):
        progress = {"best": math.inf, "since": None, "no_way_since": None}
        t = 0.0
        while NDD.blocked(progress, max(distance(t), 0.2), True, t) is None:
            t += step
            assert t <= bound, distance
    assert t < 2 * NDD.PROGRESS_TIMEOUT  # the wandering robot gives up at once


def test_ndd_throws_e_blocked_with_its_reason_and_stops_the_robot():
    """Enclosed, GoTo's step sets the speed to zero and throws e_blocked whose detail says where and why."""
    ring = [(1.0 * math.cos(a / 60 * 2 * math.pi), 1.0 * math.sin(a / 60 * 2 * math.pi)) for a in range(60)]
    obs = {"resolution": 0.1, "origin": {"x": 0.0, "y": 0.0, "theta": 0.0}, "cells": [0] * (64 * 64), "seq": 1,
           "stamp": 0.0}
    for x, y in ring:
        obs["cells"][grid.cell_of(x, y, 0.1, 64)] = grid.OCCUPIED
    params = {"robot_radius": 0.35, "security_distance": 0.3, "goal_tolerance": 0.15}
    speed = Ref({"v": 0.3, "w": 0.0})
    nav = Ref(None)
    NDD.nddStartGoTo({"x": 5.0, "y": 0.0, "theta": 0.0}, Ref(None), Ref(False), nav)
    assert nav.value["active"] and nav.value["goal"] == {"x": 5.0, "y": 0.0, "theta": 0.0}
    t, thrown = 0.0, None
    while thrown is None and t < 10:
        pos = {"estimate": {"x": 0.0, "y": 0.0, "theta": 0.0}, "covariance": [0.0] * 3, "stamp": t}
        try:
            assert NDD.nddPlan({"x": 5.0, "y": 0.0, "theta": 0.0}, params, {"v": 0.5, "w": 1.0}, obs, pos,
                               None, speed, nav) == "pause::plan"
        except Throw as err:
            thrown = err
        t += 0.1
    assert thrown is not None and thrown.name == "e_blocked"
    assert thrown.detail["reason"] == f"no navigable gap towards the goal for {NDD.NO_WAY_TIMEOUT:g} s"
    assert thrown.detail["where"] == {"x": 0.0, "y": 0.0, "theta": 0.0}
    assert NDD.NO_WAY_TIMEOUT < t < NDD.NO_WAY_TIMEOUT + 0.5
    assert speed.value == {"v": 0.0, "w": 0.0}
    assert not nav.value["active"] and nav.value["stalls"] == 0  # no Planner: nothing asked, the planner told

