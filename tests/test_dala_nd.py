"""The nearness diagram (descriptions/dala/codels/nd.py) situation by situation, on laser-like point sets.

Each case places walls round the robot (at the origin, facing +x), sweeps them with a
lidar like DALA's (181 beams over the 180 degrees ahead, 6 m), and checks the situation
ND finds and the direction it chooses.
"""
from __future__ import annotations

import importlib
import math

import pytest

from runtime.controller.codels import load_codels
from tests.runkit import ROOT

_codels = load_codels(str(ROOT / "descriptions" / "dala" / "codels"), ["NDD"])
nd = importlib.import_module(f"{_codels.modules['NDD'].__package__}.nd")

P = nd.Params(radius=0.35, security=0.3, dmax=3.2, vmax=0.5, wmax=1.0)
SECTOR = 2 * math.pi / P.sectors


def laser(walls, beams=181, fov=math.pi, reach=6.0):
    """The points where each beam of a sweep meets the nearest wall (segments ((x0, y0), (x1, y1)))."""
    points = []
    for k in range(beams):
        a = -fov / 2 + k * fov / (beams - 1)
        dx, dy = math.cos(a), math.sin(a)
        best = reach
        for (x0, y0), (x1, y1) in walls:
            ex, ey = x1 - x0, y1 - y0
            den = dx * ey - dy * ex
            if abs(den) < 1e-12:
                continue
            t = (x0 * ey - y0 * ex) / den  # along the beam
            u = (x0 * dy - y0 * dx) / den  # along the wall
            if 0 < t < best and 0 <= u <= 1:
                best = t
        if best < reach:
            points.append((best * dx, best * dy))
    return points


def box(x0, y0, x1, y1):
    return [((x0, y0), (x1, y0)), ((x1, y0), (x1, y1)), ((x1, y1), (x0, y1)), ((x0, y1), (x0, y0))]


def cells(points, size=0.1):
    """The points as Aspect's map gives them: the centre of the cell each falls in."""
    return sorted({((math.floor(x / size) + 0.5) * size, (math.floor(y / size) + 0.5) * size) for x, y in points})


# -- high safety ------------------------------------------------------------------------------------------------


def test_hsgr_in_free_space_heads_for_the_goal():
    got = nd.decide(laser(box(-1, -5, 8, 5)), (3.0, 1.0), P)  # the room's walls are beyond dmax
    assert got.situation == "HSGR" and got.area.goal_region
    assert got.direction == pytest.approx(math.atan2(1, 3))
    assert got.v > 0


def test_hsgr_a_goal_before_a_wall_is_in_the_free_walking_area():
    got = nd.decide(laser([((2.5, -3), (2.5, 3))]), (1.5, 0.2), P)
    assert got.situation == "HSGR" and got.direction == pytest.approx(math.atan2(0.2, 1.5))


def test_hswr_passes_the_end_of_a_wall_with_the_security_distance_to_spare():
    # a wall 2 m ahead from far on the right up to y = 0.5; the goal behind it, on the right
    got = nd.decide(laser([((2, -4), (2, 0.5))]), (5.0, -1.0), P)
    assert got.situation == "HSWR"
    edge = math.atan2(0.5, 2.0)
    expected = edge + math.atan2(P.radius + P.security, math.hypot(2.0, 0.5))
    assert got.direction == pytest.approx(expected, abs=SECTOR)  # past the wall's end, on its free side
    assert got.v > 0


def test_hsnr_goes_through_the_middle_of_a_doorway():
    # a wall 2 m ahead with a door from y = 0.2 to y = 1.4; the goal behind the wall, on the right
    wall = [((2, -4), (2, 0.2)), ((2, 1.4), (2, 4))]
    got = nd.decide(laser(wall), (5.0, -1.0), P)
    assert got.situation == "HSNR"
    assert got.direction == pytest.approx(math.atan2(0.8, 2.0), abs=1.5 * SECTOR)  # the door's middle
    assert not got.area.goal_region


def test_a_wall_reaching_the_map_disc_s_edge_ends_in_gaps_and_the_robot_goes_round_it():
    """A doorway as Aspect's map shows it: ND heads past the end of what it sees of the wall, then through the door."""
    # The robot 3.14 m before a wall whose door starts 1.35 m to its left; the goal 8 m straight on.
    # As Aspect's map gives it: cells of 0.1 m within a 6.4 m square.  The wall's far parts lie past
    # dmax (3.2 m): they are not counted, so the wall's visible part ends in gaps, and ND heads past
    # one of its ends rather than giving up in front of it.
    wall = [((3.14, -5), (3.14, 1.35)), ((3.14, 3.25), (3.14, 5)), ((-1, -3.0), (4, -3.0))]
    points = [p for p in cells(laser(wall)) if abs(p[0]) < 3.2 and abs(p[1]) < 3.2]
    setting = nd.Params(radius=0.35, security=0.3, dmax=3.2, cell=0.1)
    got = nd.decide(points, (8.14, 0.0), setting)
    assert got is not None and got.situation in ("HSWR", "HSNR")
    visible_end = math.asin(math.sqrt(3.2 ** 2 - 3.14 ** 2) / 3.2)
    assert abs(got.direction) > visible_end  # past an end of what is seen of the wall
    # closer, the door's edge is inside the disc: the way is through the door, on the left
    closer = [(x - 1.24, y) for x, y in laser([((1.9, -5), (1.9, 1.35)), ((1.9, 3.25), (1.9, 5))])]
    got = nd.decide([p for p in cells(closer) if abs(p[0]) < 3.2 and abs(p[1]) < 3.2], (6.9, 0.0), setting)
    assert got.direction > math.atan2(1.35, 1.9)


def test_an_obstacle_beyond_dmax_is_not_counted_and_one_within_it_always_makes_a_gap():
    far = nd.sectorise([(3.3, 0.0)], P.sectors, dmax=3.2)
    assert far.d == [math.inf] * P.sectors and nd.gaps(far.d, P) == []
    near = nd.sectorise([(3.1, 0.0)], P.sectors, dmax=3.2)
    k = nd.sector_of(0.0, P.sectors)
    assert sorted(nd.gaps(near.d, P)) == [k - 1, k]  # free on both sides of an obstacle near dmax: two gaps
    assert near.points[k] == (3.1, 0.0)


# -- low safety -------------------------------------------------------------------------------------------------


def test_ls1_an_obstacle_on_one_side_turns_the_robot_away_from_it():
    got = nd.decide(laser([((-1, -0.55), (4, -0.55))]), (3.0, 0.0), P)  # a wall 0.55 m on the right
    assert got.situation == "LS1"
    assert 0 < got.direction < math.pi / 2  # away from it, to the left, and still forward
    assert 0 < got.v < P.vmax


def test_ls2_obstacles_on_both_sides_keep_the_robot_in_the_middle():
    corridor = [((-1, 0.55), (5, 0.55)), ((-1, -0.62), (5, -0.62))]  # the left wall the nearer
    got = nd.decide(laser(corridor), (4.0, 0.0), P)
    assert got.situation == "LS2"
    assert -math.radians(30) < got.direction < 0  # towards the farther wall, along the corridor
    assert got.v > 0


def test_ls2_centred_between_equal_walls_goes_straight_on():
    corridor = [((-1, 0.6), (5, 0.6)), ((-1, -0.6), (5, -0.6))]
    got = nd.decide(laser(corridor), (4.0, 0.0), P)
    assert got.situation == "LS2" and got.direction == pytest.approx(0.0, abs=SECTOR)


# -- no way, speeds, keeping the way ----------------------------------------------------------------------------


def test_an_enclosed_robot_has_no_free_walking_area():
    ring = [(1.0 * math.cos(a / 100 * 2 * math.pi), 1.0 * math.sin(a / 100 * 2 * math.pi)) for a in range(100)]
    assert nd.decide(ring, (3.0, 0.0), P) is None


def test_a_passage_narrower_than_the_robot_is_not_navigable():
    wall = [((2, -4), (2, -0.3)), ((2, 0.3), (2, 4))]  # a slot 0.6 m wide ahead, the goal beyond it
    got = nd.decide(laser(wall), (5.0, 0.0), P)
    assert got is None or abs(got.direction) > math.radians(45)  # not through the slot


def test_an_obstacle_touching_the_robot_ahead_stops_it_and_it_turns_in_place():
    got = nd.decide([(0.34, 0.0), (0.34, 0.05), (0.34, -0.05)], (3.0, 0.3), P)
    assert got is not None and got.v == 0.0 and got.w != 0.0


def test_near_the_goal_the_arc_driven_ends_at_the_goal():
    got = nd.decide([], (0.2, 0.2), P)  # 45 degrees off, 0.28 m away
    assert got.situation == "HSGR"
    radius = got.v / abs(got.w)
    assert radius <= math.hypot(0.2, 0.2) / (2 * math.sin(math.pi / 4)) + 1e-9


def test_the_valley_the_robot_headed_for_is_kept_while_it_still_leads_there():
    # two doors 0.9 m wide, 23 degrees either side of the goal behind the wall
    wall = [((2, -4), (2, -1.3)), ((2, -0.4), (2, 0.4)), ((2, 1.3), (2, 4))]
    free = nd.decide(laser(wall), (6.0, 0.0), P)
    assert abs(free.direction) < math.radians(40)  # through one of the doors
    other = (2.0, 0.85) if free.area.target[1] < 0 else (2.0, -0.85)  # the other door
    kept = nd.decide(laser(wall), (6.0, 0.0), P, keep=other)
    assert math.copysign(1, kept.area.target[1]) == math.copysign(1, other[1])
    assert math.copysign(1, free.area.target[1]) != math.copysign(1, other[1])


def test_a_goal_in_sight_whose_way_brushes_a_box_is_reached_round_the_box_with_room():
    # the corridor's first leg: the goal 6 m ahead, 0.4 m to the left; a box's corner 0.2 m from the way
    got = nd.decide(laser(box(3.1, -2.0, 3.9, 0.0)), (6.0, 0.4), P)
    assert not got.area.goal_region
    corner = math.atan2(0.0, 3.1)
    assert got.direction >= corner + math.atan2(P.radius + P.security, 3.1) - SECTOR  # past it with R + Ds
    # in a closed room whose wall the way brushes, the goal itself is the way
    room = [((-1, -0.45), (2.5, -0.45)), ((2.5, -0.45), (2.5, 2)), ((2.5, 2), (-1, 2))]
    assert nd.decide(laser(room), (2.0, 0.0), P).area.goal_region
