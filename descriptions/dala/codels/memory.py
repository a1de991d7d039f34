"""NDD's obstacle memory: each sweep's returns kept in the world frame, so ND sees what left the laser's field.

The laser covers the 180 degrees ahead, and Aspect's map forgets a return
within two sweeps; what the robot passed, beside and behind it, would
otherwise count as free.  Each new map's returns (its cells at OCCUPIED:
the last sweep's) are placed in the world frame at the pose the robot had
when the sweep was taken (the map's ``stamp``, the poses interpolated from
the Pos posters seen), kept ``keep`` seconds and within ``reach`` of the
robot, and given back in the robot's current frame.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from . import grid, odometry

HISTORY = 2.0  # s of poses kept to place a sweep


@dataclass
class Memory:
    cells: dict[tuple[int, int], tuple[float, float, float]] = field(default_factory=dict)  # cell -> x, y, seen
    poses: list[tuple[float, dict]] = field(default_factory=list)  # (stamp, pose), oldest first
    seq: int | None = None  # the last map's sweep placed
    resolution: float = 0.0
    heading_for: dict | None = None  # the point ND last headed for through a valley (world frame)

    def clear(self) -> None:
        self.cells, self.poses, self.seq, self.resolution, self.heading_for = {}, [], None, 0.0, None


def _between(t0: float, a: dict, t1: float, b: dict, t: float) -> dict:
    f = (t - t0) / (t1 - t0) if t1 > t0 else 0.0
    return {"x": a["x"] + f * (b["x"] - a["x"]), "y": a["y"] + f * (b["y"] - a["y"]),
            "theta": odometry.wrap(a["theta"] + f * odometry.wrap(b["theta"] - a["theta"]))}


def pose_at(poses: list[tuple[float, dict]], t: float) -> dict:
    """The pose at ``t``: interpolated between the two poses around it, extrapolated (0.2 s at most) past the last.

    A sweep may be newer than the last Pos NDD read (POM publishes every 50 ms).
    """
    if t <= poses[0][0] or len(poses) == 1:
        return poses[0][1] if t <= poses[0][0] else poses[-1][1]
    for (t0, a), (t1, b) in zip(poses, poses[1:]):
        if t0 <= t <= t1:
            return _between(t0, a, t1, b, t)
    (t0, a), (t1, b) = poses[-2], poses[-1]
    return _between(t0, a, t1, b, min(t, t1 + 0.2))


def update(memory: Memory, obs: dict | None, pos: dict, side: int, keep: float,
           reach: float) -> list[tuple[float, float]]:
    """Place the map's new sweep, forget what is old or far, and return the remembered points in the robot frame."""
    now, here = pos["stamp"], pos["estimate"]
    if not memory.poses or now > memory.poses[-1][0]:
        memory.poses.append((now, dict(here)))
    memory.poses = [(t, p) for t, p in memory.poses if now - t <= HISTORY]
    if obs is not None and obs["seq"] != memory.seq:
        size = obs["resolution"]
        if size != memory.resolution:
            memory.cells, memory.resolution = {}, size
        memory.seq = obs["seq"]
        at = pose_at(memory.poses, obs["stamp"])
        for x, y in grid.points(obs["cells"], size, side, threshold=grid.OCCUPIED):
            w = odometry.compose(at, {"x": x, "y": y, "theta": 0.0})
            memory.cells[(math.floor(w["x"] / size), math.floor(w["y"] / size))] = (w["x"], w["y"], obs["stamp"])
    out = []
    for key, (x, y, seen) in list(memory.cells.items()):
        p = odometry.between(here, {"x": x, "y": y, "theta": 0.0})
        if now - seen > keep or math.hypot(p["x"], p["y"]) > reach:
            del memory.cells[key]
        else:
            out.append((p["x"], p["y"]))
    return out
