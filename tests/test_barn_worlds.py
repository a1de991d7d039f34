"""The BARN challenge's worlds converted at true scale (genom2bip/mission/worlds/barn.py), on a world of our own."""
from __future__ import annotations

import importlib
import math
import shutil
import sys

import numpy as np
import pytest
import yaml

from genom2bip.mission.world import check_world
from genom2bip.mission.worlds import barn
from runtime.controller.codels import load_codels
from tests.runkit import ROOT

sys.path.insert(0, str(ROOT / "bench"))
import navigation_bench  # noqa: E402

FIXTURE = ROOT / "tests/fixtures/barn/world_3.world"
ROBOT = yaml.safe_load((ROOT / "descriptions/dala/worlds/doorway.yaml").read_text())["robot"][0]


@pytest.fixture
def challenge(tmp_path):
    """A copy of the challenge repository's shape: one world, its path file and DWA's runs."""
    worlds = tmp_path / barn.WORLDS
    (worlds / "path_files").mkdir(parents=True)
    shutil.copy(FIXTURE, worlds / "world_3.world")
    np.save(worlds / "path_files" / "path_3.npy", np.array([[15, 0], [15, 10], [16, 20], [15, 29]]))
    (tmp_path / "res").mkdir()
    (tmp_path / barn.DWA_RUNS).write_text("3 1 0 0 20.0000 1.0\n3 0 1 0 12.5000 1.0\n3 1 0 0 40.0000 1.0\n"
                                          "7 1 0 0 30.0000 1.0\n")
    return tmp_path


def test_the_cylinders_are_read_where_the_world_s_state_leaves_them():
    assert barn.cylinders(FIXTURE) == [(-2.475, 6.075), (-2.025, 6.075), (-1.275, 7.125)]


def test_a_world_loads_with_the_challenge_s_start_goal_path_and_dwa_runs(challenge):
    runs = barn.dwa_runs(challenge / barn.DWA_RUNS)
    assert sorted(runs) == [3, 7] and runs[3].runs == 3 and runs[3].succeeded == 2 and runs[3].collided == 1
    world = barn.load(challenge, 3, runs)
    assert world.start == (-2.25, 3.0, 1.57) and world.goal == (-2.25, 13.0)
    # run.py's conversion of the path file's (column, row) points, between the start and the goal
    assert world.path[0] == (-2.25, 3.0) and world.path[-1] == (-2.25, 13.0)
    assert world.path[1] == pytest.approx((15 * 0.15 - 0.075 - 4.5, 0.075 + 5))
    assert world.length == pytest.approx(sum(math.dist(a, b) for a, b in zip(world.path, world.path[1:])))
    assert world.optimal_time == pytest.approx(world.length / 2)
    assert world.difficulty is not None and world.difficulty.tortuosity > 1
    assert barn.available(challenge) == [3] and world.name == "barn_003"


def test_the_navigation_metric_is_the_challenge_s():
    assert barn.nav_metric(False, 10.0, 5.0) == 0
    assert barn.nav_metric(True, 5.0, 5.0) == pytest.approx(0.5)  # faster than twice the optimal time: clipped
    assert barn.nav_metric(True, 20.0, 5.0) == pytest.approx(0.25)
    assert barn.nav_metric(True, 99.0, 5.0) == pytest.approx(5 / 40)  # slower than 8 times: clipped
    runs = barn.DwaRuns(runs=2, succeeded=1, outcomes=[(True, 20.0), (False, 30.0)])
    assert runs.success == 0.5 and runs.metric(5.0) == pytest.approx(0.125)


def test_the_world_file_keeps_every_cylinder_as_a_circle_and_passes_the_world_check(challenge, tmp_path):
    world = barn.load(challenge, 3)
    path = tmp_path / "barn_003.yaml"
    path.write_text(barn.world_text(world, ROBOT))
    data = yaml.safe_load(path.read_text())
    circles = [o for o in data["obstacle"] if o["shape"]["name"] == "circle"]
    assert [tuple(o["state"][:2]) for o in circles] == world.cylinders
    assert {o["shape"]["radius"] for o in circles} == {0.075} and len(data["obstacle"]) == 3
    assert data["robot"][0]["state"] == [-2.25, 3.0, 1.57]
    lo_x, lo_y = data["world"]["offset"]
    assert lo_x < -4.5 and lo_x + data["world"]["width"] > 0 and lo_y < 3 and lo_y + data["world"]["height"] > 13
    check_world(path)  # ir-sim's reader and ours accept it


def test_a_file_that_is_not_xml_is_named_with_its_line_and_column(tmp_path):
    bad = tmp_path / "world_1.world"
    bad.write_text("<sdf version='1.6'>\n  <world name='default'>\n    <model name='a'\n</sdf>\n")
    with pytest.raises(barn.BarnError, match=r"world_1\.world:4:\d+: not a Gazebo world file"):
        barn.cylinders(bad)


def test_a_cylinder_of_another_radius_and_a_world_without_one_are_refused(tmp_path):
    other = tmp_path / "world_2.world"
    other.write_text(FIXTURE.read_text().replace("0.075000", "0.2", 1))
    with pytest.raises(barn.BarnError, match=r"world_2\.world:1:1: model 'unit_cylinder_0' is a cylinder of radius "
                                             r"0\.2, expected 0\.075"):
        barn.cylinders(other)
    empty = tmp_path / "world_4.world"
    empty.write_text("<sdf version='1.6'><world name='default'></world></sdf>")
    with pytest.raises(barn.BarnError, match=r"world_4\.world:1:1: no cylinder in this world"):
        barn.cylinders(empty)


def test_a_bad_line_of_dwa_s_runs_is_named_and_a_folder_without_worlds_refused(challenge, tmp_path):
    (challenge / barn.DWA_RUNS).write_text("3 1 0 0 20.0 1.0\n3 yes 0 0 20.0 1.0\n")
    with pytest.raises(barn.BarnError, match=r"dwa_out\.txt:2:1: expected 'world success collided timeout time"):
        barn.dwa_runs(challenge / barn.DWA_RUNS)
    with pytest.raises(barn.BarnError, match=r"expected the challenge repository \(no jackal_helper/worlds/BARN/"):
        barn.available(tmp_path / "elsewhere")


def test_the_barn_robot_s_ndd_stops_short_of_a_cylinder_its_body_would_touch():
    # ND's "how far straight on" counts a disc of R less half a cell (its points are cell centres): R must be the
    # robot's radius plus half a cell, or a return 0.2 m aside of a 0.215 m robot's way does not stop it.
    ndd = load_codels(str(ROOT / "descriptions/dala/codels"), ["NDD"]).modules["NDD"]
    nd = importlib.import_module(f"{ndd.__package__}.nd")
    params = navigation_bench.BARN_NDD["params"]
    robot = navigation_bench.BARN_ROBOT_RADIUS
    setting = nd.Params(radius=params["robot_radius"], security=params["security_distance"], dmax=3.2,
                        cell=navigation_bench.MAP_CELL)
    for aside in (0.0, 0.1, robot - 0.015, -(robot - 0.015)):
        sectors = nd.sectorise([(1.0, aside)], setting.sectors, setting.cell, setting.dmax)
        touch = 1.0 - math.sqrt(robot ** 2 - aside ** 2)
        assert nd.ahead(sectors, setting) == pytest.approx(touch, abs=1e-9)
    clear_of_it = nd.sectorise([(1.0, robot + 0.01)], setting.sectors, setting.cell, setting.dmax)
    assert nd.ahead(clear_of_it, setting) == math.inf
