"""Codels that misbehave: one that never returns, one that exits the process, one that fails for good, a slow start."""
from __future__ import annotations

import re
import signal
import sys

from controlproc import ROOT, ControllerProcess
from probes import EventLog, codels_with, tasks

#: lrfAcquire blocks for ever once Init has configured 7 beams (a driver waiting on a device that died).
STUCK_ACQUIRE = '''
import threading as _threading
_acquire = lrfAcquire

def lrfAcquire(Scan):
    if _config["beams"] == 7:
        _threading.Event().wait()
    return _acquire(Scan)
'''

#: lrfConfigure calls os._exit(3) when asked for a range of 13 m.
EXITING_CONFIGURE = '''
import os as _os
_configure = lrfConfigure

def lrfConfigure(max_range, beams):
    if max_range == 13:
        _os._exit(3)
    return _configure(max_range, beams)
'''

#: rflexOdometry fails for good once Init opened the device "/dev/broken".
BROKEN_ODOMETRY = '''
_broken = {"on": False}
_open, _odometry = rflexOpen, rflexOdometry

def rflexOpen(device, opened):
    _broken["on"] = device == "/dev/broken"
    return _open(device, opened)

def rflexOdometry(Odo):
    if _broken["on"]:
        raise RuntimeError("encoder lost")
    return _odometry(Odo)
'''

#: The servo task's first codel takes 2 s (a slow driver to open, the world to load).
SLOW_START = '''
import time as _time
_init = rflexInitOdometry

def rflexInitOdometry(Odo):
    _time.sleep(2.0)
    return _init(Odo)
'''


def declared_wcet_ms(component: str, service: str, codel: str) -> float:
    """The WCET (ms) the generated DALA interface gives ``codel`` of ``service``."""
    sys.path.insert(0, str(ROOT / "gen"))
    try:
        from dala.interface import INTERFACE
    finally:
        sys.path.remove(str(ROOT / "gen"))
    return INTERFACE["components"][component]["services"][service]["codels"][f"{component}_{codel}"]["wcet_us"] / 1e3


def test_a_codel_that_never_returns_is_reported_and_holds_neither_the_other_tasks_nor_stop_nor_the_exit(tmp_path):
    with ControllerProcess(codels=codels_with(tmp_path, LaserRF=STUCK_ACQUIRE)) as ctl:
        ctl.wait_ready()
        client = ctl.client()
        log = EventLog(ctl.url)
        assert client.call("LaserRF", "SetConfig", beams=7, timeout=30)["status"] == "ok"
        assert client.call("LaserRF", "Init", timeout=30)["status"] == "ok"  # configures the driver
        start = client.send("LaserRF", "Start")
        stuck = log.wait(lambda e: e["event"] == "codel_overrun" and e["codel"] == "lrfAcquire")
        assert (stuck["codel"], stuck["task"], stuck["service"], stuck["request"]) == \
            ("lrfAcquire", "LaserRF.acquisition", "LaserRF.Start", start), stuck
        wcet = declared_wcet_ms("LaserRF", "Start", "lrfAcquire")  # its bound, the WCET descriptions/dala declares
        assert stuck["bound_ms"] == wcet and stuck["running_ms"] >= wcet, stuck
        assert stuck["message"].startswith("codel lrfAcquire of LaserRF.Start (request ") and \
            f"past its bound of {wcet:g} ms (its declared WCET)" in stuck["message"]
        # the other tasks keep their periods; the stuck task runs none
        before = tasks(client)
        assert ctl.wait_for(lambda: tasks(client)["RFLEX.servo"]["periods"] >= before["RFLEX.servo"]["periods"] + 40)
        assert tasks(client)["LaserRF.acquisition"]["periods"] == before["LaserRF.acquisition"]["periods"]
        assert client.info()["status"] == "running"
        # Stop interrupts Start: the codel is given up on, Start fails naming it, Stop is done
        assert client.call("LaserRF", "Stop", timeout=30)["status"] == "ok"
        final = client.wait(start, timeout=30)
        assert final["status"] == "failed" and final["codel"] == "lrfAcquire", final
        assert re.match(r"codel lrfAcquire did not return after \d+\.\d s: abandoned so that LaserRF\.Stop can run",
                        final["message"]), final["message"]
        assert ctl.wait_for(lambda: tasks(client)["LaserRF.acquisition"]["periods"] >
                            before["LaserRF.acquisition"]["periods"])
        end = ctl.stop(signal.SIGINT)
    assert end.status == 0 and "Traceback" not in end.err, end.err[-2000:]
    # said on stdout: as it came, or counted in that second's summary and named in the lines at the stop
    assert "codel lrfAcquire of LaserRF.Start" in end.out, end.out
    assert re.search(r"^still running, abandoned: codel lrfAcquire of LaserRF\.Start \(request \d+\), for "
                     r"\d+\.\d s$", end.out, re.M), end.out[-1500:]


def test_a_codel_that_exits_the_process_leaves_a_word_saying_what_ran_and_what_was_left(tmp_path):
    with ControllerProcess(codels=codels_with(tmp_path, LaserRF=EXITING_CONFIGURE)) as ctl:
        ctl.wait_ready()
        client = ctl.client()
        assert client.call("LaserRF", "SetConfig", max_range=13, timeout=30)["status"] == "ok"
        init = client.send("LaserRF", "Init")
        ctl.proc.wait(60)
        ctl.wait_for(lambda: "os._exit" in "".join(ctl.err), timeout=10)
        err = "".join(ctl.err)
    assert ctl.proc.returncode == 3
    assert f"codel lrfConfigure of LaserRF.Init (request {init}) called os._exit(3): the controller exits now" \
        in err, err
    assert re.search(rf"1 request\(s\) left without a final report: {init}\b", err), err
    assert re.search(r"after \d+ steps; requests: 1 ok, 1 running", err), err


def test_a_codel_that_fails_for_good_leaves_its_poster_visibly_stale(tmp_path):
    with ControllerProcess(codels=codels_with(tmp_path, RFLEX=BROKEN_ODOMETRY)) as ctl:
        ctl.wait_ready()
        client = ctl.client()
        log = EventLog(ctl.url)
        assert client.call("RFLEX", "Init", device="/dev/broken", timeout=30)["status"] == "ok"
        error = log.wait(lambda e: e["event"] == "codel_error" and e.get("codel") == "rflexOdometry")
        assert error["task"] == "RFLEX.servo" and error["posters"] == ["RFLEX.Odo"], error
        assert error["message"] == "codel rflexOdometry raised RuntimeError: encoder lost"
        first = client.poster("RFLEX", "Odo")
        servo = tasks(client)["RFLEX.servo"]["periods"]
        assert ctl.wait_for(lambda: tasks(client)["RFLEX.servo"]["periods"] >= servo + 20)
        later = client.poster("RFLEX", "Odo")
        assert later["seq"] == first["seq"]  # no longer written
        assert later["age_ms"] >= first["age_ms"] + 20 * 25 * 0.9, (first, later)
        assert later["failure"]["codel"] == "rflexOdometry" and later["failure"]["task"] == "RFLEX.servo"
        assert later["failure"]["message"] == "codel rflexOdometry raised RuntimeError: encoder lost"
        end = ctl.stop()
    assert end.status == 0, end.err


def test_the_startup_is_not_counted_as_missed_periods(tmp_path):
    with ControllerProcess(codels=codels_with(tmp_path, RFLEX=SLOW_START)) as ctl:
        ctl.wait_ready()
        client = ctl.client()
        info = client.info()
        servo = tasks(client)["RFLEX.servo"]
        end = ctl.stop()
    # 2 s are 80 periods of 25 ms: counted as missed before; now the periods start when the level is ready
    assert servo["missed"] < 40 and servo["overruns"] < 40, servo
    assert info["startup_ms"] >= 2000, info
    assert end.status == 0, end.err
