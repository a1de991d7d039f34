"""End to end: the generated DALA controller with stub codels, requests through the HTTP interface and its client."""
from __future__ import annotations

import http.client
import json
import threading
from collections import Counter

import pytest

from runkit import ORIGIN, navigation_ready, ndd_settings, serving_dala, until
from runtime.services.client import Client, ServiceError

@pytest.fixture
def ctl():
    """A running DALA controller, its server and a client; stopped after the test."""
    with serving_dala() as running:
        yield running


def raw(server, method, path, body=None, headers=None):
    """(status, decoded JSON) of one HTTP call, for bodies and headers the client would never send."""
    conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
    conn.request(method, path, body=body, headers={"Content-Type": "application/json"} if headers is None else headers)
    response = conn.getresponse()
    data = json.loads(response.read())
    conn.close()
    return response.status, data


def test_goto_is_rejected_until_setparams_setspeed_and_setdatasource_have_completed(ctl):
    _, _, client = ctl
    navigation_ready(client)
    report = client.call("NDD", "GoTo", goal={"x": 0.1, "y": 0.0, "theta": 0.0}, timeout=5)
    assert report["status"] == "rejected" and report["reason"] == "rule"
    assert report["rule"] == "NDD.GoTo.after"
    assert report["message"] == "NDD.GoTo refused by rule NDD.GoTo.after"
    assert set(report["status_of"]) == {"NDD.SetParams", "NDD.SetSpeed", "NDD.SetDataSource"}
    assert client.call("NDD", "SetParams", timeout=5)["status"] == "ok"
    assert client.call("NDD", "GoTo", goal={"x": 0.1, "y": 0, "theta": 0}, timeout=5)["rule"] == "NDD.GoTo.after"
    ndd_settings(client)
    report = client.call("NDD", "GoTo", goal={"x": 0.1, "y": 0.0, "theta": 0.0}, timeout=5)
    assert report["status"] == "ok", report
    statuses = [r["status"] for r in client.request(report["request"])["reports"]]
    assert statuses == ["queued", "started", "ok"]


def test_stop_interrupts_a_running_goto(ctl):
    _, _, client = ctl
    navigation_ready(client)
    ndd_settings(client)
    goto = client.send("NDD", "GoTo", goal={"x": 1000.0, "y": 0.0, "theta": 0.0})
    until(lambda: client.poster("NDD", "Speed")["value"] == {"v": 0.3, "w": 0.0})
    assert client.request(goto)["status"] == "running"
    stop = client.call("NDD", "Stop", timeout=5)
    assert stop["status"] == "ok"
    report = client.wait(goto, timeout=5)
    assert report["status"] == "interrupted"
    assert report["by"] == "NDD.Stop" and report["by_request"] == stop["request"]
    assert report["message"] == "NDD.GoTo interrupted by NDD.Stop"
    assert client.poster("NDD", "Speed")["value"] == {"v": 0.0, "w": 0.0}  # nddStopGoTo braked


def test_a_validate_codel_rejects_bad_parameters(ctl):
    _, _, client = ctl
    report = client.call("NDD", "SetSpeed", max_speed={"v": -0.5, "w": 0.5}, timeout=5)
    assert report["status"] == "rejected" and report["reason"] == "validate"
    assert report["exception"] == "NDD::e_bad_params" and report["detail"] == {"value": -0.5}
    assert report["codel"] == "nddCheckSpeed"
    assert client.call("NDD", "SetSpeed", max_speed={"v": 0.5}, timeout=5)["status"] == "ok"


@pytest.mark.parametrize("x, fields", [
    (13, {"exception": "NDD::e_blocked", "detail": {"where": {"x": 1.0, "y": 2.0, "theta": 0.0}}}),
    (99, {"error": "python exception", "message": "codel nddPlan raised ZeroDivisionError: division by zero"}),
    (7, {"error": "undeclared yield",
         "message": "codel nddPlan returned 'lost', not a declared yield (declared: pause::plan, arrived)"}),
])
def test_a_failing_codel_fails_its_service_and_the_controller_keeps_running(ctl, x, fields):
    controller, _, client = ctl
    navigation_ready(client)
    ndd_settings(client)
    report = client.call("NDD", "GoTo", goal={"x": x, "y": 0.0, "theta": 0.0}, timeout=5)
    assert report["status"] == "failed" and report["codel"] == "nddPlan"
    assert {k: report[k] for k in fields} == fields
    assert client.call("NDD", "GoTo", goal={"x": 0.05, "y": 0.0, "theta": 0.0}, timeout=5)["status"] == "ok"
    assert controller.status == "running"


def test_a_missing_codel_fails_its_service_with_its_name(ctl):
    _, _, client = ctl
    report = client.call("POM", "Reset", timeout=5)
    assert report["status"] == "failed" and report["error"] == "missing codel"
    assert report["message"].startswith("codel pomReset is missing: no function pomReset in ")
    assert client.info()["codels"]["missing"] == ["POM.pomReset"]


def test_posters_show_the_last_written_value_to_clients_and_codels(ctl):
    controller, _, client = ctl
    navigation_ready(client)
    until(lambda: client.poster("LaserRF", "Scan")["written"])
    scan = client.poster("LaserRF", "Scan")
    assert scan["written"] and scan["value"]["ranges"] == [8.0] * 7
    later = client.poster("LaserRF", "Scan")
    assert later["seq"] >= scan["seq"]
    ndd_settings(client)
    client.call("NDD", "SetSpeed", max_speed={"v": 0.2, "w": 0.1}, timeout=5)
    goto = client.send("NDD", "GoTo", goal={"x": 1000.0, "y": 0.0, "theta": 0.0})
    until(lambda: client.poster("NDD", "Speed")["value"] == {"v": 0.2, "w": 0.0})
    until(lambda: controller.data.ids["RFLEX"]["command"] == {"v": 0.2, "w": 0.0})  # rflexTrack read NDD's Speed
    client.call("NDD", "Stop", timeout=5)
    assert client.wait(goto, timeout=5)["status"] == "interrupted"
    assert client.poster("POM", "Pos")["value"]["estimate"] == ORIGIN
    with pytest.raises(ServiceError) as err:
        client.poster("NDD", "Obs")
    assert err.value.status == 404 and "no poster 'Obs' (posters: Speed, Nav)" in err.value.message


def test_outputs_come_back_in_the_ok_report(ctl):
    _, _, client = ctl
    report = client.call("RFLEX", "SetAcceleration", acceleration_max=1.5, timeout=5)
    assert report["status"] == "ok" and report["outputs"] == {}
    ok = client.call("NDD", "SetDataSource", obs="Obs2", timeout=5)
    assert ok["status"] == "ok"


@pytest.mark.parametrize("method, path, body, status, message", [
    ("POST", "/components/NDD/services/SetSpeed", b'{"max_speed": {"v": 1,', 400, "malformed JSON"),
    ("POST", "/components/NDX/services/GoTo", b"{}", 404, "no component 'NDX' (components: Aspect, LaserRF"),
    ("POST", "/components/NDD/services/Goto", b"{}", 404, "component NDD has no service 'Goto' (services: SetParams"),
    ("POST", "/components/NDD/services/SetSpeed", b'{"max_speed": {"v": "fast"}}', 422,
     "max_speed.v: expected a number, got 'fast'"),
    ("POST", "/components/NDD/services/GoTo", b"{}", 422, "missing parameter 'goal'"),
    ("POST", "/components/NDD/services/GoTo", b'{"goal": {"x": 1, "y": 2, "theta": 0}, "speed": 1}', 422,
     "unknown parameter 'speed'"),
    ("POST", "/components/NDD/services/GoTo", b"[1]", 422, "must be a JSON object"),
    ("POST", "/components/RFLEX/services/Init", b'{"device": "' + b"x" * 80 + b'"}', 422,
     "device: a string of at most 64 characters expected, got 80"),
    ("GET", "/requests/123456", None, 404, "no request 123456"),
    ("GET", "/requests/abc", None, 400, "request id 'abc' is not a number"),
    ("GET", "/requests/1?wait=soon", None, 400, "wait='soon'"),
    ("GET", "/nowhere", None, 404, "no route /nowhere"),
    ("DELETE", "/components/NDD/services/GoTo", None, 405, "DELETE is not allowed"),
    ("GET", "/events?types=report,gossip", None, 400, "unknown event type(s) gossip"),
    ("POST", "/components/NDD/services/SetSpeed", b'{"max_speed": {"v": ' + b"1" * 5000 + b"}}", 400,
     "unreadable JSON in the body of the request to NDD.SetSpeed: Exceeds the limit (4300 digits)"),
    ("POST", "/components/NDD/services/SetSpeed", b"[" * 100_000 + b"]" * 100_000, 400,
     "the body of the request to NDD.SetSpeed nests arrays or objects too deeply (at most 64 levels)"),
    ("POST", "/components/NDD/services/SetSpeed", b'{"max_speed": ' * 70 + b"1" + b"}" * 70, 400,
     "nests arrays or objects too deeply"),
    ("POST", "/components/NDD/services/SetSpeed", b'{"max_speed": {"v": NaN}}', 422,
     "max_speed.v: nan is not a finite number"),
    ("POST", "/components/NDD/services/SetSpeed", b'{"max_speed": {"v": Infinity}}', 422,
     "max_speed.v: inf is not a finite number"),
    ("POST", "/components/NDD/services/SetSpeed", b'{"max_speed": {"w": -Infinity}}', 422,
     "max_speed.w: -inf is not a finite number"),
    ("POST", "/components/NDD/services/SetSpeed", b'{"max_speed": {"v": 1e999}}', 422,
     "max_speed.v: inf is not a finite number"),
    ("POST", "/components/NDD/services/SetSpeed", b"null", 422, "must be a JSON object, not null"),
    ("POST", "/components/NDD/services/SetSpeed", b"\xff\xfe{}", 400, "is not UTF-8"),
    ("GET", "/requests?limit=-5", None, 400, "limit='-5': a number of requests from 1 to 999999999 expected"),
    ("GET", "/requests?limit=0", None, 400, "limit='0'"),
    ("GET", "/requests?limit=" + "9" * 5000, None, 400, "a number of requests from 1"),
    ("GET", "/requests?status=runing", None, 400,
     "status='runing': one of queued, running, ok, rejected, failed, interrupted expected"),
    ("GET", "/requests?status=", None, 400, "status='': one of queued"),
], ids=lambda v: None if v is None else (v.decode(errors="replace") if isinstance(v, bytes) else str(v))[:40])
def test_bad_requests_get_a_4xx_that_names_the_problem(ctl, method, path, body, status, message):
    controller, server, client = ctl
    before = client.send("NDD", "SetSpeed")
    got_status, data = raw(server, method, path, body)
    assert got_status == status and message in data["error"], data
    assert data["status"] == status
    assert client.wait(before, timeout=5)["status"] == "ok"  # nobody else lost a report
    assert controller.status == "running"


def test_a_second_goto_interrupts_the_first_and_reaches_its_own_goal(ctl):
    _, _, client = ctl  # GoTo interrupts itself: re-sending it changes the goal, as GenoM users do
    navigation_ready(client)
    ndd_settings(client)
    first = client.send("NDD", "GoTo", goal={"x": 1000.0, "y": 0.0, "theta": 0.0})
    until(lambda: client.request(first)["status"] == "running")
    second = client.send("NDD", "GoTo", goal={"x": 0.05, "y": 0.0, "theta": 0.0})
    ended = client.wait(first, timeout=5)
    assert ended["status"] == "interrupted" and ended["by"] == "NDD.GoTo" and ended["by_request"] == second
    assert client.wait(second, timeout=5)["status"] == "ok"


def test_components_services_and_openapi_describe_the_interface(ctl):
    _, _, client = ctl
    names = [c["name"] for c in client.components()]
    assert names == ["Aspect", "LaserRF", "NDD", "POM", "Planner", "RFLEX"]
    goto = client.service("NDD", "GoTo")
    assert goto["kind"] == "activity" and not goto["reentrant"]
    assert goto["inputs"] == [{"name": "goal", "schema": {"$ref": "dala::pose"}, "doc": "Goal in the world frame",
                               "required": True}]
    assert goto["throws"] == ["NDD::e_no_goal", "NDD::e_blocked"]
    spec = client.openapi()
    assert spec["openapi"].startswith("3.")
    post = spec["paths"]["/components/NDD/services/GoTo"]["post"]
    body = post["requestBody"]["content"]["application/json"]["schema"]
    assert body["required"] == ["goal"] and body["properties"]["goal"]["$ref"] == "#/components/schemas/dala.pose"
    assert spec["components"]["schemas"]["dala.pose"]["required"] == ["x", "y", "theta"]
    assert "/components/NDD/ports/Speed" in spec["paths"]
    tasks = {t["task"]: t for t in client.tasks()}
    assert tasks["RFLEX.servo"]["period_ms"] == 25.0 and tasks["RFLEX.servo"]["periods"] > 0


def test_post_with_wait_returns_the_ended_request(ctl):
    _, server, _ = ctl
    status, data = raw(server, "POST", "/components/NDD/services/SetSpeed?wait=5", b"")
    assert status == 200 and data["status"] == "ok" and data["final"]["status"] == "ok"


def test_the_event_stream_carries_reports_and_poster_writes(ctl):
    _, server, client = ctl
    events = []

    def odometry(event):
        return event["event"] == "poster" and event["component"] == "RFLEX" and event["port"] == "Odo"

    def listen():  # until the request's final report and a write of RFLEX's Odo (every 25 ms) have come
        for event in client.events(types="report,poster", timeout=10):
            events.append(event)
            if any(e["event"] == "report" and e["final"] for e in events) and any(map(odometry, events)):
                return

    reader = threading.Thread(target=listen)
    reader.start()
    until(lambda: server.app.state.hub.streams == 1)  # the stream is open: it will see every report
    rid = client.send("NDD", "SetParams")
    reader.join(60)
    assert not reader.is_alive()
    reports = [(e["request"], e["status"]) for e in events if e["event"] == "report"]
    assert reports == [(rid, "queued"), (rid, "started"), (rid, "ok")]
    assert any(map(odometry, events))


def test_a_flood_of_requests_from_concurrent_clients_gets_exactly_one_final_report_each(ctl):
    controller, server, client = ctl
    finals: Counter = Counter()
    expected = 2000
    done = threading.Event()

    def listen():
        for event in client.events(types="report", timeout=60):
            if event["final"]:
                finals[event["request"]] += 1
                if sum(finals.values()) >= expected:
                    done.set()
                    return

    reader = threading.Thread(target=listen, daemon=True)
    reader.start()
    until(lambda: server.app.state.hub.streams == 1)  # the stream is open: it will see every final report
    services = [("NDD", "SetSpeed", {"max_speed": {"v": 0.2, "w": 0.3}}),
                ("NDD", "SetSpeed", {"max_speed": {"v": -1.0}}),  # rejected by its validate codel
                ("NDD", "SetParams", {}), ("NDD", "SetDataSource", {"obs": "Obs"}), ("Aspect", "SetParams", {}),
                ("LaserRF", "SetConfig", {"beams": 181}), ("RFLEX", "SetAcceleration", {"acceleration_max": 0.4})]
    ids: list[int] = []
    refused: list[int] = []
    lock = threading.Lock()

    def flood(k: int):
        mine = Client(server.url, timeout=20)
        for i in range(expected // 8):
            component, service, inputs = services[(k + i) % len(services)]
            rid = mine.send(component, service, inputs)
            if i % 50 == 0:  # now and then something malformed: it must not cost anybody a report
                try:
                    mine.send("NDD", "SetSpeed", {"max_speed": {"v": "x"}})
                except ServiceError as err:
                    with lock:
                        refused.append(err.status)
            with lock:
                ids.append(rid)

    senders = [threading.Thread(target=flood, args=(k,)) for k in range(8)]
    for s in senders:
        s.start()
    for s in senders:  # a few seconds here; the bounds only keep a lost report from hanging the suite
        s.join(300)
    assert done.wait(300), f"{sum(finals.values())} final reports of {expected}"
    assert len(ids) == expected == len(set(ids))
    assert set(finals) == set(ids) and set(finals.values()) == {1}
    assert refused == [422] * len(refused) and len(refused) == 8 * (expected // 8 // 50)
    statuses = Counter(controller.requests[i].status for i in ids)
    assert set(statuses) == {"ok", "rejected"}
    for rid in ids[::97]:
        reports = client.request(rid)["reports"]
        assert [r["final"] for r in reports].count(True) == 1

    def servo_accounted():  # every deadline of the 25 ms task so far: a period run or a period counted missed
        servo = next(t for t in client.tasks() if t["task"] == "RFLEX.servo")
        due = int((controller.clock.now() - controller.started_at) / (servo["period_ms"] / 1e3)) + 1
        return due - 2 <= servo["periods"] + servo["missed"] <= due

    until(servo_accounted)


def _unsent(port: int, peer: int) -> int:
    """Bytes the server on ``port`` holds in its socket to the client port ``peer`` (Linux /proc/net/tcp)."""
    with open("/proc/net/tcp") as table:
        for line in table.readlines()[1:]:
            fields = line.split()
            local, remote, queues = fields[1], fields[2], fields[4]
            if int(local.rsplit(":", 1)[1], 16) == port and int(remote.rsplit(":", 1)[1], 16) == peer:
                return int(queues.split(":")[0], 16)
    return 0


def test_an_event_stream_blocked_on_a_full_socket_does_not_hold_the_stop(capfd):
    """The stream's writer is stuck on a connection whose buffers are full: the stop cuts it, quietly and soon."""
    import socket

    from runtime.controller import Controller
    from runtime.services.server import ServiceServer
    from runkit import DALA_CODELS, dala

    pkg = dala()
    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, str(DALA_CODELS))
    server = ServiceServer(controller)
    server.socket.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)  # inherited: the buffer fills at once
    controller.start()
    server.start()
    client = Client(server.url, timeout=10)
    stalled = socket.socket()
    stalled.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    stalled.connect(("127.0.0.1", server.port))
    stalled.sendall(b"GET /events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")  # and never reads
    peer = stalled.getsockname()[1]
    try:
        sent, unsent = 0, []
        while sent < 3000 and not (len(unsent) > 20 and len(set(unsent[-20:])) == 1 and unsent[-1] > 0):
            client.call("NDD", "SetSpeed", timeout=5)  # three reports on the stream each
            sent += 1
            unsent.append(_unsent(server.port, peer))
        assert sent < 3000, f"the stalled client's buffers did not fill: {unsent[-5:]}"
        for _ in range(200):  # and more, that the server can only keep: its writer to the stream waits
            client.send("NDD", "SetSpeed")
        server.stop()
    finally:
        stalled.close()
        server.stop()
        controller.stop()
    # held, the stop would wait for the server's graceful-shutdown timeout (3 s) and say so
    assert not server._thread.is_alive()
    err = capfd.readouterr().err
    assert "Traceback" not in err and "CancelledError" not in err and "graceful shutdown exceeded" not in err, err
