"""How long each codel runs: calls counted exactly, CPU and wall time taken in the codel's thread, a file written whole.

The codels here busy-loop on their own thread's CPU clock (``time.thread_time``), never sleep, so a codel is
known to take at least its loop's time whatever the machine's speed.
"""
from __future__ import annotations

import json
import os
from collections import Counter
import subprocess
import sys
import threading
import time

import pytest

from runkit import HELD, ROOT, TICK, build, tick_codels
from runtime.controller import Controller, VirtualClock
from runtime.controller.codel_times import merge, table, unwritable, write_json
from runtime.genom import Throw

BUSY = 0.02  # s of the codel thread's CPU time that tickSlow spins for


def spin(seconds: float) -> None:
    """Use ``seconds`` of this thread's CPU time (not wall time: a busy machine makes it last longer, not shorter)."""
    end = time.thread_time() + seconds
    while time.thread_time() < end:
        pass


def slow_or_throw(seconds: float) -> None:
    """tickSlow's work: spin for ``seconds`` of CPU time, throw e_slow for a negative time."""
    if seconds < 0:
        raise Throw("e_slow")
    spin(seconds)


def test_each_codel_is_counted_exactly_and_a_busy_one_takes_at_least_its_cpu_time(tmp_path):
    package, root, interface = build(tmp_path, TICK.replace("yield ether;\n    throw", "yield ether wcet 5 ms;\n"
                                                                                         "    throw"))
    clock, calls = VirtualClock(), []
    c = Controller(package, root, interface, tick_codels(clock, calls, slow_or_throw), clock=clock, times=True)
    c.start()
    try:
        requests = []
        for seconds in (BUSY, -1.0, BUSY):  # Slow takes one request at a time
            requests.append(c.wait(c.submit("tick", "Slow", {"seconds": seconds}).id, timeout=60))
    finally:
        c.stop(timeout=60)
    assert [r.status for r in requests] == ["ok", "failed", "ok"]
    got = c.codel_times()
    assert got["clock"] == "virtual" and got["runs"] == 1
    codels = got["codels"]
    assert set(codels) == {"tick.t.tickStart", "tick.t.tickCount", "tick.Slow.tickSlow"}
    counted = Counter(name for name, _ in calls)
    assert {name.rsplit(".", 1)[1]: c["calls"] for name, c in codels.items()} == counted
    assert counted["tickSlow"] == 3  # the call that threw is counted too
    slow = codels["tick.Slow.tickSlow"]
    assert slow["task"] == "tick.t" and slow["wcet"] == 5.0 and codels["tick.t.tickCount"]["wcet"] is None
    assert slow["cpu"]["max"] >= BUSY * 1e3
    assert slow["wall"]["max"] >= slow["cpu"]["max"] * 0.99  # a thread's CPU time never runs ahead of the wall clock
    assert slow["cpu"]["mean"] >= BUSY * 1e3 * 2 / 3  # two of the three calls spun
    for figures in (c["cpu"] for c in codels.values()):
        assert 0 <= figures["mean"] <= figures["max"] and figures["p99"] <= figures["max"]
    assert got["not_run"] == ["tick.Work.tickWork"]
    lines = table(got)
    assert lines[0].split()[:3] == ["codel", "task", "calls"]
    assert any(line.startswith("tick.Slow.tickSlow") and line.endswith("5.000 ms") for line in lines)
    assert "CPU time past the declared WCET: tick.Slow.tickSlow" in lines  # 20 ms of CPU against 5 declared
    assert lines[-1] == "not run: tick.Work.tickWork"


def test_nothing_is_timed_unless_asked(tmp_path):
    package, root, interface = build(tmp_path, TICK)
    c = Controller(package, root, interface, tick_codels(), clock=VirtualClock())
    assert c.run(duration=0.05) == "stopped"
    assert c.codel_times() is None and c.binder.times is None


def test_a_detached_codel_is_timed_once_over_its_whole_call_and_waiting_is_not_cpu_time(tmp_path):
    package, root, interface = build(tmp_path, HELD, "held")
    release = threading.Event()

    def heldTick(n):
        n.value += 1
        return "pause::start"

    def heldCheck(seen):
        release.wait(30)

    c = Controller(package, root, interface, {"held": {"heldTick": heldTick, "heldCheck": heldCheck}}, times=True)
    overrun = threading.Event()
    c.subscribe(lambda e: e["event"] == "codel_overrun" and overrun.set())
    c.start()
    try:
        req = c.submit("held", "Set", {"seen": 7})
        assert overrun.wait(30)  # past its 100 ms bound, reported (and detached once a period is due)
        release.set()
        assert c.wait(req.id, timeout=30).final["status"] == "ok"
    finally:
        release.set()
        c.stop(timeout=30)
    held = c.codel_times()["codels"]["held.Set.heldCheck"]
    assert c.codel_times()["clock"] == "real"
    assert held["calls"] == 1  # the step fired again with its outcome does not call, nor count, it twice
    assert held["wall"]["max"] >= 100.0  # it ran past its bound before it was released
    assert held["cpu"]["max"] < held["wall"]["max"] / 2  # waiting for an event takes no CPU time
    assert held["task"] is None  # a validate codel runs in the control task


def _run(calls: int, cpu: tuple[float, float, float], wall: float, clock: str = "virtual", not_run=()) -> dict:
    figures = dict(zip(("max", "p99", "mean"), cpu))
    return {"measured": "m", "clock": clock, "runs": 1, "not_run": list(not_run),
            "codels": {"M.T.c": {"task": "M.T", "calls": calls, "cpu": figures,
                                 "wall": {"max": wall, "p99": wall, "mean": wall}, "wcet": 2.0}}}


def test_runs_merge_calls_exactly_and_keep_the_longest():
    a = _run(10, (1.0, 0.5, 0.2), 3.0, not_run=["M.T.d", "M.T.e"])
    b = _run(30, (0.8, 0.7, 0.6), 9.0, clock="real", not_run=["M.T.d"])
    c = b["codels"]["M.T.c"]
    b["codels"] = {"M.T.a": {**c, "calls": 2}, "M.T.c": c, "M.T.e": {**c, "calls": 1}}
    got = merge([a, b])
    assert list(got["codels"]) == ["M.T.a", "M.T.c", "M.T.e"]  # the order of the runs, whichever ran first
    c = got["codels"]["M.T.c"]
    assert c["calls"] == 40 and c["cpu"]["max"] == 1.0 and c["cpu"]["p99"] == 0.7 and c["wall"]["max"] == 9.0
    assert c["cpu"]["mean"] == pytest.approx((10 * 0.2 + 30 * 0.6) / 40)
    assert got["runs"] == 2 and got["clock"] == "real, virtual"
    assert got["not_run"] == ["M.T.d"]  # e ran in the second run
    assert a["codels"]["M.T.c"]["calls"] == 10  # the runs given are left as they were


def test_the_file_is_written_whole_or_not_at_all(tmp_path):
    path = tmp_path / "deep" / "times.json"
    data = _run(1, (1.0, 1.0, 1.0), 1.0)
    write_json(path, data)
    assert json.loads(path.read_text()) == data
    with pytest.raises(TypeError):
        write_json(path, {"codels": object()})  # fails half way through
    assert json.loads(path.read_text()) == data  # the previous file, whole
    assert os.listdir(path.parent) == ["times.json"]  # no temporary file left beside it


def test_a_path_that_cannot_be_written_says_why(tmp_path):
    (tmp_path / "file").write_text("")
    assert unwritable(tmp_path) == "is a directory"
    assert unwritable(tmp_path / "file" / "times.json") == f"{tmp_path / 'file'} is not a directory"
    assert unwritable(tmp_path / "new" / "times.json") is None  # its folder is made when written
    (tmp_path / "gone").symlink_to(tmp_path / "missing")
    assert unwritable(tmp_path / "gone" / "times.json") == f"{tmp_path / 'gone'} is a broken link"


def _cli(command: list[str], cwd=ROOT):
    return subprocess.run([sys.executable, *command], cwd=cwd, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})


def test_mission_refuses_a_file_it_cannot_write_before_it_runs_and_writes_nothing(tmp_path):
    (tmp_path / "file").write_text("")
    out = tmp_path / "out"
    done = _cli(["-m", "genom2bip", "mission", "descriptions/dala/missions/corridor.yaml", "--out", str(out),
                 "--codel-times", str(tmp_path / "file" / "times.json")])
    assert done.returncode == 1, done.stdout + done.stderr
    assert f"--codel-times {tmp_path / 'file' / 'times.json'}: cannot write it: {tmp_path / 'file'} is not a " \
           "directory" in done.stderr
    assert done.stdout == "" and not out.exists()


def test_the_generated_run_writes_the_times_when_it_ends_and_refuses_a_directory(tmp_path):
    target = tmp_path / "times.json"
    done = _cli(["-m", "dala", "run", "--codels", str(ROOT / "tests/fixtures/dala_codels"), "--duration", "0.5",
                 "--quiet", "--codel-times", str(target)], cwd=ROOT / "gen")
    assert done.returncode == 0, done.stderr
    data = json.loads(target.read_text())
    assert data["clock"] == "real" and data["codels"]["RFLEX.servo.rflexInitOdometry"]["calls"] == 1
    assert data["codels"]["RFLEX.servo.rflexInitOdometry"]["task"] == "RFLEX.servo"
    assert "codel times (cpu: the codel thread's CPU time, wall: wall time):" in done.stdout
    assert f"wrote {target}" in done.stdout
    refused = _cli(["-m", "dala", "run", "--duration", "0.1", "--codel-times", str(tmp_path)], cwd=ROOT / "gen")
    assert refused.returncode == 1
    assert f"--codel-times {tmp_path}: cannot write it: is a directory" in refused.stderr
    assert "services interface on" not in refused.stdout  # refused before the controller started


@pytest.mark.parametrize("args, message", [
    (["--runs", "0"], "argument --runs: expected an integer above 0, got '0'"),
    (["--margin", "-1"], "argument --margin: expected a number above 0, got '-1'"),
    (["--margin", "inf"], "argument --margin: expected a number above 0, got 'inf'"),
    (["--from", "missing.json"], "--from missing.json: no such file"),
    (["no/such/mission.yaml"], "no/such/mission.yaml: no such mission file"),
    (["--lower"], "--lower goes with --write"),
])
def test_the_measuring_script_names_a_bad_option_before_it_runs_anything(args, message):
    before = {p: p.read_text() for p in (ROOT / "descriptions" / "dala").glob("*.gen")}
    done = _cli([str(ROOT / "bench" / "codel_times.py"), *args])
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.splitlines()[-1] == f"codel_times.py: error: {message}"
    assert {p: p.read_text() for p in before} == before
