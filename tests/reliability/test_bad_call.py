"""``genom2bip call`` against servers that are not a services interface: a bounded read, a clear error (exit 1),
a server's text escaped before it reaches the terminal; a --timeout that is not a time is a usage error (exit 2)."""
from __future__ import annotations

import json

import pytest

from badinputkit import genom2bip
from liars import Liar

pytestmark = pytest.mark.reliability

#: Far above what a refused reply costs (about 40 MB with the 16 MB read), far below the 2 GB cap a runaway reaches.
PEAK_MB = 300


def _http(status: str, body: bytes, *headers: str) -> bytes:
    head = [f"HTTP/1.1 {status}", f"Content-Length: {len(body)}", "Content-Type: application/json", *headers]
    return ("\r\n".join(head) + "\r\n\r\n").encode() + body


def _endless(conn) -> None:
    """A 200 whose body never ends: written until the client hangs up (or stops reading, then its cap ends it)."""
    conn.sendall(b"HTTP/1.1 200 OK\r\nContent-Type: application/json\r\nConnection: close\r\n\r\n[")
    chunk = b"1," * 32768
    while True:
        conn.sendall(chunk)


def _call(liar: Liar, *argv):
    done = genom2bip("call", f"http://127.0.0.1:{liar.port}", *argv)
    assert "internal error" not in done.err and "Traceback" not in done.err, done.err
    return done


@pytest.mark.parametrize("reply, why", [
    (_endless, "the reply goes on past 16 MB, more than a services interface sends"),
    (_http("200 OK", b"[" * 200_000), "the reply's JSON nests too deep to be read"),
    (b"SSH-2.0-OpenSSH_9.6\r\n", "the reply is not HTTP (BadStatusLine)"),
    (_http("200 OK", b"<html>hello</html>"), "the reply is not JSON"),
    (_http("200 OK", b"[1, 2]"), "the components listed are not of the interface's shape"),
    (b"HTTP/1.1 200 OK\r\nContent-Length: 99999999999\r\n\r\n", "the reply announces 99,999,999,999 bytes, more than "
                                                               "the 16 MB a services interface sends"),
], ids=["endless", "deep", "ssh", "html", "list", "huge-length"])
def test_a_listing_from_a_server_that_is_not_an_interface_is_refused(reply, why):
    with Liar(reply) as liar:
        done = _call(liar)
    assert done.code == 1, done.err
    assert done.err == f"genom2bip: error: http://127.0.0.1:{liar.port}: not a services interface: {why}\n"
    assert done.out == ""
    assert done.peak_mb < PEAK_MB, done.peak_mb


@pytest.mark.parametrize("reply, why", [
    (_http("202 Accepted", b'{"id": "7"}'), "a request id expected in the reply, got str"),
    (_http("202 Accepted", b"[" * 200_000), "the reply's JSON nests too deep to be read"),
    (b"garbage\r\n\r\n", "the reply is not HTTP (BadStatusLine)"),
], ids=["id-not-int", "deep", "garbage"])
def test_a_request_answered_by_a_server_that_is_not_an_interface_is_refused(reply, why):
    with Liar(reply) as liar:
        done = _call(liar, "NDD.Stop", "--wait")
    assert done.code == 1, done.err
    assert done.err == f"genom2bip: error: http://127.0.0.1:{liar.port}: not a services interface: {why}\n"


def test_escape_sequences_in_an_error_are_shown_escaped_never_sent_to_the_terminal():
    message = "\x1b]0;owned\x07\x1b[2J\x1b[31mred\rover\x9b1m"
    with Liar(_http("422 Unprocessable Entity", json.dumps({"error": message}).encode())) as liar:
        done = _call(liar, "NDD.Stop")
    assert done.code == 1, done.err
    assert done.err == "genom2bip: error: NDD.Stop: \\x1b]0;owned\\x07\\x1b[2J\\x1b[31mred\\rover\\x9b1m\n"


def test_escape_sequences_in_a_listing_are_shown_escaped():
    components = json.dumps([{"name": "A\x1b[2J", "doc": "d\x07"}]).encode()
    services = json.dumps({"services": [{"name": "S\x1b[0m", "kind": "activity", "inputs": []}]}).encode()
    replies = iter([components, services])

    def answer(conn) -> None:  # each request on a connection of its own (Connection: close)
        conn.recv(65536)
        conn.sendall(_http("200 OK", next(replies), "Connection: close"))

    with Liar(answer, limit=2) as liar:
        done = _call(liar)
    assert done.code == 0, done.err
    assert done.out == "A\\x1b[2J: d\\x07\n  A\\x1b[2J.S\\x1b[0m (activity)\n"


@pytest.mark.parametrize("seconds", ["nan", "inf", "-1", "-inf", "1e9"])
def test_a_timeout_that_is_not_a_time_is_a_usage_error_before_anything_is_sent(seconds):
    with Liar(_http("202 Accepted", b'{"id": 1}')) as liar:
        done = _call(liar, "NDD.Stop", "--wait", f"--timeout={seconds}")
    assert done.code == 2, done.err
    assert done.err == f"genom2bip: error: --timeout: a number of seconds from 0 to 604800 (a week) expected, got " \
                       f"{float(seconds):g}\n"
    assert liar.served == 0
