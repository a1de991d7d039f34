"""LaserRF, simulated: a 180 degree sweep cast into the simulated room."""
import math

from runtime.genom import Throw

from . import world

_config = {"max_range": 8.0, "beams": 37}


def lrfInitTask(acquiring):
    acquiring.value = False
    return "ether"


def lrfCheckConfig(max_range, beams):
    if max_range <= 0 or beams < 2:
        raise Throw("e_bad_config")


def lrfOpen(local_device, ids_device):
    if not local_device:
        raise Throw("e_device", what="no device name")
    ids_device.value = local_device
    return "configure"


def lrfConfigure(max_range, beams):
    _config.update(max_range=max_range or 8.0, beams=min(beams or 37, 361))
    return "ether"


def lrfStartAcquisition(acquiring):
    acquiring.value = True
    return "acquire"


def lrfAcquire(Scan):
    n, top = _config["beams"], _config["max_range"]
    step = math.pi / (n - 1)
    seq = Scan.value["seq"] + 1 if Scan.value else 0
    Scan.value = {"angle_min": -math.pi / 2, "angle_step": step, "range_max": top,
                  "ranges": [round(world.ray(-math.pi / 2 + i * step, top), 3) for i in range(n)], "seq": seq}
    return "pause::acquire"


def lrfStopAcquisition(acquiring):
    acquiring.value = False
    return "ether"
