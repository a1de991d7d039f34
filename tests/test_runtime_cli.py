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
from genom2bip.call_cli import parse_assignments
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
    assert lines[0].startswith("dala controller: 5 components, 18 services; codels: ")
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
    assert re.search(r"stopped after \d+ steps; requests: .*\d+ ok.*\d+ rejected", out), out
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
    assert interface["codels"] == "descriptions/dala/codels"
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
