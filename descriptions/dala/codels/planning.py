"""The Planner's global method: a world-frame obstacle grid of what the laser saw, and Dijkstra's search over it.

What Aspect's map showed is kept for good in the world frame (``Seen``: the
cells of every sweep, placed at the pose of the sweep); what was never seen
counts as free, as D* Lite and its kin assume, and the plan changes as the
map grows.  A cell seen stands for a laser return anywhere inside it, up to
half its diagonal from its centre (``precision``): every distance to an
obstacle is counted from there.  ``plan`` searches the 8-connected grid of
the cells where the robot fits (at least ``radius`` from every place an
obstacle cell may hold) with scipy's
Dijkstra from the goal, each step's cost its length times a penalty that
grows as the cell comes within ``clearance`` of an obstacle (the plan keeps
to the middle of passages where it can, squeezes through where it must) and
times ``avoid`` on the cells of a way the robot could not follow; ``target``
takes the farthest point of the path within ``lookahead`` that the robot
reaches in a straight line keeping ``radius`` from every such place: the
intermediate goal ND drives to.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage, sparse, spatial
from scipy.sparse import csgraph

MARGIN = 2.0  # m of grid round the robot, the goal and the obstacles seen
CROWD = 3.0  # the cost of a step at ``radius`` from an obstacle, over one at ``clearance`` or more
SNAP = 1.0  # m: a start or goal inside the obstacles' margin moves to the nearest free cell within this


def precision(resolution: float) -> float:
    """How far from its cell's centre the return that marked the cell may lie: half the cell's diagonal."""
    return resolution * math.sqrt(2) / 2


class NoPath(Exception):
    """No way joins the start to the goal on the grid; the message says why."""


@dataclass
class Seen:
    """The obstacle cells seen, in the world frame (cell size ``resolution``), and how often the set grew."""

    resolution: float = 0.1
    cells: set[tuple[int, int]] = field(default_factory=set)
    version: int = 0

    def add(self, points: list[tuple[float, float]]) -> bool:
        """Add world points; True when a cell was new."""
        before = len(self.cells)
        r = self.resolution
        self.cells.update((math.floor(x / r), math.floor(y / r)) for x, y in points)
        if len(self.cells) != before:
            self.version += 1
            return True
        return False


@dataclass
class Plan:
    """A path from the start to the goal (world points, cell centres), its length, and the grid it was found on."""

    points: list[tuple[float, float]]
    length: float
    free: np.ndarray
    origin: tuple[int, int]  # the cell of free[0, 0]
    resolution: float
    radius: float = 0.0  # m the robot keeps from every place an obstacle cell may hold
    obstacles: spatial.cKDTree | None = None  # the obstacle cells' centres (world frame)


def _graph(free: np.ndarray, cost: np.ndarray, resolution: float) -> sparse.csr_matrix:
    """The 8-connected graph of the free cells, each edge its length times the mean cost of its two cells."""
    rows, cols = free.shape
    ids = np.arange(rows * cols).reshape(rows, cols)
    heads, tails, weights = [], [], []
    for dj, di in ((0, 1), (1, 0), (1, 1), (1, -1)):
        j1 = rows - dj
        i0, i1 = max(0, -di), cols - max(0, di)
        a = free[0:j1, i0:i1] & free[dj:j1 + dj, i0 + di:i1 + di]
        if dj and di:  # no diagonal step past the corner of a blocked cell
            a &= free[dj:j1 + dj, i0:i1] & free[0:j1, i0 + di:i1 + di]
        heads.append(ids[0:j1, i0:i1][a])
        tails.append(ids[dj:j1 + dj, i0 + di:i1 + di][a])
        mean = (cost[0:j1, i0:i1][a] + cost[dj:j1 + dj, i0 + di:i1 + di][a]) / 2
        weights.append(mean * resolution * math.hypot(dj, di))
    n = rows * cols
    return sparse.csr_matrix((np.concatenate(weights), (np.concatenate(heads), np.concatenate(tails))), shape=(n, n))


def _snap(free: np.ndarray, cell: tuple[int, int], reach: int) -> tuple[int, int] | None:
    """``cell`` when free, else the nearest free cell within ``reach`` cells, else None."""
    j, i = cell
    if 0 <= j < free.shape[0] and 0 <= i < free.shape[1] and free[j, i]:
        return cell
    best, where = math.inf, None
    for dj in range(-reach, reach + 1):
        for di in range(-reach, reach + 1):
            jj, ii = j + dj, i + di
            d = math.hypot(dj, di)
            if d <= reach and d < best and 0 <= jj < free.shape[0] and 0 <= ii < free.shape[1] and free[jj, ii]:
                best, where = d, (jj, ii)
    return where


def plan(seen: Seen, start: tuple[float, float], goal: tuple[float, float], radius: float, clearance: float,
         avoid: set[tuple[int, int]] | None = None, avoid_cost: float = 4.0) -> Plan:
    """The cheapest way from ``start`` to ``goal`` keeping ``radius`` (m) from every cell seen; NoPath if none."""
    r = seen.resolution
    cs = [(math.floor(start[0] / r), math.floor(start[1] / r)), (math.floor(goal[0] / r), math.floor(goal[1] / r))]
    known = list(seen.cells) + cs
    pad = math.ceil(MARGIN / r)
    i0, j0 = min(c[0] for c in known) - pad, min(c[1] for c in known) - pad
    i1, j1 = max(c[0] for c in known) + pad, max(c[1] for c in known) + pad
    occupied = np.zeros((j1 - j0 + 1, i1 - i0 + 1), dtype=bool)
    if seen.cells:
        cells = np.array(list(seen.cells))
        occupied[cells[:, 1] - j0, cells[:, 0] - i0] = True
    # from a cell's centre to the nearest place an obstacle cell may hold its return, m
    distance = ndimage.distance_transform_edt(~occupied) * r - precision(r)
    free = distance >= radius
    depth = np.clip((clearance - distance) / max(clearance - radius, 1e-9), 0.0, 1.0)
    cost = 1.0 + (CROWD - 1.0) * depth
    for i, j in avoid or ():
        if 0 <= j - j0 < cost.shape[0] and 0 <= i - i0 < cost.shape[1]:
            cost[j - j0, i - i0] *= avoid_cost
    reach = math.ceil(SNAP / r)
    s = _snap(free, (cs[0][1] - j0, cs[0][0] - i0), reach)
    g = _snap(free, (cs[1][1] - j0, cs[1][0] - i0), reach)
    if s is None:
        raise NoPath(f"the robot stands within {radius:g} m of obstacles, with no free cell within {SNAP:g} m")
    if g is None:
        raise NoPath(f"the goal lies within {radius:g} m of obstacles, with no free cell within {SNAP:g} m")
    cols = free.shape[1]
    _, previous = csgraph.dijkstra(_graph(free, cost, r), directed=False, indices=g[0] * cols + g[1],
                                   return_predecessors=True)
    k = s[0] * cols + s[1]
    if k != g[0] * cols + g[1] and previous[k] < 0:
        raise NoPath(f"no way with {radius:g} m of clearance joins the robot to the goal on the map seen")
    chain = [k]
    while chain[-1] != g[0] * cols + g[1]:
        chain.append(int(previous[chain[-1]]))
    points = [((c % cols + i0 + 0.5) * r, (c // cols + j0 + 0.5) * r) for c in chain]
    points = [tuple(start), *points[1:-1], tuple(goal)] if len(points) > 1 else [tuple(start), tuple(goal)]
    length = sum(math.dist(a, b) for a, b in zip(points, points[1:]))
    centres = [((i + 0.5) * r, (j + 0.5) * r) for i, j in seen.cells]
    return Plan(points, length, free, (i0, j0), r, radius, spatial.cKDTree(centres) if centres else None)


def clearance_of(p: Plan, a: tuple[float, float], b: tuple[float, float]) -> float:
    """The least distance from the segment a-b to a place an obstacle cell may hold (inf when none is seen)."""
    if p.obstacles is None:
        return math.inf
    mid, half = ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2), math.dist(a, b) / 2
    reach = half + p.radius + 2 * precision(p.resolution)
    near = p.obstacles.query_ball_point(mid, reach)
    if not near:
        return math.inf
    q = p.obstacles.data[near]
    ab = np.array(b) - np.array(a)
    t = np.clip(((q - np.array(a)) @ ab) / max(float(ab @ ab), 1e-12), 0.0, 1.0)
    closest = np.array(a) + t[:, None] * ab
    return float(np.min(np.hypot(*(q - closest).T))) - precision(p.resolution)


def visible(p: Plan, a: tuple[float, float], b: tuple[float, float]) -> bool:
    """Can the robot drive straight from a to b, on the plan's grid, keeping ``p.radius`` from every obstacle?"""
    for x, y in (a, b):
        i, j = math.floor(x / p.resolution) - p.origin[0], math.floor(y / p.resolution) - p.origin[1]
        if not (0 <= j < p.free.shape[0] and 0 <= i < p.free.shape[1]):
            return False
    return clearance_of(p, a, b) >= p.radius


def target(p: Plan, here: tuple[float, float], lookahead: float) -> tuple[tuple[float, float], float]:
    """(the intermediate goal: the farthest path point within ``lookahead`` seen straight from ``here``, the length
    of the path left from the path point nearest ``here``)."""
    nearest = min(range(len(p.points)), key=lambda k: math.dist(p.points[k], here))
    left = sum(math.dist(a, b) for a, b in zip(p.points[nearest:], p.points[nearest + 1:]))
    left += math.dist(here, p.points[nearest])
    best = p.points[min(nearest + 1, len(p.points) - 1)]
    along = 0.0
    for k in range(nearest + 1, len(p.points)):
        along += math.dist(p.points[k - 1], p.points[k])
        if along > lookahead:
            break
        if visible(p, here, p.points[k]) or k == nearest + 1:
            best = p.points[k]
    return best, left


def corridor(p: Plan, here: tuple[float, float], width: float) -> set[tuple[int, int]]:
    """The cells within ``width`` of the plan's path ahead of ``here``: where a stalled robot was led."""
    nearest = min(range(len(p.points)), key=lambda k: math.dist(p.points[k], here))
    r = p.resolution
    reach = math.ceil(width / r)
    out: set[tuple[int, int]] = set()
    for x, y in p.points[nearest: nearest + math.ceil(3.0 / r)]:
        ci, cj = math.floor(x / r), math.floor(y / r)
        out.update((ci + di, cj + dj) for di in range(-reach, reach + 1) for dj in range(-reach, reach + 1))
    return out
