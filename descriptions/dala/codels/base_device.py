"""The simulated base as a device for RFLEX's C codels: a table of C-callable functions over the ir-sim world.

A real base's codels talk to its serial port; RFLEX's C codels (descriptions/dala/codels_c/RFLEX) talk to
this table instead, which they get with ``genom2bip_device("dala_base")``.  Its layout is
descriptions/dala/codels_c/RFLEX/dala_base.h.  The Python codels (RFLEX.py) drive the same world directly.
"""
from __future__ import annotations

import ctypes

from . import world

COMMAND = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.c_double)
ADVANCE = ctypes.CFUNCTYPE(ctypes.c_double, ctypes.c_double)
MEASURE = ctypes.CFUNCTYPE(ctypes.c_double, ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_double))


class Base(ctypes.Structure):
    """``struct dala_base``: command(v, w), advance(seconds) -> t, measure(&v, &w) -> t."""

    _fields_ = [("command", COMMAND), ("advance", ADVANCE), ("measure", MEASURE)]


def _command(v: float, w: float) -> None:
    world.sim().command = (v, w)


def _advance(seconds: float) -> float:
    sim = world.sim()
    sim.advance(seconds)
    return sim.t


def _measure(v, w) -> float:
    sim = world.sim()
    speed = sim.velocity()
    v[0], w[0] = speed["v"], speed["w"]
    return sim.t


def make() -> Base:
    """The device's table (its callbacks kept alive by the structure)."""
    return Base(COMMAND(_command), ADVANCE(_advance), MEASURE(_measure))
