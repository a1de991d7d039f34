"""RFLEX, simulated: the base applies the Speed poster (acceleration-limited) and publishes odometry."""
from . import world

PERIOD = 0.025  # s, the servo task


def rflexInitOdometry(Odo):
    Odo.value = {"position": dict(world.pose), "velocity": {"v": 0.0, "w": 0.0}, "stamp": world.clock["t"]}
    return "odometry"


def rflexOdometry(Odo):
    Odo.value = {"position": dict(world.pose), "velocity": dict(_applied), "stamp": world.clock["t"]}
    world.move(_applied["v"], _applied["w"], PERIOD)
    return "pause::odometry"


_applied = {"v": 0.0, "w": 0.0}


def rflexClose():
    return "ether"


def rflexOpen(local_device, ids_device):
    ids_device.value = local_device
    return "ether"


def rflexStartTracking(mode):
    mode.value = "drive_tracking"
    return "track"


def rflexTrack(Speed, acceleration_max, command):
    wanted = Speed or {"v": 0.0, "w": 0.0}
    step = (acceleration_max or 0.5) * PERIOD
    _applied["v"] += max(-step, min(step, wanted["v"] - _applied["v"]))
    _applied["w"] = wanted["w"]
    command.value = dict(_applied)
    return "pause::track"


def rflexBrake(mode, command):
    mode.value = "drive_braking"
    _applied.update(v=0.0, w=0.0)
    command.value = dict(_applied)
    return "ether"


def rflexStop(command):
    _applied.update(v=0.0, w=0.0)
    command.value = dict(_applied)
    return "ether"
