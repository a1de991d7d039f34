"""Aspect: every new laser sweep is fused into the robot-centred obstacle map Obs (see grid.py).

The map's cell size and the decay of old returns are the ids' ``resolution``
and ``decay`` (SetParams); before any SetParams (resolution still 0) they are
0.1 m and 0.6.  A new cell size starts the map afresh: cells of another size
cannot be fused.
"""
from runtime.genom import Throw

from . import grid

SIDE = 64  # dala::map_cells
RESOLUTION = 0.1  # m per cell, until SetParams
DECAY = 0.6  # a return missed by one sweep stays one more sweep, until SetParams
_seen = {"seq": None}


def aspCheckParams(resolution, decay):
    if resolution <= 0 or not 0 <= decay <= 1:
        raise Throw("e_bad_params", resolution=resolution)


def parameters(resolution: float, decay: float) -> tuple[float, float]:
    """The cell size and decay in force: SetParams' values, or the defaults before it."""
    return (resolution, decay) if resolution > 0 else (RESOLUTION, DECAY)


def _empty(resolution: float):
    return {"resolution": resolution, "origin": {"x": 0.0, "y": 0.0, "theta": 0.0}, "cells": [0] * (SIDE * SIDE),
            "seq": 0, "stamp": 0.0}


def aspReset(resolution, Obs):
    _seen["seq"] = None
    Obs.value = _empty(parameters(resolution, 0.0)[0])
    return "fuse"


def aspFuse(Scan, resolution, decay, last_seq, Obs):
    if Scan is None or Scan["seq"] == _seen["seq"]:
        return "wait"
    size, keep = parameters(resolution, decay)
    previous = Obs.value
    if not previous or previous["resolution"] != size:
        previous = _empty(size)
    cells = grid.fuse(Scan, previous["cells"], size, SIDE, keep)
    last_seq.value = _seen["seq"] = Scan["seq"]
    Obs.value = {**previous, "cells": cells, "seq": Scan["seq"], "stamp": Scan["stamp"]}
    return "pause::fuse"


def aspWaitScan(Scan):
    return "pause::fuse" if Scan is not None and Scan["seq"] != _seen["seq"] else "pause::wait"


def aspStop():
    return "ether"
