"""Who may command the robot: Host, Origin, content type and token checks; bodies that stream in, or never do."""
from __future__ import annotations

import http.client
import json
import os
import socket
import subprocess
import sys
import threading
import time

import pytest

from runkit import DALA_CODELS, ROOT, dala, serving_dala, until
from runtime.services.client import Client, ServiceError
from runtime.services.guard import TOKEN_ENV
from runtime.services.server import MAX_BODY, ServiceServer
from test_services_http import raw

SETSPEED = "/components/NDD/services/SetSpeed"
JSON = {"Content-Type": "application/json"}


@pytest.fixture
def ctl():
    with serving_dala() as running:
        yield running


@pytest.mark.parametrize("method, headers, status, message", [
    ("POST", {"Content-Type": "text/plain", "Origin": "http://evil.example", "Host": "evil.example:8080"}, 403,
     "Host 'evil.example:8080' is not this server: a controller on the loopback answers only to 127.0.0.1, "
     "localhost, ::1 (a guard against DNS rebinding)"),
    ("GET", {"Host": "evil.example"}, 403, "Host 'evil.example' is not this server"),
    ("POST", {**JSON, "Origin": "http://evil.example"}, 403,
     "cross-site request from Origin 'http://evil.example' refused: only pages of http://127.0.0.1:"),
    ("POST", {**JSON, "Origin": "null"}, 403, "cross-site request from Origin 'null' refused"),
    ("POST", {"Content-Type": "text/plain"}, 415,
     "Content-Type 'text/plain': a request that acts must be sent as application/json"),
    ("POST", {"Content-Type": "application/x-www-form-urlencoded"}, 415, "Content-Type 'application/x-www-form"),
    ("POST", {}, 415, "Content-Type none: a request that acts must be sent as application/json"),
])
def test_cross_site_and_foreign_requests_are_refused_and_start_nothing(ctl, method, headers, status, message):
    controller, server, client = ctl
    before = dict(controller.requests)
    got, data = raw(server, method, SETSPEED, b'{"max_speed": {"v": 0.1}}' if method == "POST" else None, headers)
    assert got == status and message in data["error"], data
    assert controller.requests == before and controller.data.ids["NDD"]["max_speed"] == {"v": 0.0, "w": 0.0}


def test_the_servers_own_pages_and_names_are_accepted(ctl):
    _, server, _ = ctl
    for host in (f"127.0.0.1:{server.port}", f"localhost:{server.port}", "127.0.0.1"):
        headers = {**JSON, "Host": host, "Origin": f"http://{host}"}
        status, data = raw(server, "POST", SETSPEED + "?wait=5", b'{"max_speed": {"v": 0.1}}', headers)
        assert status == 200 and data["final"]["status"] == "ok", data
    assert raw(server, "POST", SETSPEED + "?wait=5", b"{}", {"Content-Type": "application/json; charset=utf-8"}
               )[0] == 200


@pytest.fixture
def with_token():
    """A DALA controller whose interface requires the token "s3cret"."""
    from runtime.controller import Controller

    pkg = dala()
    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, str(DALA_CODELS))
    controller.start()
    server = ServiceServer(controller, token="s3cret").start()
    try:
        yield controller, server
    finally:
        server.stop()
        controller.stop()


def test_with_a_token_every_request_must_carry_it(with_token, monkeypatch):
    controller, server = with_token
    status, data = raw(server, "GET", "/")
    assert status == 401 and data["error"].startswith("no token: this controller requires 'Authorization: Bearer")
    status, data = raw(server, "POST", SETSPEED, b"{}", {**JSON, "Authorization": "Bearer guess"})
    assert status == 401 and data["error"].startswith("a wrong token")
    with pytest.raises(ServiceError) as err:
        Client(server.url, token="").info()
    assert err.value.status == 401
    assert controller.requests == {}
    assert Client(server.url, token="s3cret").call("NDD", "SetSpeed", timeout=5)["status"] == "ok"
    monkeypatch.setenv(TOKEN_ENV, "s3cret")
    assert Client(server.url).info()["status"] == "running"
    got = []
    reader = threading.Thread(target=lambda: got.append(next(Client(server.url).events(types="report", timeout=10))))
    reader.start()
    until(lambda: server.app.state.hub.streams == 1)  # the stream is open: it will see the report
    rid = Client(server.url).send("NDD", "SetParams")
    reader.join(10)
    assert got and got[0]["request"] == rid
    with pytest.raises(ServiceError) as err:
        next(Client(server.url, token="guess").events())
    assert err.value.status == 401


def test_listening_beyond_the_loopback_needs_a_token():
    from runtime.controller import Controller

    pkg = dala()
    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, str(DALA_CODELS))
    with pytest.raises(ValueError) as err:
        ServiceServer(controller, host="0.0.0.0")
    assert "listening on 0.0.0.0 lets other machines command the robot: give a token (--token-file or " \
           "GENOM2BIP_TOKEN)" in str(err.value)
    controller.start()
    server = ServiceServer(controller, host="0.0.0.0", token="s3cret").start()
    try:  # beyond the loopback the token is what keeps others out: any Host is taken
        status, _ = raw(server, "GET", "/", None, {"Host": "robot.lab:8080", "Authorization": "Bearer s3cret"})
        assert status == 200
        assert raw(server, "GET", "/", None, {"Host": "robot.lab:8080"})[0] == 401
    finally:
        server.stop()
        controller.stop()


def test_run_refuses_another_address_without_a_token():
    env = {k: v for k, v in os.environ.items() if k != TOKEN_ENV}
    result = subprocess.run([sys.executable, "-m", "dala", "run", "--codels", str(DALA_CODELS), "--host", "0.0.0.0",
                             "--duration", "0.1"], cwd=ROOT / "gen", capture_output=True, text=True, timeout=60,
                            env=env)
    assert result.returncode == 1
    assert "error: --host 0.0.0.0: listening on 0.0.0.0 lets other machines command the robot: give a token" \
           in result.stderr
    assert "services interface on" not in result.stdout


# --------------------------------------------------------------------------- bodies


def _connect(server):
    return socket.create_connection(("127.0.0.1", server.port), timeout=10)


def _answer(sock) -> tuple[int, dict]:
    response = http.client.HTTPResponse(sock)
    response.begin()
    return response.status, json.loads(response.read())


def test_a_body_announced_too_long_is_refused_before_it_is_sent(ctl):
    controller, server, client = ctl
    sock = _connect(server)
    sock.sendall(f"POST {SETSPEED} HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
                 f"Content-Length: 300000000\r\n\r\n{{".encode())
    status, data = _answer(sock)
    sock.close()
    assert status == 413 and data["error"] == "request body of 300000000 bytes to NDD.SetSpeed: at most 1048576 " \
                                              "accepted"
    assert controller.requests == {}


def test_a_streamed_body_is_cut_off_at_the_limit_whatever_its_length(ctl):
    controller, server, client = ctl
    sock = _connect(server)
    sock.sendall(f"POST {SETSPEED} HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
                 "Transfer-Encoding: chunked\r\n\r\n".encode())
    chunk = b"x" * 65536
    sent = 0
    sock.settimeout(0.2)
    answered = b""
    while sent < 50 * MAX_BODY and not answered:
        try:
            sock.sendall(b"%x\r\n%s\r\n" % (len(chunk), chunk))
            sent += len(chunk)
            answered = sock.recv(65536, socket.MSG_PEEK)
        except (socket.timeout, BlockingIOError):
            continue
        except (BrokenPipeError, ConnectionResetError):
            break
    sock.settimeout(10)
    status, data = _answer(sock)
    sock.close()
    assert status == 413 and data["error"] == "request body to NDD.SetSpeed longer than 1048576 bytes: refused"
    assert sent < 4 * MAX_BODY  # refused as it came, not once all was read
    assert controller.requests == {}


def test_a_half_sent_body_costs_nothing_and_prints_no_traceback(ctl, capfd):
    controller, server, client = ctl
    for _ in range(3):
        sock = _connect(server)
        sock.sendall(f"POST {SETSPEED} HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
                     "Content-Length: 100\r\n\r\n{\"max_speed\":".encode())
        time.sleep(0.1)
        sock.close()
    time.sleep(0.3)
    assert client.call("NDD", "SetSpeed", timeout=5)["status"] == "ok"
    assert [r.id for r in controller.requests.values()] == [1]
    err = capfd.readouterr().err
    assert "Traceback" not in err and "ClientDisconnect" not in err, err
