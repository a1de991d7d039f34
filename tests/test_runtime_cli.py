"""``python -m dala run`` in its own process, ``genom2bip call`` against it, Ctrl-C; the generated interface data."""
from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time

import pytest

from genom2bip.back.interface import codel_params
from genom2bip.cli.call import parse_assignments
from genom2bip.cli import main as genom2bip_main
from genom2bip.ir import Codel, CodelParam
from runkit import DALA_CODELS, ROOT, dala
from runtime.controller.schema import problems


@pytest.fixture(scope="module")
def running():
    """``python -m dala run --codels tests/fixtures/dala_codels`` on a free port: (process, url)."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-m", "dala", "run", "--codels", str(DALA_CODELS)], cwd=ROOT / "gen",
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    lines = []
    url = None
    deadline = time.monotonic() + 30
    while url is None and time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        lines.append(line)
        found = re.search(r"services interface on (http://127\.0\.0\.1:\d+)/", line)
        url = found.group(1) if found else None
    if url is None:
        proc.kill()
        pytest.fail(f"no URL printed: {''.join(lines)}{proc.stderr.read()}")
    yield proc, url, lines
    if proc.poll() is None:
        proc.kill()
        proc.wait(10)


def test_run_prints_what_it_runs_and_where_it_listens(running):
    proc, url, lines = running
    assert lines[0].startswith("dala controller: 6 components, 22 services; codels: ")
    assert str(DALA_CODELS) in lines[0]


def test_call_sends_a_request_and_prints_its_final_report(running, capsys):
    _, url, _ = running
    assert genom2bip_main(["call", url, "NDD.SetSpeed", "max_speed.v=0.25", "--wait", "--timeout", "10"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["status"] == "ok" and report["service"] == "SetSpeed"
    assert genom2bip_main(["call", url, "NDD.SetSpeed", "max_speed.v=-1", "--wait"]) == 1
    assert json.loads(capsys.readouterr().out)["exception"] == "NDD::e_bad_params"
    assert genom2bip_main(["call", url, "NDD.SetParams"]) == 0
    queued = json.loads(capsys.readouterr().out)
    assert queued["status"] == "queued" and queued["url"] == f"{url}/requests/{queued['id']}"


def test_call_exits_by_the_table_failed_4_and_no_final_report_yet_5(capsys):
    from runkit import navigation_ready, ndd_settings, serving_dala

    with serving_dala() as (_, server, client):  # a controller of its own: this test leaves it navigating
        url = server.url
        navigation_ready(client)
        ndd_settings(client)
        # the stub nddPlan throws e_blocked for a goal at x = 13: the request failed, what the run found
        goal = ["goal.x=13", "goal.y=0", "goal.theta=0"]
        assert genom2bip_main(["call", url, "NDD.GoTo", *goal, "--wait", "--timeout", "60"]) == 4
        assert json.loads(capsys.readouterr().out)["exception"] == "NDD::e_blocked"
        # a goal at x = 1000 is never reached (the stub): no final report within the time given, no answer yet
        assert genom2bip_main(["call", url, "NDD.GoTo", "goal.x=1000", *goal[1:], "--wait", "--timeout", "0.5"]) == 5
        assert "has no final report after 0.5 s" in capsys.readouterr().err


def test_call_reports_bad_requests_and_unreachable_servers(running, capsys):
    _, url, _ = running
    assert genom2bip_main(["call", url, "NDD.SetSpeed", "max_speed.v=fast"]) == 1
    assert "max_speed.v: expected a number, got 'fast'" in capsys.readouterr().err
    assert genom2bip_main(["call", url, "NDD.Teleport"]) == 1
    assert "component NDD has no service 'Teleport'" in capsys.readouterr().err
    assert genom2bip_main(["call", url, "GoTo"]) == 2
    assert "Component.Service expected" in capsys.readouterr().err
    assert genom2bip_main(["call", url, "NDD.GoTo", "goal"]) == 2
    assert "key=value expected" in capsys.readouterr().err
    assert genom2bip_main(["call", "http://127.0.0.1:9", "NDD.Stop"]) == 1
    assert "cannot reach http://127.0.0.1:9" in capsys.readouterr().err


def test_call_without_a_service_lists_them(running, capsys):
    _, url, _ = running
    assert genom2bip_main(["call", url]) == 0
    out = capsys.readouterr().out
    assert "  NDD.GoTo (activity) goal" in out
    assert '  NDD.SetSpeed (attribute) max_speed={"v": 0.3, "w": 0.5}' in out


def test_ctrl_c_stops_the_controller_and_the_server_cleanly(running):
    proc, url, _ = running
    from runtime.services.client import Client

    client = Client(url)
    rid = client.send("NDD", "GoTo", goal={"x": 1.0, "y": 0.0, "theta": 0.0})  # refused by a rule: a report
    assert client.wait(rid, timeout=10)["status"] == "rejected"
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=20)
    assert proc.returncode == 0, err
    assert re.search(r"stopped after \d+ steps; requests: (.*, )?\d+ rejected", out), out  # earlier tests share it
    assert "Traceback" not in err


def test_run_without_codels_says_so(tmp_path):
    result = subprocess.run([sys.executable, "-m", "dala", "run", "--codels", str(tmp_path / "nowhere/x"),
                             "--duration", "0.1"], cwd=ROOT / "gen", capture_output=True, text=True, timeout=60)
    assert result.returncode == 1 and "--codels" in result.stderr and "no such directory" in result.stderr


def test_run_for_a_duration_ends_by_itself(tmp_path):
    result = subprocess.run([sys.executable, "-m", "dala", "run", "--codels", str(DALA_CODELS), "--duration", "0.5",
                             "--quiet"], cwd=ROOT / "gen", capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert re.search(r"stopped after \d+ steps; requests: none", result.stdout)
    assert "1 codel(s) missing, their services will fail: POM.pomReset" in result.stderr


# --------------------------------------------------------------------------- pieces


def test_key_value_arguments_build_json_inputs():
    assert parse_assignments(["goal.x=1", "goal.y=2.5", "name=/dev/ttyS0", "on=true", 'o={"a": 1}', "o.b=2"]) == {
        "goal": {"x": 1, "y": 2.5}, "name": "/dev/ttyS0", "on": True, "o": {"a": 1, "b": 2}}
    with pytest.raises(ValueError):
        parse_assignments(["a=1", "a.b=2"])


def test_codel_arguments_are_named_after_their_variables_and_clashes_are_prefixed():
    codel = Codel("nddStartGoTo", params=[CodelParam("goal", "in", "local"), CodelParam("goal", "out", "ids"),
                                          CodelParam("pos.x", "in", "ids"), CodelParam("lambda", "in", None),
                                          CodelParam("a", "in", "ids", alias="b")])
    args = codel_params(codel, {"goal"}, set(), validate=False)
    assert [(a["arg"], a["source"], a["path"]) for a in args] == [
        ("local_goal", "local", "goal"), ("ids_goal", "ids", "goal"), ("x", "ids", "pos.x"),
        ("lambda_", "ids", "lambda"), ("b", "ids", "a")]
    validate = Codel("check", params=[CodelParam("speed", "in", "ids")])
    assert codel_params(validate, set(), {"speed"}, validate=True)[0]["source"] == "local"


def test_generated_interface_describes_dala():
    interface = dala().INTERFACE
    assert interface["codels"] == "../../descriptions/dala/codels"  # relative to the package
    ndd = interface["components"]["NDD"]
    assert ndd["ports"]["Speed"] == {"direction": "out", "schema": {"$ref": "dala::twist"}, "multiple": False}
    assert ndd["tasks"]["motion"]["period_us"] == 100_000 and ndd["tasks"]["motion"]["instance"] == "NDD.motion"
    assert ndd["ids"]["max_speed"]["initial"] == {"v": 0.0, "w": 0.0}
    setspeed = ndd["services"]["SetSpeed"]
    assert setspeed["parameters"][0] | {"schema": None} == {
        "name": "max_speed", "direction": "in", "schema": None, "source": "ids", "member": "max_speed",
        "default": {"v": 0.3, "w": 0.5}, "doc": "Maximal speeds"}
    assert setspeed["codels"]["NDD_nddCheckSpeed"]["role"] == "validate"
    assert interface["types"]["dala::drive_mode"]["enum"] == ["drive_idle", "drive_tracking", "drive_braking"]
    scan = interface["types"]["dala::scan"]["properties"]
    assert scan["ranges"] == {"type": "array", "items": {"type": "number"}, "maxItems": 361}
    assert scan["seq"] == {"type": "integer", "minimum": 0, "maximum": 2 ** 32 - 1}
    types = interface["types"]
    assert problems({"estimate": {"x": 0, "y": 0, "theta": 0}, "covariance": [0, 0], "stamp": 1},
                    {"$ref": "dala::position"}, types, "Pos") == ["Pos.covariance: at least 3 items expected, got 2"]
    assert problems("drive_fast", {"$ref": "dala::drive_mode"}, types, "mode") == [
        "mode: 'drive_fast' is not one of drive_idle, drive_tracking, drive_braking"]
    assert problems(True, {"type": "number"}, types, "v") == ["v: expected a number, got True"]


# --------------------------------------------------------------------------- stopping: reports, stuck codels, Ctrl-C

#: Codels of runkit.TICK for ``run``: tickWork's ``add`` says how it misbehaves (2: loops, 3: sleeps, 4: SystemExit).
TICK_CODELS = '''
import time


def tickStart(n):
    n.value = 0
    return "count"


def tickCount(n, Count):
    n.value += 1
    Count.value = n.value
    return "pause::count"


def tickSlow(seconds):
    return "ether"


def tickWork(add, n, total):
    if add == 2:
        while True:
            pass
    if add == 3:
        time.sleep(1000)
    if add == 4:
        raise SystemExit(4)
    n.value += add
    total.value = n.value
    return "ether"
'''


@pytest.fixture(scope="module")
def tick_package(tmp_path_factory):
    """runkit.TICK generated as a package, and a codels directory for it: (directory of the package, codels)."""
    from runkit import TICK

    where = tmp_path_factory.mktemp("tick")
    (where / "tick.gen").write_text(TICK)
    assert genom2bip_main([str(where / "tick.gen"), "-o", str(where / "gen")]) == 0
    (where / "codels").mkdir()
    (where / "codels" / "tick.py").write_text(TICK_CODELS)
    return where / "gen", where / "codels"


def start(cwd, package, *args):
    """``python -m package run ARGS`` in its own process: (process, url), once the URL is printed."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-m", package, "run", *map(str, args)], cwd=cwd,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        found = re.search(r"services interface on (http://127\.0\.0\.1:\d+)/", line)
        if found:
            return proc, found.group(1)
        if not line:
            break
    proc.kill()
    pytest.fail(f"no URL printed: {proc.communicate()}")


@pytest.fixture
def launch():
    """:func:`start`, and every process it started killed after the test if still running (a failed test)."""
    procs = []

    def run(cwd, package, *args):
        proc, url = start(cwd, package, *args)
        procs.append(proc)
        return proc, url

    yield run
    for proc in procs:
        if proc.poll() is None:
            proc.kill()
            proc.communicate(timeout=10)


def stopped(proc, signals=1, between=0.5, timeout=120):
    """Send Ctrl-C ``signals`` times: (stdout, stderr) once the process has ended.

    ``timeout`` fails the test: far above what a loaded machine takes, far below the codels that never return.
    """
    for k in range(signals):
        if k:
            time.sleep(between)
        proc.send_signal(signal.SIGINT)
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
        pytest.fail(f"still running {timeout} s after Ctrl-C: {out}{err}")
    return out, err


def running_work(url, add):
    from runtime.services.client import Client
    from runkit import until

    client = Client(url, timeout=10)
    rid = client.send("tick", "Work", add=add)
    until(lambda: client.request(rid)["status"] == "running")
    return client, rid


def test_a_codel_raising_system_exit_fails_its_request_and_the_controller_runs_on(launch, tick_package):
    gen, codels = tick_package
    proc, url = launch(gen, "tick", "--codels", codels)
    from runtime.services.client import Client

    client = Client(url, timeout=10)
    report = client.call("tick", "Work", add=4, timeout=10)
    assert report["status"] == "failed" and report["message"] == "codel tickWork raised SystemExit: 4"
    assert client.info()["status"] == "running"
    assert client.call("tick", "Work", add=1, timeout=10)["status"] == "ok"
    out, err = stopped(proc)
    assert proc.returncode == 0 and "Traceback" not in err, err


@pytest.mark.parametrize("add, line, status", [
    (2, "[{rid}] tick.Work: interrupted tick.Work: the controller stopped; codel tickWork did not return after the "
        "controller was told to stop: interrupted", 0),  # a Python loop: interrupted
    (3, "[{rid}] tick.Work: interrupted tick.Work: the controller stopped (codel tickWork of tick.Work (request "
        "{rid}) did not return within 3 s of the stop: abandoned)", 4),  # blocked in time.sleep: given up on
], ids=["loop", "blocked"])
def test_ctrl_c_stops_within_a_bounded_time_whatever_the_codel_under_way_does(launch, tick_package, add, line,
                                                                         status):
    gen, codels = tick_package
    proc, url = launch(gen, "tick", "--codels", codels)
    client, rid = running_work(url, add)
    out, err = stopped(proc)  # within stopped()'s bound: the codel never returns by itself
    assert line.format(rid=rid) in out, out
    assert re.search(r"stopped after \d+ steps; requests: 1 interrupted", out), out
    assert proc.returncode == status and "Traceback" not in err, err


def test_a_second_ctrl_c_exits_at_once_saying_what_it_interrupted(launch, tick_package):
    gen, codels = tick_package
    proc, url = launch(gen, "tick", "--codels", codels)
    client, rid = running_work(url, 3)
    queued = client.send("tick", "Work", add=1)
    out, err = stopped(proc, signals=2, between=0.3)
    assert proc.returncode == 130  # the exit at once: the stop would wait 3 s for the codel, then exit 4
    assert f"second Ctrl-C: exiting at once; interrupted: codel tickWork of tick.Work (request {rid}); " \
           f"2 request(s) left without a final report: {rid}, {queued}" in err, err
    assert "Traceback" not in err


def test_every_accepted_request_gets_one_final_report_on_every_channel_when_stopped(launch):
    import threading
    from collections import Counter

    from runkit import navigation_ready, ndd_settings, until
    from runtime.services.client import Client

    proc, url = launch(ROOT / "gen", "dala", "--codels", DALA_CODELS)
    client = Client(url, timeout=10)
    finals: Counter = Counter()
    streaming = threading.Event()

    def listen():
        for event in client.events(types="report,controller", timeout=30):
            streaming.set()
            if event["event"] == "report" and event["final"]:
                finals[event["request"]] += 1

    reader = threading.Thread(target=listen, daemon=True)
    reader.start()
    navigation_ready(client)
    ndd_settings(client)
    goto = client.send("NDD", "GoTo", goal={"x": 1000.0, "y": 0.0, "theta": 0.0})
    until(lambda: client.request(goto)["status"] == "running")
    polled = {}

    def long_poll():
        polled.update(Client(url, timeout=10).request(goto, wait=60))

    poller = threading.Thread(target=long_poll, daemon=True)
    poller.start()
    time.sleep(0.3)
    accepted = [r["id"] for r in client.requests(limit=1000)]
    out, err = stopped(proc)
    poller.join(10)
    reader.join(10)
    assert proc.returncode == 0 and "Traceback" not in err, err
    assert polled["final"]["status"] == "interrupted", polled
    assert polled["final"]["message"] == "NDD.GoTo: the controller stopped"
    assert set(finals) == set(accepted) and set(finals.values()) == {1}, (finals, accepted)
    console = Counter(int(m) for m in re.findall(r"^\[(\d+)\] ", out, re.M))
    assert set(console) == set(accepted) and set(console.values()) == {1}
    assert f"[{goto}] NDD.GoTo: interrupted NDD.GoTo: the controller stopped" in out


def test_an_event_stream_client_that_stopped_reading_does_not_hold_the_stop(launch):
    import socket

    from runkit import until
    from runtime.services.client import Client

    proc, url = launch(ROOT / "gen", "dala", "--codels", DALA_CODELS)
    port = int(url.rsplit(":", 1)[1])
    client = Client(url, timeout=10)
    client.call("LaserRF", "Init", timeout=10)
    client.send("LaserRF", "Start")  # a 361-range scan on the stream every period
    stalled = socket.socket()
    stalled.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    stalled.connect(("127.0.0.1", port))
    stalled.sendall(b"GET /events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")  # and never reads
    until(lambda: client.poster("LaserRF", "Scan")["seq"] > 20, timeout=20)
    out, err = stopped(proc)
    stalled.close()
    assert proc.returncode == 0, err
    # held, the stop would wait for the server's graceful-shutdown timeout (3 s) and say so
    assert "Traceback" not in err and "CancelledError" not in err and "graceful shutdown exceeded" not in err, err
