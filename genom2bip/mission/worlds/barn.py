"""The worlds of the BARN challenge (Perille et al. 2020; Daffan/the-barn-challenge) at true scale, and its rules.

A challenge world is a Gazebo world file (``jackal_helper/worlds/BARN/world_N.world``)
whose obstacles are unit cylinders of 0.075 m radius standing on a 0.15 m
grid; its ``path_files/path_N.npy`` holds the grid path the challenge takes
as the optimal one, and ``res/dwa_out.txt`` its DWA baseline's runs
(``world success collided timeout time ...``, ten runs of 50 worlds; its
report recomputes each run's metric from the time, as :func:`nav_metric` does).
The challenge's rules, from its ``run.py``: the Jackal starts at (-2.25, 3)
facing +y, the goal is 10 m ahead, a run succeeds when the robot comes within
1 m of the goal with no collision in 100 s, and the navigation metric is
``success * optimal_time / clip(time, 2 optimal_time, 8 optimal_time)`` with
``optimal_time`` the optimal path's length at 2 m/s.
"""
from __future__ import annotations

import copy
import math
import xml.etree.ElementTree as ET
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from genom2bip.mission.worlds.difficulty import Difficulty, measure

RADIUS = 0.075  # m: every cylinder of a BARN world
CELL = 2 * RADIUS  # m: the grid the cylinders stand on
START = (-2.25, 3.0, 1.57)  # x, y (m), theta (rad): the challenge's initial pose (run.py)
GOAL_AHEAD = (0.0, 10.0)  # m: the goal relative to the start
SUCCESS_RADIUS = 1.0  # m: within this of the goal, a run has succeeded
TIME_LIMIT = 100.0  # s
OPTIMAL_SPEED = 2.0  # m/s: the optimal time is the optimal path's length at this speed
FIELD_X = (-4.5, 0.0)  # m: the columns of cylinders (x of their edges)
GRID_HEIGHT = 15.0  # m: the grid on which the difficulty is measured, from y = 0, past the goal
WORLDS = "jackal_helper/worlds/BARN"
DWA_RUNS = "res/dwa_out.txt"


class BarnError(ValueError):
    """A challenge file that cannot be read; the message starts with ``file:line:column``."""


@dataclass
class DwaRuns:
    """The challenge's DWA baseline on one world: its runs' outcomes."""

    runs: int = 0
    succeeded: int = 0
    collided: int = 0
    outcomes: list[tuple[bool, float]] = field(default_factory=list)  # (succeeded, time in s) of each run

    @property
    def success(self) -> float:
        return self.succeeded / self.runs if self.runs else float("nan")

    def metric(self, optimal_time: float) -> float:
        """The mean of the runs' navigation metrics, as the challenge's report_test.py computes them."""
        values = [nav_metric(ok, time, optimal_time) for ok, time in self.outcomes]
        return sum(values) / len(values) if values else float("nan")


@dataclass
class BarnWorld:
    """One challenge world: its cylinders' centres, the start and goal, the optimal path and its difficulty."""

    index: int
    cylinders: list[tuple[float, float]]
    path: list[tuple[float, float]]  # the challenge's optimal path, start and goal included (m, Gazebo frame)
    start: tuple[float, float, float] = START
    goal: tuple[float, float] = (START[0] + GOAL_AHEAD[0], START[1] + GOAL_AHEAD[1])
    difficulty: Difficulty | None = None
    dwa: DwaRuns | None = None

    @property
    def name(self) -> str:
        return f"barn_{self.index:03d}"

    @property
    def length(self) -> float:
        return sum(math.dist(a, b) for a, b in zip(self.path, self.path[1:]))

    @property
    def optimal_time(self) -> float:
        return self.length / OPTIMAL_SPEED


def nav_metric(success: bool, time: float, optimal_time: float) -> float:
    """The challenge's navigation metric of one run (run.py)."""
    return float(success) * optimal_time / min(max(time, 2 * optimal_time), 8 * optimal_time)


def _where(path: Path, line: int = 1, column: int = 1) -> str:
    return f"{path}:{line}:{column}"


def cylinders(path: Path) -> list[tuple[float, float]]:
    """The centres of the cylinders of a BARN Gazebo world file (their state's pose, else the model's)."""
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        line, column = e.position
        reason = str(e).split(":")[0]
        raise BarnError(f"{_where(path, line, column + 1)}: not a Gazebo world file: {reason}") from None
    except OSError as e:
        raise BarnError(f"{_where(path)}: cannot read: {e.strerror}") from None
    world = root.find("world")
    if world is None:
        raise BarnError(f"{_where(path)}: expected a <world> element in <{root.tag}>")
    state = world.find("state")
    posed = {m.get("name"): m.findtext("pose") for m in state.findall("model")} if state is not None else {}
    out = []
    for model in world.findall("model"):
        radius = model.findtext("link/collision/geometry/cylinder/radius")
        if radius is None:
            continue  # the ground plane
        if abs(float(radius) - RADIUS) > 1e-6:
            raise BarnError(f"{_where(path)}: model {model.get('name')!r} is a cylinder of radius {radius}, "
                            f"expected {RADIUS} as in every BARN world")
        pose = posed.get(model.get("name")) or model.findtext("pose")
        values = (pose or "").split()
        if len(values) < 2:
            raise BarnError(f"{_where(path)}: model {model.get('name')!r} has no pose (expected 'x y z r p y')")
        out.append((float(values[0]), float(values[1])))
    if not out:
        raise BarnError(f"{_where(path)}: no cylinder in this world (expected the BARN unit cylinders)")
    return out


def grid_to_gazebo(col: float, row: float) -> tuple[float, float]:
    """A point of a challenge path file in the Gazebo frame (run.py's ``path_coord_to_gazebo_coord``)."""
    return (col * CELL - RADIUS - 30 * CELL, row * CELL + RADIUS + 5)


def optimal_path(path: Path) -> list[tuple[float, float]]:
    """The challenge's optimal path of a world: its start, the path file's points, its goal."""
    points = np.load(path)
    goal = (START[0] + GOAL_AHEAD[0], START[1] + GOAL_AHEAD[1])
    return [START[:2], *(grid_to_gazebo(float(c), float(r)) for c, r in points), goal]


def dwa_runs(path: Path) -> dict[int, DwaRuns]:
    """The DWA baseline's runs by world, from the challenge's ``res/dwa_out.txt``."""
    out: dict[int, DwaRuns] = defaultdict(DwaRuns)
    for number, line in enumerate(path.read_text().splitlines(), 1):
        if not line.strip():
            continue
        fields = line.split()
        try:
            index, ok, collided = int(fields[0]), bool(int(fields[1])), bool(int(fields[2]))
            time = float(fields[4])
        except (IndexError, ValueError):
            raise BarnError(f"{_where(path, number)}: expected 'world success collided timeout time ...', "
                            f"got {line.strip()!r}") from None
        runs = out[index]
        runs.runs += 1
        runs.succeeded += ok
        runs.collided += collided
        runs.outcomes.append((ok, time))
    return dict(out)


def occupancy(world: BarnWorld) -> tuple[np.ndarray, float]:
    """The cylinders as a grid of ``CELL`` m from (FIELD_X[0], 0) up to GRID_HEIGHT: (occupied, x shift)."""
    cols = round((FIELD_X[1] - FIELD_X[0]) / CELL)
    rows = round(GRID_HEIGHT / CELL)
    grid = np.zeros((rows, cols), dtype=bool)
    for x, y in world.cylinders:
        i, j = math.floor((x - FIELD_X[0]) / CELL), math.floor(y / CELL)
        if 0 <= i < cols and 0 <= j < rows:
            grid[j, i] = True
    return grid, -FIELD_X[0]


def load(root: Path, index: int, dwa: dict[int, DwaRuns] | None = None) -> BarnWorld:
    """World ``index`` of the challenge repository at ``root``, its difficulty measured along the optimal path."""
    folder = Path(root) / WORLDS
    world = BarnWorld(index, cylinders(folder / f"world_{index}.world"),
                      optimal_path(folder / "path_files" / f"path_{index}.npy"))
    grid, shift = occupancy(world)
    world.difficulty = measure(grid, CELL, [(x + shift, y) for x, y in world.path])
    world.dwa = (dwa or {}).get(index)
    return world


def available(root: Path) -> list[int]:
    """The indices of the world files under the challenge repository ``root``, in order."""
    folder = Path(root) / WORLDS
    if not folder.is_dir():
        raise BarnError(f"{root}: expected the challenge repository (no {WORLDS}/ in it)")
    return sorted(int(p.stem.split("_")[1]) for p in folder.glob("world_*.world") if p.stem.split("_")[1].isdigit())


def world_text(world: BarnWorld, robot: dict[str, Any]) -> str:
    """The ir-sim YAML of ``world``: every cylinder a circle of 0.075 m, ``robot`` (an ir-sim entry) at the start."""
    robot = copy.deepcopy(robot)
    robot["state"] = [round(v, 3) for v in world.start]
    obstacles = [{"name": f"cylinder_{k}", "shape": {"name": "circle", "radius": RADIUS},
                  "state": [round(x, 4), round(y, 4), 0]} for k, (x, y) in enumerate(world.cylinders)]
    data = {"world": {"width": 10.0, "height": 17.0, "step_time": 0.025, "sample_time": 0.1, "offset": [-7.0, -1.5],
                      "collision_mode": "stop"},
            "robot": [robot], "obstacle": obstacles}
    d = world.difficulty.as_dict() if world.difficulty else {}
    head = (f"# BARN world {world.index} at true scale: {len(world.cylinders)} cylinders of {RADIUS} m, from "
            f"({world.start[0]:g}, {world.start[1]:g}) to ({world.goal[0]:g}, {world.goal[1]:g}); optimal path "
            f"{world.length:.2f} m.\n# difficulty: " + ", ".join(f"{k} {v:g}" for k, v in d.items()) + "\n")
    return head + yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=120)
