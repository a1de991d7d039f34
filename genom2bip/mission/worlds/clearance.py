"""Where the robot fits in a grid world, and the shortest path there: a grid search, shortened by line of sight.

The obstacle grid is refined ``FINE`` times (5 cm cells for 15 cm obstacles)
so that a cell's distance to the nearest obstacle is within 2.5 cm of the
true one; the world's outer walls count as obstacles.  A cell is free for
the robot when that distance is at least the clearance.  Dijkstra's search
(scipy's, over the 8-connected free cells) gives the shortest grid path;
pulling it tight where the straight segment stays free gives a path close to
the true shortest one, whose length is the benchmark's reference.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import ndimage, sparse
from scipy.sparse import csgraph

FINE = 3  # fine cells per obstacle cell, along each axis


def distances(occupied: np.ndarray, cell: float) -> tuple[np.ndarray, float]:
    """(distance in m from each fine cell's centre to the nearest obstacle or outer wall, the fine cell's size)."""
    fine = cell / FINE
    grid = np.kron(occupied, np.ones((FINE, FINE), dtype=bool))
    padded = np.pad(grid, 1, constant_values=True)
    edt = ndimage.distance_transform_edt(~padded)[1:-1, 1:-1] * fine
    return np.maximum(edt - fine / 2, 0.0), fine  # to the obstacle cell's edge, not its centre


def _index(point: tuple[float, float], fine: float, shape: tuple[int, int]) -> tuple[int, int]:
    j = min(max(int(point[1] / fine), 0), shape[0] - 1)
    i = min(max(int(point[0] / fine), 0), shape[1] - 1)
    return j, i


def _graph(free: np.ndarray, fine: float) -> sparse.csr_matrix:
    """The 8-connected graph of the free cells, edges weighted by their length."""
    rows, cols = free.shape
    ids = np.arange(rows * cols).reshape(rows, cols)
    heads, tails, weights = [], [], []
    for dj, di in ((0, 1), (1, 0), (1, 1), (1, -1)):
        j0, j1 = 0, rows - dj
        i0, i1 = max(0, -di), cols - max(0, di)
        a = free[j0:j1, i0:i1] & free[j0 + dj:j1 + dj, i0 + di:i1 + di]
        heads.append(ids[j0:j1, i0:i1][a])
        tails.append(ids[j0 + dj:j1 + dj, i0 + di:i1 + di][a])
        weights.append(np.full(int(a.sum()), fine * math.hypot(dj, di)))
    n = rows * cols
    return sparse.csr_matrix((np.concatenate(weights), (np.concatenate(heads), np.concatenate(tails))), shape=(n, n))


def visible(a: tuple[float, float], b: tuple[float, float], free: np.ndarray, fine: float) -> bool:
    """Does the segment a-b stay on free cells: every cell it passes through, corners included (a grid traversal)?"""
    rows, cols = free.shape
    i, j = int(a[0] / fine), int(a[1] / fine)
    ti, tj = int(b[0] / fine), int(b[1] / fine)
    dx, dy = b[0] - a[0], b[1] - a[1]
    si, sj = (1 if dx > 0 else -1), (1 if dy > 0 else -1)
    # the distance along the segment (as a fraction of it) to the next vertical and horizontal cell border
    tx = ((i + (si > 0)) * fine - a[0]) / dx if dx else math.inf
    ty = ((j + (sj > 0)) * fine - a[1]) / dy if dy else math.inf
    step_x, step_y = (fine / abs(dx) if dx else math.inf), (fine / abs(dy) if dy else math.inf)
    while True:
        if not (0 <= i < cols and 0 <= j < rows and free[j, i]):
            return False
        if (i, j) == (ti, tj) or min(tx, ty) > 1:
            return True
        if abs(tx - ty) < 1e-9:  # through a corner: both cells beside it count
            if not (0 <= i + si < cols and free[j, i + si]) or not (0 <= j + sj < rows and free[j + sj, i]):
                return False
            i, j, tx, ty = i + si, j + sj, tx + step_x, ty + step_y
        elif tx < ty:
            i, tx = i + si, tx + step_x
        else:
            j, ty = j + sj, ty + step_y


def _pulled(points: list[tuple[float, float]], free: np.ndarray, fine: float) -> list[tuple[float, float]]:
    """The path with every corner removed whose neighbours see each other: a taut string along the grid path."""
    out = [points[0]]
    anchor, last = points[0], points[0]
    for p in points[1:]:
        if not visible(anchor, p, free, fine):
            out.append(last)
            anchor = last
        last = p
    out.append(points[-1])
    return out


def shortest_path(occupied: np.ndarray, cell: float, start: tuple[float, float], goal: tuple[float, float],
                  clearance: float) -> list[tuple[float, float]] | None:
    """The shortest path from start to goal keeping ``clearance`` from every obstacle, None when there is none."""
    dist, fine = distances(occupied, cell)
    free = dist >= clearance
    s, g = _index(start, fine, free.shape), _index(goal, fine, free.shape)
    if not (free[s] and free[g]):
        return None
    cols = free.shape[1]
    lengths, previous = csgraph.dijkstra(_graph(free, fine), directed=False, indices=s[0] * cols + s[1],
                                         return_predecessors=True)
    target = g[0] * cols + g[1]
    if not math.isfinite(lengths[target]):
        return None
    chain = [target]
    while chain[-1] != s[0] * cols + s[1]:
        chain.append(int(previous[chain[-1]]))
    cells = [((k % cols + 0.5) * fine, (k // cols + 0.5) * fine) for k in reversed(chain)]
    return _pulled([start, *cells[1:-1], goal], free, fine)
