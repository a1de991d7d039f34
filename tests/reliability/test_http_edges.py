"""The HTTP edges of the services interface: malformed bodies, bad ports, tokens, repeated headers, slow clients."""
from __future__ import annotations

import json
import os
import socket
import subprocess
import sys

import pytest

from controlproc import ROOT, ControllerProcess
from probes import raw

SET_SPEED = b"POST /components/NDD/services/SetSpeed HTTP/1.1\r\nHost: 127.0.0.1\r\n"


def run(*args: str, env: dict | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "dala", "run", *args], cwd=ROOT / "gen", capture_output=True,
                          text=True, timeout=120, env=dict(os.environ, **(env or {})))


def test_an_oversize_chunked_body_that_turns_malformed_gets_its_413_and_no_traceback():
    with ControllerProcess() as ctl:
        port = int(ctl.url.rsplit(":", 1)[1])
        with socket.create_connection(("127.0.0.1", port), timeout=30) as s:
            s.sendall(SET_SPEED + b"Content-Type: application/json\r\nTransfer-Encoding: chunked\r\n\r\n")
            chunk = b"x" * 65536
            try:
                for _ in range(20):
                    s.sendall(b"%x\r\n" % len(chunk) + chunk + b"\r\n")
                s.sendall(b"zz\r\nnot a chunk\r\n\r\n")
            except OSError:
                pass  # the server may close before the client has sent everything
            answer = s.recv(65536)
        assert answer.startswith(b"HTTP/1.1 413 "), answer[:200]
        assert ctl.client().info()["status"] == "running"
        end = ctl.stop()
    assert end.status == 0
    assert "Traceback" not in end.err and "Fatal error" not in end.err, end.err


@pytest.mark.parametrize("port", ["70000", "-1", "http"])
def test_a_port_out_of_range_is_an_error_that_names_it(port):
    result = run("--port", port)
    assert result.returncode == 1 and "Traceback" not in result.stderr, result.stderr
    assert f"error: --port {port}: a TCP port from 0 to 65535 expected" in result.stderr, result.stderr


def test_a_token_with_non_ascii_characters_can_be_used():
    from runtime.services.client import Client, ServiceError

    token = "jeton-€-секрет"
    with ControllerProcess(env={"GENOM2BIP_TOKEN": token}) as ctl:
        assert Client(ctl.url, token=token).info()["status"] == "running"
        status, _ = raw(ctl.url, b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nAuthorization: Bearer " + token.encode()
                        + b"\r\n\r\n")
        assert status == 200  # as curl sends it: UTF-8 bytes
        with pytest.raises(ServiceError) as refused:
            Client(ctl.url, token="jeton-e-sekret").info()
        assert refused.value.status == 401
        end = ctl.stop()
    assert "Traceback" not in end.err, end.err


def test_the_token_is_taken_from_a_file_or_the_environment_never_from_the_command_line(tmp_path):
    from runtime.services.client import Client, ServiceError

    refused = run("--token", "s3cret")
    assert refused.returncode == 1, refused.stderr
    assert "--token: a token on the command line shows to anyone who lists the processes (ps): give --token-file " \
           "FILE or set GENOM2BIP_TOKEN" in refused.stderr and "s3cret" not in refused.stderr, refused.stderr
    help_text = run("--help").stdout
    assert "--token-file FILE" in help_text and "GENOM2BIP_TOKEN" in help_text, help_text
    secret = tmp_path / "token"
    secret.write_text("from-a-file\n")
    with ControllerProcess("--token-file", str(secret)) as ctl:
        assert Client(ctl.url, token="from-a-file").info()["status"] == "running"
        with pytest.raises(ServiceError):
            Client(ctl.url, token="").info()
        ctl.stop()
    empty = tmp_path / "empty"
    empty.write_text("\n")
    result = run("--token-file", str(empty))
    assert result.returncode == 1 and f"--token-file {empty}: the file holds no token" in result.stderr, result.stderr


@pytest.mark.parametrize("headers, what", [
    (b"Origin: http://evil.example\r\nOrigin: http://127.0.0.1\r\n", "Origin"),
    (b"Content-Type: text/plain\r\nContent-Type: application/json\r\n", "Content-Type"),
    (b"Authorization: Bearer wrong\r\nAuthorization: Bearer s3cret\r\n", "Authorization"),
], ids=["Origin", "Content-Type", "Authorization"])
def test_a_repeated_security_header_is_refused(headers, what):
    with ControllerProcess(env={"GENOM2BIP_TOKEN": "s3cret"}) as ctl:
        if what != "Content-Type":
            headers += b"Content-Type: application/json\r\n"
        if what != "Authorization":
            headers += b"Authorization: Bearer s3cret\r\n"
        status, body = raw(ctl.url, SET_SPEED + headers + b"Content-Length: 2\r\n\r\n{}")
        assert status == 400, body
        assert json.loads(body)["error"] == f"repeated {what} header: refused (a request names it once)"
        from runtime.services.client import Client

        assert Client(ctl.url, token="s3cret").requests() == []  # nothing was sent to the controller
        ctl.stop()


def test_slow_clients_are_cut_by_read_timeouts_and_a_connection_limit():
    with ControllerProcess("--read-timeout", "3", "--max-connections", "20") as ctl:
        port = int(ctl.url.rsplit(":", 1)[1])

        def cut(sock: socket.socket, trickle: bytes) -> bytes:
            """Send ``trickle`` a byte at a time until the server answers or closes: what it answered."""
            sock.settimeout(0.2)
            for byte in trickle:
                try:
                    answer = sock.recv(4096)
                    return answer  # b"" when closed
                except TimeoutError:
                    pass
                sock.sendall(bytes([byte]))
            raise AssertionError(f"still open after {len(trickle)} bytes sent over {len(trickle) * 0.2:.0f} s")

        head = socket.create_connection(("127.0.0.1", port))
        assert cut(head, b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: " + b"a" * 150).startswith(
            b"HTTP/1.1 408 "), "a request whose headers never end"
        body = socket.create_connection(("127.0.0.1", port))
        body.sendall(SET_SPEED + b"Content-Type: application/json\r\nContent-Length: 200\r\n\r\n")
        assert cut(body, b"{" + b" " * 150).startswith(b"HTTP/1.1 408 "), "a body that never ends"
        idle = [socket.create_connection(("127.0.0.1", port)) for _ in range(20)]
        extra = socket.create_connection(("127.0.0.1", port))
        extra.sendall(b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
        extra.settimeout(30)
        answer = extra.recv(4096)
        assert answer.startswith(b"HTTP/1.1 503 ") and b"connections" in answer, answer[:300]
        for s in idle:  # silent connections are closed by the read timeout too, and the slots come back
            s.settimeout(30)
            assert s.recv(4096) == b""
        assert ctl.client().info()["status"] == "running"
        end = ctl.stop()
    assert end.status == 0 and "Traceback" not in end.err, end.err
