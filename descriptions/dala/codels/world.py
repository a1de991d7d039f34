"""The simulated world of the DALA codels: a 10 m square room with one box, and the robot's true pose.

RFLEX moves the robot by integrating the speed it applies (unicycle
kinematics); LaserRF casts its beams from the true pose.  Everything else
sees the robot only through posters, as on the real robot.
"""
import math

ROOM = (-5.0, -5.0, 5.0, 5.0)  # xmin, ymin, xmax, ymax of the walls
BOXES = [(1.5, -0.5, 2.0, 0.5)]  # obstacles, as axis-aligned rectangles
pose = {"x": 0.0, "y": 0.0, "theta": 0.0}
clock = {"t": 0.0}


def move(v: float, w: float, dt: float) -> None:
    pose["theta"] = math.atan2(math.sin(pose["theta"] + w * dt), math.cos(pose["theta"] + w * dt))
    pose["x"] += v * math.cos(pose["theta"]) * dt
    pose["y"] += v * math.sin(pose["theta"]) * dt
    clock["t"] += dt


def _slab(o: float, d: float, lo: float, hi: float) -> tuple[float, float]:
    if abs(d) < 1e-12:
        return (-math.inf, math.inf) if lo <= o <= hi else (math.inf, -math.inf)
    a, b = (lo - o) / d, (hi - o) / d
    return min(a, b), max(a, b)


def ray(angle: float, range_max: float) -> float:
    """Distance from the robot to the first wall or box along ``angle`` (robot frame)."""
    ox, oy = pose["x"], pose["y"]
    dx, dy = math.cos(pose["theta"] + angle), math.sin(pose["theta"] + angle)
    best = range_max
    xmin, ymin, xmax, ymax = ROOM
    for t in ((xmax - ox) / dx if dx > 0 else (xmin - ox) / dx if dx < 0 else math.inf,
              (ymax - oy) / dy if dy > 0 else (ymin - oy) / dy if dy < 0 else math.inf):
        best = min(best, t)
    for x0, y0, x1, y1 in BOXES:
        tx0, tx1 = _slab(ox, dx, x0, x1)
        ty0, ty1 = _slab(oy, dy, y0, y1)
        near, far = max(tx0, ty0), min(tx1, ty1)
        if near <= far and near > 0:
            best = min(best, near)
    return best
