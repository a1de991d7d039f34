"""Generated worlds (genom2bip/mission/worlds): seeded, feasible with the clearance, measured, written for ir-sim."""
from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
import yaml

from genom2bip.mission.spec import read_mission
from genom2bip.mission.world import check_world
from genom2bip.mission.worlds import FAMILIES, generate, mission_file, world_file
from genom2bip.mission.worlds.clearance import distances, shortest_path
from genom2bip.mission.worlds.difficulty import measure
from genom2bip.mission.worlds.families import CELL, CLEARANCE, MIX, family_of
from tests.runkit import ROOT

ROBOT = yaml.safe_load((ROOT / "descriptions/dala/worlds/doorway.yaml").read_text())["robot"][0]


def test_a_seed_gives_the_same_world_every_time_and_seeds_differ():
    a, b, c = generate(7), generate(7), generate(11)
    assert a.family == family_of(7) and np.array_equal(a.occupied, b.occupied)
    assert (a.start, a.goal, a.path) == (b.start, b.goal, b.path)
    assert c.family == family_of(11) and not (c.family == a.family and np.array_equal(a.occupied, c.occupied))
    assert [family_of(s) for s in range(len(MIX))] == list(MIX)


@pytest.mark.parametrize("family", FAMILIES)
def test_every_world_kept_has_a_path_with_the_robot_s_clearance(family):
    for seed in range(3):
        w = generate(seed, family)
        assert w.family == family and w.path[0] == w.start[:2] and w.path[-1] == w.goal
        # measured exactly, on the obstacles' squares and the outer walls: the grid's clearance within a fine cell
        rows, cols = w.occupied.nonzero()
        obstacles = shapely.union_all([shapely.box(c * CELL, r * CELL, (c + 1) * CELL, (r + 1) * CELL)
                                       for r, c in zip(rows, cols)] + [shapely.box(0, 0, w.width, w.height).exterior])
        way = shapely.LineString(w.path)
        assert obstacles.distance(way) >= CLEARANCE - distances(w.occupied, w.cell)[1], (family, seed)
        assert w.length >= math.dist(w.start[:2], w.goal) - 1e-9
        assert 0 < w.difficulty.narrowest <= w.difficulty.closest


def test_a_u_trap_stands_between_the_start_and_the_goal():
    w = generate(0, "u_trap")
    straight = [(w.start[0] + (w.goal[0] - w.start[0]) * t, w.start[1] + (w.goal[1] - w.start[1]) * t)
                for t in np.linspace(0, 1, 400)]
    assert any(w.occupied[int(y / CELL), int(x / CELL)] for x, y in straight)  # the straight way is shut
    assert w.difficulty.tortuosity > 1.05  # the way round is a detour


def test_a_grid_without_a_way_has_no_path_and_a_seed_without_one_is_refused():
    grid = np.zeros((40, 80), dtype=bool)
    grid[:, 40] = True  # a wall across the whole field
    assert shortest_path(grid, CELL, (1.0, 3.0), (11.0, 3.0), CLEARANCE) is None
    assert shortest_path(grid, CELL, (6.0, 3.0), (11.0, 3.0), CLEARANCE) is None  # the start inside the wall
    with pytest.raises(ValueError, match=r"cellular seed 3: no draw in \d+ has a path with 3 m of clearance"):
        generate(3, "cellular", clearance=3.0)
    with pytest.raises(ValueError, match="unknown world family 'maze' \\(families: cellular, doorway"):
        generate(0, "maze")


def test_the_metrics_of_a_straight_corridor_are_its_geometry():
    grid = np.ones((40, 80), dtype=bool)  # 12 m x 6 m, all full but a corridor 1.5 m wide along y = 3
    grid[15:25, :] = False
    path = [(2.0, 3.0), (10.0, 3.0)]  # 2 m from the grid's ends, beyond what dispersion looks at
    d = measure(grid, CELL, path)
    assert d.closest == pytest.approx(0.75, abs=0.03) and d.narrowest == pytest.approx(0.75, abs=0.03)
    assert d.dimension == pytest.approx(1.5, abs=0.06)  # the narrowest axis: across the corridor
    assert d.dispersion == pytest.approx(4.0)  # the walls on each side, the corridor's two ends open
    assert d.tortuosity == pytest.approx(1.0)
    assert 0.75 < d.visibility < 6.0


def test_the_world_file_holds_the_obstacles_and_the_robot_at_its_start(tmp_path):
    w = generate(2, "doorway")
    data = yaml.safe_load(world_file.text(w, ROBOT))
    assert data["robot"][0]["state"] == pytest.approx(list(w.start), abs=1e-3)
    assert data["robot"][0]["sensors"] == ROBOT["sensors"]
    assert data["world"]["width"] == pytest.approx(w.width) and data["world"]["height"] == pytest.approx(w.height)
    blocks = [shapely.Polygon(o["shape"]["vertices"]) for o in data["obstacle"][1:]]
    assert all(b.is_valid for b in blocks)
    assert sum(b.area for b in blocks) == pytest.approx(w.occupied.sum() * CELL * CELL)  # every cell, no hole
    rows, cols = w.occupied.nonzero()
    covered = shapely.union_all(blocks)
    assert all(covered.contains(shapely.Point((c + 0.5) * CELL, (r + 0.5) * CELL)) for r, c in zip(rows, cols))


def test_the_world_file_loads_in_the_simulator(tmp_path):
    from runtime.controller.codels import load_codels

    w = generate(1, "cellular")
    path = tmp_path / "w.yaml"
    path.write_text(world_file.text(w, ROBOT))
    check_world(path)  # what `genom2bip mission` checks before the controller starts
    codels = load_codels(str(ROOT / "descriptions/dala/codels"), ["RFLEX"])
    sim = codels.modules["RFLEX"].world.load(path)
    assert sim.pose() == pytest.approx({"x": w.start[0], "y": w.start[1], "theta": w.start[2]}, abs=1e-3)
    assert len(sim.obstacles()) == len(world_file.polygons(w)) + 1  # the blocks and the walls round them
    assert sim.bounds() == pytest.approx((0.0, 0.0, w.width, w.height))


def test_the_mission_of_a_world_is_the_template_s_bring_up_and_one_goto(tmp_path):
    """The generated mission keeps the template's bring-up, anchors POM at the start and sends one GoTo to the goal."""
    w = generate(4, "corridor")
    template = ROOT / "descriptions/dala/missions/doorway.yaml"
    path = tmp_path / "m.yaml"
    path.write_text(mission_file.text(w, tmp_path / "w.yaml", template, timeout=321.0))
    mission = read_mission(path)
    assert mission.name == w.name and mission.world == (tmp_path / "w.yaml").resolve()
    sends = [s.target for s in mission.steps]
    expected = [s["send"] for s in yaml.safe_load(template.read_text())["steps"]]
    assert sends == expected  # the template's steps, its one GoTo last
    pom = mission.steps[sends.index("POM.Run")]
    assert pom.inputs["origin"] == pytest.approx({"x": w.start[0], "y": w.start[1], "theta": 0.0}, abs=1e-3)
    goto = mission.steps[-1]
    assert goto.inputs["goal"]["x"] == pytest.approx(w.goal[0], abs=1e-3) and goto.timeout == 321.0
    assert goto.expect == {"status": "ok"}


def test_a_template_without_pom_run_before_its_goto_is_refused(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("steps:\n  - send: NDD.GoTo\n    with: {goal: {x: 1, y: 1, theta: 0}}\n"
                   "  - send: POM.Run\n")
    with pytest.raises(ValueError, match="bad.yaml: no POM.Run before a first NDD.GoTo"):
        mission_file.text(generate(0), tmp_path / "w.yaml", bad, timeout=60)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.yaml"]  # nothing written
