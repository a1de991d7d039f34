"""The Planner's codels on small grids (planning.py, Planner.py) and NDD's request for a way round."""
from __future__ import annotations

import importlib
import math

import pytest

from runtime.controller.codels import load_codels
from runtime.genom import Ref, Throw
from tests.runkit import ROOT

_codels = load_codels(str(ROOT / "descriptions" / "dala" / "codels"), ["NDD", "Planner"])
planning = importlib.import_module(f"{_codels.modules['NDD'].__package__}.planning")
grid = importlib.import_module(f"{_codels.modules['NDD'].__package__}.grid")
NDD, Planner = _codels.modules["NDD"], _codels.modules["Planner"]
PARAMS = {"robot_radius": 0.35, "clearance": 0.6, "lookahead": 2.0}


def _u_trap(seen: planning.Seen) -> None:
    """A U open towards -x, its arms 3 m long from x = 4 to 7 at y = 3.5 and 6.5, its bottom at x = 7."""
    r = seen.resolution
    wall = [(4 + k * r, 3.5) for k in range(31)] + [(4 + k * r, 6.5) for k in range(31)]
    wall += [(7.0, 3.5 + k * r) for k in range(31)]
    seen.add(wall)


def _clearance(seen: planning.Seen, points) -> float:
    r = seen.resolution
    centres = [((i + 0.5) * r, (j + 0.5) * r) for i, j in seen.cells]
    return min(math.dist(p, c) for p in points for c in centres)


def _dense(points, step=0.05):
    out = []
    for a, b in zip(points, points[1:]):
        n = max(1, math.ceil(math.dist(a, b) / step))
        out += [(a[0] + (b[0] - a[0]) * k / n, a[1] + (b[1] - a[1]) * k / n) for k in range(n)]
    return out + [points[-1]]


def test_the_plan_goes_round_a_u_trap_keeping_the_robot_s_radius():
    seen = planning.Seen(0.1)
    _u_trap(seen)
    p = planning.plan(seen, (2.0, 5.0), (10.0, 5.0), 0.35, 0.6)
    assert p.points[0] == (2.0, 5.0) and p.points[-1] == (10.0, 5.0)
    assert p.length > 9.0  # round an arm: 1.5 m aside and back, 8 m straight
    assert not any(4.0 < x < 7.4 and 3.2 < y < 6.8 for x, y in _dense(p.points[1:]))  # never into the U
    assert _clearance(seen, _dense(p.points[1:-1])) >= 0.35 - 1e-9


def test_the_intermediate_goal_is_seen_straight_from_the_robot_within_the_lookahead():
    seen = planning.Seen(0.1)
    _u_trap(seen)
    p = planning.plan(seen, (2.0, 5.0), (10.0, 5.0), 0.35, 0.6)
    point, left = planning.target(p, (2.0, 5.0), 2.0)
    assert math.dist(point, (2.0, 5.0)) <= 2.0 + 1e-9 and planning.visible(p, (2.0, 5.0), point)
    assert left == pytest.approx(p.length, abs=0.15)
    # from inside the U, the way out leads back towards the mouth, away from the goal
    inside = planning.plan(seen, (6.0, 5.0), (10.0, 5.0), 0.35, 0.6)
    point, _ = planning.target(inside, (6.0, 5.0), 2.0)
    assert point[0] < 6.0 and planning.visible(inside, (6.0, 5.0), point)


def _cylinder_row(first_x: float, y: float, count: int) -> list[tuple[float, float]]:
    """Laser returns all round a row of BARN's cylinders (0.075 m, every 0.15 m): a wall with a thin tip."""
    return [(first_x + 0.15 * i + 0.075 * math.cos(a * math.pi / 12), y + 0.075 * math.sin(a * math.pi / 12))
            for i in range(count) for a in range(24)]


def _segment_distance(a, b, q) -> float:
    ab = (b[0] - a[0], b[1] - a[1])
    length = ab[0] ** 2 + ab[1] ** 2
    t = max(0.0, min(1.0, ((q[0] - a[0]) * ab[0] + (q[1] - a[1]) * ab[1]) / length)) if length else 0.0
    return math.dist(q, (a[0] + t * ab[0], a[1] + t * ab[1]))


def test_the_way_to_the_intermediate_goal_keeps_the_radius_from_the_returns_wherever_they_fell_in_their_cells():
    # A wall of cylinders whose tip the way to the goal rounds: the robot (0.215 m, the BARN runs') must not cut
    # the corner on its straight way to the intermediate goal.  A cell stands for a return anywhere in it, up to
    # half its diagonal (7 cm) from its centre: distances counted between centres let the robot graze the tip.
    returns = _cylinder_row(0.375, 2.0, 18)
    seen = planning.Seen(0.1)
    seen.add(returns)
    closest, tried = math.inf, 0
    for k in range(20):
        for m in range(10):
            here = (0.6 + 0.05 * m, 0.3 + 0.07 * k)
            p = planning.plan(seen, here, (here[0], 3.6), 0.215, 0.45)
            assert min(x for x, _ in p.points) < 0.375  # round the tip, not through the wall
            point, _ = planning.target(p, here, 2.0)
            closest = min(closest, *(_segment_distance(here, point, q) for q in returns))
            assert min(math.dist(q, h) for q in p.points[1:-1] for h in returns) >= 0.215
            tried += 1
    assert tried == 200 and 0.215 <= closest < 0.35  # near the tip, yet never nearer than the robot's radius


def test_a_stalled_way_costs_more_and_the_next_plan_takes_the_other_side():
    seen = planning.Seen(0.1)
    _u_trap(seen)
    first = planning.plan(seen, (2.0, 5.0), (10.0, 5.0), 0.35, 0.6)
    side = 1 if max(y for _, y in first.points) > 6.5 else -1
    avoid = planning.corridor(first, (4.0, 5.0 + side * 2.2), 0.5)
    second = planning.plan(seen, (2.0, 5.0), (10.0, 5.0), 0.35, 0.6, avoid, 4.0)
    assert (max(y for _, y in second.points) > 6.5) != (side == 1)


def test_no_path_is_an_exception_that_says_why():
    seen = planning.Seen(0.1)
    ring = [(5 + 1.5 * math.cos(a / 100 * 2 * math.pi), 5 + 1.5 * math.sin(a / 100 * 2 * math.pi)) for a in range(100)]
    seen.add(ring)
    with pytest.raises(planning.NoPath, match="no way with 0.35 m of clearance joins the robot to the goal"):
        planning.plan(seen, (1.0, 5.0), (5.0, 5.0), 0.35, 0.6)
    block = planning.Seen(0.1)
    block.add([(3 + i * 0.1, 3 + j * 0.1) for i in range(31) for j in range(31)])
    with pytest.raises(planning.NoPath, match="the goal lies within 0.35 m of obstacles, with no free cell within 1 m"):
        planning.plan(block, (1.0, 1.0), (4.5, 4.5), 0.35, 0.6)  # inside a 3 m block
    with pytest.raises(planning.NoPath, match="the robot stands within 0.35 m of obstacles"):
        planning.plan(block, (4.5, 4.5), (1.0, 1.0), 0.35, 0.6)
    # the codel: Plan's e_no_path, with where the robot stands and the reason
    Planner._clear()
    Planner._state["seen"] = seen
    pos = {"estimate": {"x": 1.0, "y": 5.0, "theta": 0.0}, "stamp": 1.0}
    with pytest.raises(Throw) as thrown:
        Planner.plnPlan({"x": 5.0, "y": 5.0, "theta": 0.0}, PARAMS, pos)
    assert thrown.value.name == "e_no_path" and thrown.value.detail["where"] == pos["estimate"]
    assert "no way with 0.35 m of clearance" in thrown.value.detail["reason"]
    assert Planner.plnPlan({"x": 0.0, "y": 1.0, "theta": 0.0}, PARAMS, pos) == "ether"
    with pytest.raises(Throw, match="e_no_path"):
        Planner.plnCheckGoal({"x": math.nan, "y": 1.0, "theta": 0.0})
    for bad in ({**PARAMS, "robot_radius": 0.0}, {**PARAMS, "clearance": 0.2}, {**PARAMS, "lookahead": -1}):
        with pytest.raises(Throw, match="e_bad_params"):
            Planner.plnCheckParams(bad)


def _obs(points, seq, stamp, side=64, r=0.1):
    cells = [0] * side * side
    for x, y in points:
        c = grid.cell_of(x, y, r, side)
        if c is not None:
            cells[c] = grid.OCCUPIED
    return {"resolution": r, "origin": {"x": 0, "y": 0, "theta": 0}, "cells": cells, "seq": seq, "stamp": stamp}


def test_run_publishes_the_way_for_nav_s_goal_and_answers_a_request_for_a_way_round():
    way, plans = Ref(None), Ref(0)
    assert Planner.plnReset(way) == "watch" and not way.value["valid"]
    pos = {"estimate": {"x": 2.0, "y": 5.0, "theta": 0.0}, "stamp": 1.0}
    nav = {"goal": {"x": 10.0, "y": 5.0, "theta": 0.0}, "active": False, "seq": 1, "stalls": 0}
    wall = [(2.0 + k * 0.1, 0.0) for k in range(-10, 11)]  # a wall 2 m ahead, across the robot's way
    obs = _obs([(2.0, y) for _, y in wall], 1, 1.0)
    assert Planner.plnWatch(PARAMS, plans, obs, pos, nav, way) == "pause::watch"
    assert not way.value["valid"] and plans.value == 0  # NDD drives nowhere: no plan
    nav["active"] = True
    Planner.plnWatch(PARAMS, plans, obs, pos, nav, way)
    w = way.value
    assert w["valid"] and w["seq"] == 1 and w["stalls"] == 0 and plans.value == 1 and w["plans"] == 1
    assert abs(w["target"]["y"] - 5.0) > 0.3  # past the wall's end, not straight at it
    assert w["remaining"] > 8.0
    Planner.plnWatch(PARAMS, plans, obs, pos, nav, way)
    assert plans.value == 1  # nothing new: the same plan
    nav["stalls"] = 1
    Planner.plnWatch(PARAMS, plans, obs, pos, nav, way)
    assert plans.value == 2 and way.value["stalls"] == 1 and Planner._state["avoid"]
    nav["active"] = False
    Planner.plnWatch(PARAMS, plans, obs, pos, nav, way)
    assert not way.value["valid"] and not way.value["blocked"]
    assert Planner.plnStop(way) == "ether" and not way.value["valid"]


def test_ndd_asks_the_planner_for_a_way_round_a_bounded_number_of_times():
    nav = Ref({"goal": {"x": 1.0, "y": 0.0, "theta": 0.0}, "active": True, "seq": 4, "stalls": 0})
    progress = {"best": 1.0, "since": 0.0, "no_way_since": None, "situation": None, "remaining": 3.0}
    for k in range(NDD.ASKS):
        assert NDD.ask_for_way_round(progress, nav, 30.0 + k)
        assert nav.value["stalls"] == k + 1 and progress["since"] == 30.0 + k and progress["best"] == math.inf
    assert not NDD.ask_for_way_round(progress, nav, 99.0) and nav.value["stalls"] == NDD.ASKS
    way = {"valid": True, "blocked": False, "target": {"x": 0.5, "y": 0.0, "theta": 0.0}, "remaining": 1.0,
           "seq": 4, "stalls": NDD.ASKS, "plans": 3, "reason": ""}
    assert NDD.planned(way, nav.value) is way
    assert NDD.planned({**way, "seq": 3}, nav.value) is None  # an answer to an older GoTo
    assert NDD.planned({**way, "stalls": 1}, nav.value) is None  # to an older request
    assert NDD.planned({**way, "valid": False}, nav.value) is None and NDD.planned(None, nav.value) is None
