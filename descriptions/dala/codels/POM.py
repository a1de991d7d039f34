"""POM: fuses RFLEX's odometry into the position estimate Pos, in the world frame that Run anchors."""
from runtime.genom import Throw

from . import odometry

ZERO = {"x": 0.0, "y": 0.0, "theta": 0.0}
_state = {"anchor": dict(ZERO), "last": None}  # world pose of the odometry frame; last odometry pose used


def fused(anchor: dict, odo: dict, previous: dict | None, covariance: list[float]) -> dict:
    """The position for one odometry sample: its pose in the world frame, the covariance grown by the motion."""
    pose = odo["position"]
    if previous is not None:
        step = odometry.between(previous, pose)
        covariance = odometry.grow(covariance, (step["x"] ** 2 + step["y"] ** 2) ** 0.5, step["theta"])
    return {"estimate": odometry.compose(anchor, pose), "covariance": list(covariance), "stamp": odo["stamp"]}


def pomInitTask(initialised):
    initialised.value = False
    return "update"


def pomUpdate(initialised, Odo, estimate, Pos):
    if initialised and Odo is not None:
        estimate.value = fused(_state["anchor"], Odo, _state["last"], estimate.value["covariance"])
        _state["last"] = Odo["position"]
        Pos.value = estimate.value
    return "pause::update"


def pomEnd():
    return "ether"


def pomWaitOdometry(Odo):
    return "fix" if Odo is not None else "pause::start"


def pomFix(origin, Odo, estimate, initialised, Pos):
    """The odometry frame is anchored so that the robot's current odometry pose is ``origin`` in the world."""
    if Odo is None:
        raise Throw("e_no_odometry")
    _state["anchor"] = odometry.compose(origin, odometry.between(Odo["position"], ZERO))
    _state["last"] = Odo["position"]
    estimate.value = fused(_state["anchor"], Odo, None, [0.0, 0.0, 0.0])
    initialised.value = True
    Pos.value = estimate.value
    return "ether"


def pomReset(initialised):
    initialised.value = False
    return "ether"
