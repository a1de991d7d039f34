"""How hard a world is to cross, measured along its shortest path (the metrics of BARN, Perille et al. 2020).

Each metric is taken at points 0.15 m apart along the path:

* ``closest``: the distance to the closest obstacle, averaged (``narrowest``: its least value);
* ``visibility``: how far 16 rays go before meeting an obstacle (at most the lidar's 6 m), averaged;
* ``dispersion``: around each point, the number of switches between a ray that meets an
  obstacle within 1.5 m and one that does not (16 rays): how many openings surround it;
* ``dimension`` (characteristic dimension): the free width of the narrowest of four axes
  (0, 45, 90, 135 degrees) through the point, averaged: how tight the passages are;
* ``tortuosity``: the path's length over the straight distance.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from genom2bip.mission.worlds.clearance import FINE, distances

STEP = 0.15  # m between two points where the metrics are taken
RAYS = 16
REACH = 6.0  # m: the lidar's range
NEAR = 1.5  # m: the radius within which dispersion looks for obstacles


@dataclass(frozen=True)
class Difficulty:
    closest: float
    narrowest: float
    visibility: float
    dispersion: float
    dimension: float
    tortuosity: float

    def as_dict(self) -> dict[str, float]:
        return {k: round(v, 3) for k, v in asdict(self).items()}


def _samples(path: list[tuple[float, float]]) -> np.ndarray:
    out = [path[0]]
    for a, b in zip(path, path[1:]):
        n = max(1, math.ceil(math.dist(a, b) / STEP))
        out += [(a[0] + (b[0] - a[0]) * k / n, a[1] + (b[1] - a[1]) * k / n) for k in range(1, n + 1)]
    return np.array(out)


def _ray_lengths(points: np.ndarray, angles: np.ndarray, blocked: np.ndarray, fine: float, reach: float) -> np.ndarray:
    """(points, angles): how far each ray goes before a blocked cell (or the grid's edge), at most ``reach``."""
    steps = np.arange(fine / 2, reach + fine / 2, fine / 2)
    dx, dy = np.cos(angles), np.sin(angles)
    xs = points[:, None, None, 0] + dx[None, :, None] * steps[None, None, :]
    ys = points[:, None, None, 1] + dy[None, :, None] * steps[None, None, :]
    rows, cols = blocked.shape
    outside = (xs < 0) | (ys < 0) | (xs >= cols * fine) | (ys >= rows * fine)
    j = np.clip((ys / fine).astype(int), 0, rows - 1)
    i = np.clip((xs / fine).astype(int), 0, cols - 1)
    hit = outside | blocked[j, i]
    first = np.where(hit.any(axis=2), hit.argmax(axis=2), len(steps))
    return np.minimum(np.concatenate([steps, [reach]])[first], reach)


def measure(occupied: np.ndarray, cell: float, path: list[tuple[float, float]]) -> Difficulty:
    """The difficulty metrics of ``path`` in the world ``occupied`` (cells of ``cell`` m)."""
    dist, fine = distances(occupied, cell)
    blocked = np.kron(occupied, np.ones((FINE, FINE), dtype=bool))
    points = _samples(path)
    j = np.clip((points[:, 1] / fine).astype(int), 0, dist.shape[0] - 1)
    i = np.clip((points[:, 0] / fine).astype(int), 0, dist.shape[1] - 1)
    closest = dist[j, i]
    angles = np.arange(RAYS) * 2 * math.pi / RAYS
    seen = _ray_lengths(points, angles, blocked, fine, REACH)
    near = seen < NEAR
    switches = (near != np.roll(near, 1, axis=1)).sum(axis=1)
    axes = np.arange(8) * math.pi / 4  # both directions of the four axes: 0, 45, 90, 135 degrees and their opposites
    both = _ray_lengths(points, axes, blocked, fine, math.hypot(*blocked.shape) * fine)
    widths = both[:, :4] + both[:, 4:]
    length = sum(math.dist(a, b) for a, b in zip(path, path[1:]))
    straight = max(math.dist(path[0], path[-1]), 1e-9)
    return Difficulty(closest=float(closest.mean()), narrowest=float(closest.min()), visibility=float(seen.mean()),
                      dispersion=float(switches.mean()), dimension=float(widths.min(axis=1).mean()),
                      tortuosity=length / straight)
