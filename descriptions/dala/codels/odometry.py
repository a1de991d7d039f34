"""Poses in the plane: RFLEX's odometry by integration of the measured speeds, POM's fusion of it into a frame.

A pose is a dict ``{"x", "y", "theta"}``.  ``compose(a, b)`` is the pose b,
given in the frame of a, expressed in a's parent frame; ``between(a, b)`` is
its inverse (b seen from a).
"""
from __future__ import annotations

import math


def wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


def integrate(pose: dict, v: float, w: float, dt: float) -> dict:
    """Unicycle dead reckoning over ``dt`` (exact on an arc)."""
    th = pose["theta"]
    if abs(w) < 1e-9:
        dx, dy = v * dt * math.cos(th), v * dt * math.sin(th)
    else:
        dx = v / w * (math.sin(th + w * dt) - math.sin(th))
        dy = -v / w * (math.cos(th + w * dt) - math.cos(th))
    return {"x": pose["x"] + dx, "y": pose["y"] + dy, "theta": wrap(th + w * dt)}


def compose(a: dict, b: dict) -> dict:
    c, s = math.cos(a["theta"]), math.sin(a["theta"])
    return {"x": a["x"] + c * b["x"] - s * b["y"], "y": a["y"] + s * b["x"] + c * b["y"],
            "theta": wrap(a["theta"] + b["theta"])}


def between(a: dict, b: dict) -> dict:
    c, s = math.cos(a["theta"]), math.sin(a["theta"])
    dx, dy = b["x"] - a["x"], b["y"] - a["y"]
    return {"x": c * dx + s * dy, "y": -s * dx + c * dy, "theta": wrap(b["theta"] - a["theta"])}


def grow(covariance: list[float], distance: float, turned: float, k_d: float = 0.01, k_t: float = 0.005) -> list[float]:
    """Odometry drift: the variances of x, y and theta grow with the distance driven and the angle turned."""
    return [covariance[0] + k_d * distance, covariance[1] + k_d * distance, covariance[2] + k_t * abs(turned)]
