"""The families of generated worlds, drawn on an occupancy grid from a seed; a world is kept only when it is feasible.

Every family draws its obstacles on a grid of ``CELL`` (0.15 m, the width of
BARN's cylinders) inside a walled rectangle, with a start on the left facing
+x and a goal on the right:

* ``cellular``: random fill smoothed by a cellular automaton (a cell fills when
  five or more of its eight neighbours are full, empties when one or none is),
  in the middle of the field, as BARN draws its obstacle fields;
* ``doorway``: two rooms split by a wall with one door, a pillar often behind it,
  a few boxes in each room;
* ``corridor``: a corridor with a bend, boxes standing out from its walls;
* ``u_trap``: a U open towards the robot between it and the goal; the way round
  it exists, but a reactive method that enters it is in a local minimum.

A draw is kept only when a path with the robot's clearance joins the start to
the goal (clearance.py); otherwise the same seed draws again, so a seed always
gives the same world.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from genom2bip.mission.worlds.clearance import shortest_path
from genom2bip.mission.worlds.difficulty import Difficulty, measure

CELL = 0.15  # m: one cell of the obstacle grid
CLEARANCE = 0.45  # m: NDD's robot_radius in the shipped missions (0.35) and a cell of Aspect's map (0.1)
ATTEMPTS = 60  # draws of one seed before it is declared infeasible
FAMILIES = ("cellular", "doorway", "corridor", "u_trap")
MIX = ("cellular", "doorway", "cellular", "corridor")  # the benchmark's families, seed by seed


@dataclass
class GridWorld:
    """One generated world: its grid, start, goal, the shortest path with the clearance, and its difficulty."""

    family: str
    seed: int
    occupied: np.ndarray  # bool (rows, cols); row j covers y in [j, j + 1) * cell, column i x likewise
    cell: float
    start: tuple[float, float, float]  # x, y (m), theta (rad)
    goal: tuple[float, float]
    clearance: float
    path: list[tuple[float, float]] = field(default_factory=list)
    length: float = 0.0  # m, the path's
    difficulty: Difficulty | None = None

    @property
    def width(self) -> float:
        return self.occupied.shape[1] * self.cell

    @property
    def height(self) -> float:
        return self.occupied.shape[0] * self.cell

    @property
    def name(self) -> str:
        return f"{self.family}_{self.seed:03d}"


@dataclass
class _Draw:
    occupied: np.ndarray
    start: tuple[float, float, float]
    goal: tuple[float, float]


def family_of(seed: int) -> str:
    """The family the benchmark gives ``seed``."""
    return MIX[seed % len(MIX)]


def generate(seed: int, family: str | None = None, clearance: float = CLEARANCE) -> GridWorld:
    """The world of ``seed`` in ``family`` (default: the benchmark's mix): the first feasible draw of its generator."""
    family = family or family_of(seed)
    if family not in FAMILIES:
        raise ValueError(f"unknown world family {family!r} (families: {', '.join(FAMILIES)})")
    rng = np.random.default_rng([seed, FAMILIES.index(family)])
    for _ in range(ATTEMPTS):
        draw = _DRAWS[family](rng)
        occupied = _tidy(draw.occupied, draw.start[:2], draw.goal)
        path = shortest_path(occupied, CELL, draw.start[:2], draw.goal, clearance)
        if path is not None:
            world = GridWorld(family, seed, occupied, CELL, draw.start, draw.goal, clearance, path,
                              sum(math.dist(a, b) for a, b in zip(path, path[1:])))
            world.difficulty = measure(occupied, CELL, path)
            return world
    raise ValueError(f"{family} seed {seed}: no draw in {ATTEMPTS} has a path with {clearance:g} m of clearance")


# -- the grid ---------------------------------------------------------------------------------------------------


def _empty(width: float, height: float) -> np.ndarray:
    return np.zeros((round(height / CELL), round(width / CELL)), dtype=bool)


def _centres(grid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """x and y of every cell's centre, each shaped like the grid."""
    rows, cols = grid.shape
    return np.meshgrid((np.arange(cols) + 0.5) * CELL, (np.arange(rows) + 0.5) * CELL)


def _box(grid: np.ndarray, x0: float, y0: float, x1: float, y1: float, value: bool = True) -> None:
    """Fill (or clear) the cells whose centres lie in the rectangle [x0, x1] x [y0, y1]."""
    xs, ys = _centres(grid)
    grid[(xs >= min(x0, x1)) & (xs <= max(x0, x1)) & (ys >= min(y0, y1)) & (ys <= max(y0, y1))] = value


def _clear_disc(grid: np.ndarray, x: float, y: float, radius: float) -> None:
    xs, ys = _centres(grid)
    grid[(xs - x) ** 2 + (ys - y) ** 2 <= radius ** 2] = False


def _tidy(grid: np.ndarray, start: tuple[float, float], goal: tuple[float, float]) -> np.ndarray:
    """The grid ready to be a world: start and goal clear, no cells touching by a corner only, no enclosed pockets.

    Cells touching by a corner only would make polygons that touch at a point;
    a pocket of free cells no path reaches is filled, so that the obstacles
    are simple polygons without holes.
    """
    grid = grid.copy()
    for x, y in (start, goal):
        _clear_disc(grid, x, y, 0.6)
    for _ in range(8):
        a, b, c, d = grid[:-1, :-1], grid[1:, 1:], grid[:-1, 1:], grid[1:, :-1]
        falling, rising = a & b & ~c & ~d, c & d & ~a & ~b
        if not (falling.any() or rising.any()):
            break
        c |= falling
        a |= rising
    labels, _ = ndimage.label(~grid)
    i, j = int(start[0] / CELL), int(start[1] / CELL)
    if labels[j, i]:
        grid |= labels != labels[j, i]
    return grid


# -- the families -----------------------------------------------------------------------------------------------


def _cellular(rng: np.random.Generator) -> _Draw:
    """BARN's kind of field: random fill, smoothed by a cellular automaton, between two clear approach areas."""
    width, height = 12.0, 6.0
    grid = _empty(width, height)
    fill, steps = rng.uniform(0.15, 0.35), int(rng.integers(2, 5))
    grid[:] = rng.random(grid.shape) < fill
    kernel = np.ones((3, 3), dtype=int)
    kernel[1, 1] = 0
    for _ in range(steps):
        around = ndimage.convolve(grid.astype(int), kernel, mode="constant", cval=0)
        grid = np.where(around >= 5, True, np.where(around <= 1, False, grid))
    _box(grid, 0, 0, 2.2, height, value=False)
    _box(grid, width - 2.2, 0, width, height, value=False)
    start = (1.0, float(rng.uniform(2.0, height - 2.0)), 0.0)
    return _Draw(grid, start, (width - 1.0, float(rng.uniform(1.5, height - 1.5))))


def _scatter_boxes(rng: np.random.Generator, grid: np.ndarray, count: int, area: tuple[float, float, float, float],
                   keep_clear: list[tuple[float, float]]) -> None:
    """``count`` boxes 0.3 to 0.9 m wide in ``area`` (x0, y0, x1, y1), none within 1.2 m of the points to keep clear."""
    x0, y0, x1, y1 = area
    placed = 0
    for _ in range(count * 10):
        if placed == count:
            break
        w, h = rng.uniform(0.3, 0.9, size=2)
        x, y = rng.uniform(x0 + w / 2, x1 - w / 2), rng.uniform(y0 + h / 2, y1 - h / 2)
        if all(math.dist((x, y), p) > 1.2 + max(w, h) / 2 for p in keep_clear):
            _box(grid, x - w / 2, y - h / 2, x + w / 2, y + h / 2)
            placed += 1


def _doorway(rng: np.random.Generator) -> _Draw:
    """Two rooms split by a wall with one door 1.0 to 2.0 m wide; a pillar behind the door more often than not."""
    width, height = 12.0, 7.0
    grid = _empty(width, height)
    wall = float(rng.uniform(4.5, 7.5))
    door = float(rng.uniform(1.0, 2.0))
    centre = float(rng.uniform(0.8 + door / 2, height - 0.8 - door / 2))
    _box(grid, wall, 0, wall + CELL, height)
    _box(grid, wall - CELL, centre - door / 2, wall + 2 * CELL, centre + door / 2, value=False)
    start = (1.0, float(rng.uniform(1.5, height - 1.5)), 0.0)
    goal = (width - 1.0, float(rng.uniform(1.5, height - 1.5)))
    if rng.random() < 0.6:
        px, py = wall + rng.uniform(1.0, 2.0), centre + rng.uniform(-0.8, 0.8)
        _box(grid, px - 0.25, py - 0.25, px + 0.25, py + 0.25)
    keep = [start[:2], goal, (wall - 0.6, centre), (wall + 0.8, centre)]
    _scatter_boxes(rng, grid, int(rng.integers(0, 3)), (0.5, 0.3, wall - 0.6, height - 0.3), keep)
    _scatter_boxes(rng, grid, int(rng.integers(0, 3)), (wall + 0.8, 0.3, width - 0.5, height - 0.3), keep)
    return _Draw(grid, start, goal)


def _distance_to_polyline(xs: np.ndarray, ys: np.ndarray, points: list[tuple[float, float]]) -> np.ndarray:
    best = np.full(xs.shape, np.inf)
    for (ax, ay), (bx, by) in zip(points, points[1:]):
        dx, dy = bx - ax, by - ay
        t = np.clip(((xs - ax) * dx + (ys - ay) * dy) / max(dx * dx + dy * dy, 1e-12), 0, 1)
        best = np.minimum(best, np.hypot(xs - ax - t * dx, ys - ay - t * dy))
    return best


def _corridor(rng: np.random.Generator) -> _Draw:
    """A corridor 1.3 to 2.2 m wide with one bend across the field; one to three boxes stand out from its walls."""
    width, height = 12.0, 7.0
    grid = _empty(width, height)
    wide = float(rng.uniform(1.3, 2.2))
    low, high = 1.2 + wide / 2, height - 1.2 - wide / 2
    y0 = float(rng.uniform(low, high))
    y1 = float(np.clip(y0 + rng.choice((-1, 1)) * rng.uniform(1.0, 2.5), low, high))
    bend = float(rng.uniform(4.0, 8.0))
    line = [(0.0, y0), (bend, y0), (bend, y1), (width, y1)]
    xs, ys = _centres(grid)
    grid[:] = _distance_to_polyline(xs, ys, line) > wide / 2
    for _ in range(int(rng.integers(1, 4))):
        leg = int(rng.integers(0, 2))
        x = float(rng.uniform(2.0, bend - 1.0) if leg == 0 else rng.uniform(bend + 1.0, width - 2.0))
        y = y0 if leg == 0 else y1
        depth, long = float(rng.uniform(0.3, max(0.35, wide - 0.9))), float(rng.uniform(0.4, 1.0))
        side = 1 if rng.random() < 0.5 else -1
        edge = y + side * wide / 2
        _box(grid, x - long / 2, edge, x + long / 2, edge - side * depth)
    return _Draw(grid, (1.0, y0, 0.0), (width - 1.0, y1))


def _u_trap(rng: np.random.Generator) -> _Draw:
    """A U open towards the robot, between it and the goal: its arms 1.5 to 2.5 m long, 1.6 to 2.6 m apart."""
    width, height = 12.0, 8.0
    grid = _empty(width, height)
    bottom, depth, inner = float(rng.uniform(6.5, 8.0)), float(rng.uniform(1.5, 2.5)), float(rng.uniform(1.6, 2.6))
    centre = float(rng.uniform(height / 2 - 0.5, height / 2 + 0.5))
    thick = 2 * CELL
    _box(grid, bottom, centre - inner / 2 - thick, bottom + thick, centre + inner / 2 + thick)
    for side in (-1, 1):
        arm = centre + side * (inner / 2 + thick / 2)
        _box(grid, bottom - depth, arm - thick / 2, bottom + thick, arm + thick / 2)
    start = (1.0, centre + float(rng.uniform(-0.3, 0.3)), 0.0)
    return _Draw(grid, start, (width - 1.0, centre + float(rng.uniform(-0.5, 0.5))))


_DRAWS = {"cellular": _cellular, "doorway": _doorway, "corridor": _corridor, "u_trap": _u_trap}
