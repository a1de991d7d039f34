"""Aspect, simulated: a robot-centred occupancy grid of the last scan, 64 x 64 cells."""
import math

from runtime.genom import Throw

SIDE = 64
_seen = {"seq": None}


def aspCheckParams(resolution, decay):
    if resolution <= 0 or not 0 <= decay <= 1:
        raise Throw("e_bad_params", resolution=resolution)


def _empty(resolution):
    return {"resolution": resolution, "origin": {"x": 0.0, "y": 0.0, "theta": 0.0}, "cells": [0] * (SIDE * SIDE),
            "seq": 0}


def aspReset(Obs):
    Obs.value = _empty(0.1)
    return "fuse"


def aspFuse(Scan, last_seq, Obs):
    if Scan is None or Scan["seq"] == _seen["seq"]:
        return "wait"
    grid = _empty(Obs.value["resolution"] if Obs.value else 0.1)
    res = grid["resolution"]
    for i, r in enumerate(Scan["ranges"]):
        if r < Scan["range_max"]:
            a = Scan["angle_min"] + i * Scan["angle_step"]
            cx, cy = int(r * math.cos(a) / res) + SIDE // 2, int(r * math.sin(a) / res) + SIDE // 2
            if 0 <= cx < SIDE and 0 <= cy < SIDE:
                grid["cells"][cy * SIDE + cx] = 255
    grid["seq"] = last_seq.value = _seen["seq"] = Scan["seq"]
    Obs.value = grid
    return "pause::fuse"


def aspWaitScan(Scan):
    return "fuse" if Scan is not None and Scan["seq"] != _seen["seq"] else "pause::wait"


def aspStop():
    return "ether"
