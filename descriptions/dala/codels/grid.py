"""Aspect's obstacle map: laser sweeps into a robot-centred occupancy grid, and the grid back into points.

Cell (i, j) of a ``side`` x ``side`` grid covers x in [(i - side/2) r, (i - side/2 + 1) r)
and likewise y with j, in the robot frame of the last sweep; it is stored at
``cells[j * side + i]``.  A beam's end point marks its cell 255 (occupied);
cells seen before keep ``decay`` times their value, so that a return missed
by one sweep does not open a hole at once.
"""
from __future__ import annotations

import math

OCCUPIED = 255
THRESHOLD = 128  # cells at least this high are obstacles


def cell_of(x: float, y: float, resolution: float, side: int) -> int | None:
    """Index of the cell holding (x, y), None outside the grid."""
    i, j = math.floor(x / resolution) + side // 2, math.floor(y / resolution) + side // 2
    return j * side + i if 0 <= i < side and 0 <= j < side else None


def fuse(scan: dict, previous: list[int] | None, resolution: float, side: int, decay: float) -> list[int]:
    """The grid after one sweep: its returns occupied, older cells decayed."""
    cells = [int(c * decay) for c in previous] if previous and len(previous) == side * side else [0] * (side * side)
    top = scan["range_max"]
    for k, r in enumerate(scan["ranges"]):
        if r >= top or not math.isfinite(r):
            continue
        a = scan["angle_min"] + k * scan["angle_step"]
        c = cell_of(r * math.cos(a), r * math.sin(a), resolution, side)
        if c is not None:
            cells[c] = OCCUPIED
    return cells


def points(cells: list[int], resolution: float, side: int, threshold: int = THRESHOLD) -> list[tuple[float, float]]:
    """Centres of the cells at least ``threshold`` (default: the obstacles; OCCUPIED: the last sweep's), robot frame."""
    out = []
    for c, value in enumerate(cells):
        if value >= threshold:
            i, j = c % side, c // side
            out.append(((i - side // 2 + 0.5) * resolution, (j - side // 2 + 0.5) * resolution))
    return out
