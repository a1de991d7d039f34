"""RFLEX on the simulated base: tracks the Speed poster under an acceleration limit, publishes odometry.

The servo task's permanent activity advances the ir-sim world by one period
(the base moves whether or not TrackSpeed runs) and integrates the speeds
the base measures into the odometry pose, which starts at zero.
"""
from . import base_device, odometry, world

#: RFLEX's codels in C reach the same simulated base through this device (docs/codels.md).
C_DEVICES = {"dala_base": base_device.make}
PERIOD = 0.025  # s, the servo task's period
STILL = {"v": 0.0, "w": 0.0}
_state = {"pose": {"x": 0.0, "y": 0.0, "theta": 0.0}, "applied": dict(STILL)}


def _publish(Odo, sim) -> None:
    Odo.value = {"position": dict(_state["pose"]), "velocity": sim.velocity(), "stamp": round(sim.t, 6)}


def rflexInitOdometry(Odo):
    sim = world.sim()
    _state.update(pose={"x": 0.0, "y": 0.0, "theta": 0.0}, applied=dict(STILL))
    sim.command = (0.0, 0.0)
    _publish(Odo, sim)
    return "odometry"


def rflexOdometry(Odo):
    sim = world.sim()
    sim.advance(PERIOD)
    measured = sim.velocity()
    _state["pose"] = odometry.integrate(_state["pose"], measured["v"], measured["w"], PERIOD)
    _publish(Odo, sim)
    return "pause::odometry"


def rflexClose():
    return "ether"


def rflexOpen(device, opened):
    opened.value = device
    return "ether"


def rflexStartTracking(mode):
    mode.value = "drive_tracking"
    return "track"


def limited(current: dict, wanted: dict, acceleration_max: float, dt: float) -> dict:
    """The speed one period closer to ``wanted``: speeding up by at most acceleration_max * dt; braking at once."""
    v, target = current["v"], wanted["v"]
    if abs(target) > abs(v) and target * v >= 0:
        step = acceleration_max * dt
        v += max(-step, min(step, target - v))
    else:
        v = target
    return {"v": v, "w": wanted["w"]}


def _apply(speed: dict) -> None:
    _state["applied"] = dict(speed)
    world.sim().command = (speed["v"], speed["w"])


def rflexTrack(Speed, acceleration_max, command):
    _apply(limited(_state["applied"], Speed or STILL, acceleration_max or 0.5, PERIOD))
    command.value = dict(_state["applied"])
    return "pause::track"


def rflexBrake(mode, command):
    mode.value = "drive_braking"
    _apply(STILL)
    command.value = dict(STILL)
    return "ether"


def rflexStop(command):
    _apply(STILL)
    command.value = dict(STILL)
    return "ether"
