"""LaserRF: reads the simulated 2D lidar into poster Scan, with the configured range and number of beams."""
from runtime.genom import Throw

from . import world

_config = {"max_range": 8.0, "beams": 361}


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
    _config.update(max_range=max_range or 8.0, beams=min(beams or 361, 361))
    return "ether"


def lrfStartAcquisition(acquiring):
    acquiring.value = True
    return "acquire"


def sweep(raw: dict, beams: int, max_range: float) -> dict:
    """At most ``beams`` evenly spread beams of the lidar's sweep, clipped to ``max_range``."""
    ranges = raw["ranges"]
    every = max(1, -(-len(ranges) // beams))
    top = min(max_range, raw["range_max"])
    return {"angle_min": raw["angle_min"], "angle_step": raw["angle_step"] * every, "range_max": top,
            "ranges": [round(min(r, top), 3) for r in ranges[::every]]}


def lrfAcquire(Scan):
    seq = Scan.value["seq"] + 1 if Scan.value else 0
    sim = world.sim()
    Scan.value = {**sweep(sim.scan(), _config["beams"], _config["max_range"]), "seq": seq, "stamp": round(sim.t, 6)}
    return "pause::acquire"


def lrfStopAcquisition(acquiring):
    acquiring.value = False
    return "ether"
