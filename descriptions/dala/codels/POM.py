"""POM, simulated: the position estimate is the odometry, shifted to the origin given to Run."""
from runtime.genom import Throw

_offset = {"x": 0.0, "y": 0.0, "theta": 0.0}


def _estimate(odo):
    p = odo["position"]
    return {"estimate": {k: p[k] + _offset[k] for k in ("x", "y", "theta")}, "covariance": [0.01, 0.01, 0.005],
            "stamp": odo["stamp"]}


def pomInitTask(initialised):
    initialised.value = False
    return "update"


def pomUpdate(initialised, Odo, estimate, Pos):
    if initialised and Odo is not None:
        estimate.value = _estimate(Odo)
        Pos.value = estimate.value
    return "pause::update"


def pomEnd():
    return "ether"


def pomWaitOdometry(Odo):
    return "fix" if Odo is not None else "pause::start"


def pomFix(origin, Odo, estimate, initialised, Pos):
    if Odo is None:
        raise Throw("e_no_odometry")
    for k in _offset:
        _offset[k] = origin[k] - Odo["position"][k]
    estimate.value = _estimate(Odo)
    initialised.value = True
    Pos.value = estimate.value
    return "ether"


def pomReset(initialised):
    initialised.value = False
    return "ether"
