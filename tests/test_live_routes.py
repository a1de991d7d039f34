"""What the live page asks of the server, without a browser: its files, the pictures, the scene, service events, the
guard in front of them (docs/live.md)."""
from __future__ import annotations

import http.client
import json

import pytest

from runkit import navigation_ready, ndd_settings, serving_dala, until


@pytest.fixture(scope="module")
def ctl():
    with serving_dala() as running:
        yield running


def get(server, path: str, headers: dict[str, str] | None = None) -> tuple[int, dict[str, str], bytes]:
    conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=60)
    conn.request("GET", path, headers=headers or {})
    response = conn.getresponse()
    body = response.read()
    conn.close()
    return response.status, {k.lower(): v for k, v in response.getheaders()}, body


def test_the_page_and_its_scripts_are_served_with_a_policy_that_keeps_other_sites_out(ctl):
    _, server, _ = ctl
    status, headers, body = get(server, "/live/")
    assert status == 200 and headers["content-type"].startswith("text/html")
    assert b'<script src="/live/live.js"' in body
    policy = headers["content-security-policy"]
    assert "script-src 'self'" in policy and "frame-ancestors 'none'" in policy and "connect-src 'self'" in policy
    assert headers["x-content-type-options"] == "nosniff"
    for name, kind in (("live.js", "text/javascript"), ("live.css", "text/css")):
        status, headers, body = get(server, f"/live/{name}")
        assert status == 200 and headers["content-type"].startswith(kind) and body


def test_an_unknown_page_file_is_a_404_naming_the_files(ctl):
    _, server, _ = ctl
    status, _, body = get(server, "/live/secrets.txt")
    assert status == 404
    assert json.loads(body)["error"] == "no file 'secrets.txt' in the live page (files: live.js, live.css)"
    assert get(server, "/live/../components")[0] == 404  # no way out of the page's folder


def test_a_browser_opening_the_root_is_sent_to_the_page_and_any_other_client_gets_json(ctl):
    _, server, _ = ctl
    status, headers, _ = get(server, "/", {"Accept": "text/html,application/xhtml+xml,*/*;q=0.8"})
    assert status == 303 and headers["location"] == "/live/"
    for accept in (None, "*/*", "application/json", "application/json, text/html"):
        status, headers, body = get(server, "/", {"Accept": accept} if accept else {})
        assert status == 200 and headers["content-type"] == "application/json"
        assert json.loads(body)["links"]["page"] == "/live/"


def test_the_level_picture_is_the_graph_verbs_with_every_module(ctl):
    _, server, _ = ctl
    status, headers, body = get(server, "/pictures/level.svg")
    assert status == 200 and headers["content-type"].startswith("image/svg+xml")
    text = body.decode()
    assert text.lstrip().startswith("<?xml") and "<svg" in text
    for module in ("LaserRF", "Aspect", "NDD", "RFLEX", "POM", "Planner"):
        assert f"<title>{module}</title>" in text
    for service in ("GoTo", "TrackSpeed", "SetParams"):
        assert f">{service}</text>" in text  # one line of text per service: the page colours it


def test_a_modules_picture_has_its_services_atoms_and_an_unknown_module_is_a_404(ctl):
    _, server, _ = ctl
    status, _, body = get(server, "/pictures/modules/NDD.svg")
    assert status == 200
    assert "<title>NDD.GoTo.control</title>" in body.decode() and "<title>NDD.GoTo.activity</title>" in body.decode()
    status, _, body = get(server, "/pictures/modules/XYZ.svg")
    assert status == 404
    assert json.loads(body)["error"] == "no module 'XYZ' (modules: Aspect, LaserRF, NDD, POM, Planner, RFLEX)"


def test_without_a_mission_there_is_no_scene(ctl):
    _, server, _ = ctl
    status, _, body = get(server, "/scene")
    assert status == 404 and "not running a mission (genom2bip mission --view)" in json.loads(body)["error"]


def test_a_service_streams_its_states_validating_running_then_idle_with_its_outcome(ctl):
    controller, _, client = ctl
    events: list[dict] = []
    unsubscribe = controller.subscribe(lambda e: events.append(e) if e["event"] in ("service", "report") else None)
    try:
        navigation_ready(client)
        ndd_settings(client)
        goto = client.send("NDD", "GoTo", goal={"x": 1000.0, "y": 0.0, "theta": 0.0})
        until(lambda: client.request(goto)["status"] == "running")
        stop = client.call("NDD", "Stop", timeout=10)["request"]
        client.wait(goto, timeout=10)
    finally:
        unsubscribe()
    mine = [(e["event"], e.get("state") or e.get("status"), e.get("outcome")) for e in events if e["request"] == goto]
    assert mine == [("report", "queued", None), ("service", "validating", None), ("report", "started", None),
                    ("service", "running", None), ("report", "interrupted", None),
                    ("service", "idle", "interrupted")]
    assert [e for e in events if e["event"] == "service" and e["request"] == goto][0]["service"] == "NDD.GoTo"
    assert ("service", "idle", "ok") in [(e["event"], e.get("state"), e.get("outcome"))
                                         for e in events if e["request"] == stop]


def test_a_request_refused_by_a_rule_leaves_its_service_idle_without_validating():
    with serving_dala() as (controller, _, client):  # fresh: nothing a GoTo needs has run
        events: list[dict] = []
        controller.subscribe(lambda e: events.append(e) if e["event"] == "service" else None)
        rid = client.send("NDD", "GoTo", goal={"x": 1.0, "y": 0.0, "theta": 0.0})
        final = client.wait(rid, timeout=10)
    assert final["status"] == "rejected" and final["reason"] == "rule"
    assert [(e["service"], e["state"], e["outcome"]) for e in events if e["request"] == rid] == [
        ("NDD.GoTo", "idle", "rejected")]


@pytest.fixture
def guarded():
    from runtime.controller import Controller
    from runtime.services.server import ServiceServer
    from runkit import DALA_CODELS, dala

    pkg = dala()
    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, str(DALA_CODELS))
    server = ServiceServer(controller, token="s3cret-token")  # the engine need not run for the guard
    server.start()
    try:
        yield server
    finally:
        server.stop()


def test_behind_a_token_the_page_loads_and_nothing_of_the_controller_without_it(guarded):
    assert get(guarded, "/live/")[0] == 200
    assert get(guarded, "/live/live.js")[0] == 200
    assert get(guarded, "/", {"Accept": "text/html"})[0] == 303
    for path in ("/", "/components", "/pictures/level.svg", "/pictures/modules/NDD.svg", "/scene", "/events",
                 "/tasks", "/openapi.json", "/live/../components", "/live/x/../../components"):
        status, headers, body = get(guarded, path)
        assert status == 401, path
        assert json.loads(body)["error"].startswith("no token: this controller requires")
    status, _, body = get(guarded, "/pictures/level.svg", {"Authorization": "Bearer wrong"})
    assert status == 401 and json.loads(body)["error"].startswith("a wrong token")
    assert get(guarded, "/pictures/level.svg", {"Authorization": "Bearer s3cret-token"})[0] == 200


def test_the_page_is_not_served_to_a_foreign_host_or_origin(guarded):
    status, _, body = get(guarded, "/live/", {"Host": "evil.example:80"})
    assert status == 403 and "is not this server" in json.loads(body)["error"]
    status, _, body = get(guarded, "/live/", {"Origin": "http://evil.example"})
    assert status == 403 and "cross-site request" in json.loads(body)["error"]


def test_mission_view_on_a_taken_port_stops_before_the_run_and_writes_nothing(tmp_path):
    import socket
    import subprocess
    import sys

    from runkit import ROOT

    taken = socket.socket()
    taken.bind(("127.0.0.1", 0))
    taken.listen()
    port = taken.getsockname()[1]
    try:
        done = subprocess.run([sys.executable, "-m", "genom2bip", "mission", "descriptions/dala/missions/corridor.yaml",
                               "--view", "--port", str(port), "--out", str(tmp_path / "out")],
                              cwd=ROOT, capture_output=True, text=True, timeout=600)
    finally:
        taken.close()
    assert done.returncode == 1, done.stderr
    assert f"--port {port}: cannot serve the live page there: Address already in use" in done.stderr
    assert "Traceback" not in done.stderr and "live view:" not in done.stdout
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("port", ["-1", "65536", "http"])
def test_mission_view_refuses_a_port_that_is_not_one(port, tmp_path):
    import subprocess
    import sys

    from runkit import ROOT

    done = subprocess.run([sys.executable, "-m", "genom2bip", "mission", "descriptions/dala/missions/corridor.yaml",
                           "--view", "--port", port, "--out", str(tmp_path / "out")],
                          cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 2
    assert f"argument --port: {port!r} is not a port (a number from 0 to 65535; 0: a free one)" in done.stderr
    assert not (tmp_path / "out").exists()
