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
RFLEX, POM, LaserRF, NDD, Aspect = (_codels.modules[c] for c in ("RFLEX", "POM", "LaserRF", "NDD", "Aspect"))

P = nd.Params(radius=0.35, security=0.3, dmax=3.2, vmax=0.5, wmax=1.0, cell=0.1)


def wall(x0, y0, x1, y1, step=0.05):
    """Points along a segment, as the obstacle grid gives them."""
    n = max(1, int(math.hypot(x1 - x0, y1 - y0) / step))
    return [(x0 + (x1 - x0) * i / n, y0 + (y1 - y0) * i / n) for i in range(n + 1)]


# -- nearness diagram ------------------------------------------------------------------------------------


def test_a_cell_fills_every_sector_it_covers():
    d = nd.distances([(0.4, 0.0)], 144, size=0.1)
    assert sum(r < math.inf for r in d) == 6  # 0.1 m at 0.4 m spans 14.3 degrees: 6 sectors of 2.5 degrees...
    assert sum(r < math.inf for r in nd.distances([(0.4, 0.0)], 144)) == 1  # ...a point without size, one


def test_gaps_are_where_nearness_jumps_by_more_than_the_diameter():
    d = [math.inf] * 144
    for k in range(60, 80):
        d[k] = 1.0
    pnd = nd.nearness(d, P)
    assert nd.gaps(pnd, P) == [59, 79]
    valleys = nd.valleys(pnd, P)
    # the free region around the obstacle rises at both ends: two valleys, one per rising gap
    assert {(v.rising, v.other) for v in valleys} == {(80, 59), (59, 80)}


def test_free_space_goes_straight_to_the_goal():
    got = nd.decide([], (3.0, 1.0), P)
    assert got.situation == "HSGR"
    assert got.direction == pytest.approx(math.atan2(1, 3))
    assert got.v > 0


def test_a_goal_nearer_than_the_obstacles_behind_it_is_in_the_free_walking_area():
    got = nd.decide(wall(2.5, -2, 2.5, 2), (1.5, 0.2), P)
    assert got.situation == "HSGR" and got.direction == pytest.approx(math.atan2(0.2, 1.5))


def test_a_wall_with_an_opening_on_the_left_leads_through_the_opening():
    points = wall(1.5, -3, 1.5, 0.6) + wall(1.5, 1.8, 1.5, 3)  # the wall x = 1.5, open for 0.6 < y < 1.8
    got = nd.decide(points, (4.0, 0.0), P)
    assert got is not None and got.direction > 0.2  # towards the opening, not into the wall ahead
    assert got.situation in ("HSNR", "HSWR", "HSGR")


def test_wide_and_narrow_free_walking_areas():
    wide = nd.decide(wall(1.0, -3, 1.0, 0.0) + wall(1.0, 0.0, 3.0, 0.0), (3.0, -1.0), P)
    assert wide.situation == "HSWR"
    # a slot 1.2 m wide between two walls ahead; the goal beyond it, off the slot's axis
    slot = wall(0.8, 0.6, 3.0, 0.6) + wall(0.8, -0.6, 3.0, -0.6)
    narrow = nd.decide(slot, (5.0, 1.5), P)
    assert narrow.situation == "HSNR"
    assert abs(narrow.direction) < math.radians(12)  # down the middle of the slot


def test_low_safety_on_one_side_turns_away_from_the_obstacle():
    got = nd.decide(wall(0.0, -0.55, 2.0, -0.55), (3.0, 0.0), P)  # a wall 0.55 m on the right
    assert got.situation == "LS1"
    assert got.direction > 0  # away from it, to the left
    assert 0 < got.v < P.vmax


def test_low_safety_on_both_sides_keeps_to_the_middle():
    corridor = wall(-0.5, 0.55, 3.0, 0.55) + wall(-0.5, -0.6, 3.0, -0.6)
    got = nd.decide(corridor, (2.5, 0.0), P)
    assert got.situation == "LS2"
    assert abs(got.direction) < 0.3


def test_enclosed_robot_has_no_free_walking_area():
    ring = [(1.0 * math.cos(a / 100 * 2 * math.pi), 1.0 * math.sin(a / 100 * 2 * math.pi)) for a in range(100)]
    assert nd.decide(ring, (3.0, 0.0), P) is None


# -- Aspect's grid, LaserRF's sweep ---------------------------------------------------------------------------


def test_a_beam_marks_the_cell_of_its_end_and_old_cells_decay():
    scan = {"angle_min": 0.0, "angle_step": math.pi / 2, "range_max": 5.0, "ranges": [1.0, 5.0]}
    cells = grid.fuse(scan, None, 0.1, 64, 0.6)
    assert grid.points(cells, 0.1, 64) == [(1.05, 0.05)]  # the beam along x; the second one hit nothing
    later = grid.fuse({**scan, "ranges": [5.0, 5.0]}, cells, 0.1, 64, 0.6)
    assert grid.points(later, 0.1, 64) == [(1.05, 0.05)]  # missed once, it stays one sweep
    assert grid.points(grid.fuse({**scan, "ranges": [5.0, 5.0]}, later, 0.1, 64, 0.6), 0.1, 64) == []


def test_aspect_builds_its_map_with_the_setparams_cell_size_and_decay():
    scan = {"angle_min": 0.0, "angle_step": math.pi / 2, "range_max": 5.0, "ranges": [1.0, 5.0], "seq": 1}
    obs, last = Ref(None), Ref(0)
    assert Aspect.aspReset(0.0, obs) == "fuse"  # before SetParams: 0.1 m cells
    Aspect.aspFuse(scan, 0.0, 0.0, last, obs)
    assert obs.value["resolution"] == 0.1 and grid.points(obs.value["cells"], 0.1, 64) == [(1.05, 0.05)]
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
