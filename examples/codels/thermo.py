"""The codels of the thermo example module (examples/thermo.gen): a simulated room and its heater.

Each codel is a plain function named as in the description, called with one keyword argument per parameter
(docs/runtime.md, *Codels in Python*): ``in`` values are plain data, ``out``/``inout`` are holders with ``.value``.
"""
from runtime.genom import Throw

PERIOD = 0.05  # s, the sense task's period
HEATER, OUTSIDE = 23.0, 10.0  # C: what the heater can bring the room to, and the outside temperature
RATE = 0.5  # per second: how fast the room goes towards the heater's or the outside's temperature


def thermoOpen(now):
    now.value = {"celsius": 18.0, "heating": False}
    return "read"


def thermoRead(now, Room):
    towards = HEATER if now.value["heating"] else OUTSIDE
    now.value["celsius"] = round(now.value["celsius"] + (towards - now.value["celsius"]) * RATE * PERIOD, 4)
    Room.value = dict(now.value)
    return "pause::read"


def thermoCheckLimit(limit):
    if not 0.0 < limit < 60.0:
        raise Throw("e_too_hot", {"celsius": limit})


def thermoHeatOn(target, limit, now):
    if target > (limit or 30.0):
        raise Throw("e_too_hot", {"celsius": target})
    now.value["heating"] = True
    return "warm"


def thermoWarm(target, now):
    return "off" if now["celsius"] >= target else "pause::warm"


def thermoHeatOff(now):
    now.value["heating"] = False
    return "ether"


def thermoHeatStop(now):
    now.value["heating"] = False
    return "ether"


def thermoWarp(celsius, now):
    now.value["celsius"] = celsius
    return "ether"
