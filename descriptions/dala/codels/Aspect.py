"""Aspect: every new laser sweep is fused into the robot-centred obstacle map Obs (see grid.py)."""
from runtime.genom import Throw

from . import grid

SIDE = 64  # dala::map_cells
RESOLUTION = 0.1  # m per cell
DECAY = 0.6  # a return missed by one sweep stays one more sweep
_seen = {"seq": None}


def aspCheckParams(resolution, decay):
    if resolution <= 0 or not 0 <= decay <= 1:
        raise Throw("e_bad_params", resolution=resolution)


def _empty():
    return {"resolution": RESOLUTION, "origin": {"x": 0.0, "y": 0.0, "theta": 0.0}, "cells": [0] * (SIDE * SIDE),
            "seq": 0}


def aspReset(Obs):
    _seen["seq"] = None
    Obs.value = _empty()
    return "fuse"


def aspFuse(Scan, last_seq, Obs):
    if Scan is None or Scan["seq"] == _seen["seq"]:
        return "wait"
    previous = Obs.value or _empty()
    cells = grid.fuse(Scan, previous["cells"], previous["resolution"], SIDE, DECAY)
    last_seq.value = _seen["seq"] = Scan["seq"]
    Obs.value = {**previous, "cells": cells, "seq": Scan["seq"]}
    return "pause::fuse"


def aspWaitScan(Scan):
    return "fuse" if Scan is not None and Scan["seq"] != _seen["seq"] else "pause::wait"


def aspStop():
    return "ether"
