"""What the reliability tests probe a controller with: an event log, codels that misbehave, raw sockets."""
from __future__ import annotations

import http.client
import json
import shutil
import socket
import threading
import time
from pathlib import Path
from urllib.parse import urlsplit

from controlproc import REAL_CODELS


class EventLog:
    """``/events?types=...`` read all along by a thread; :meth:`wait` returns the first event a predicate accepts."""

    def __init__(self, url: str, types: str | None = None) -> None:
        parts = urlsplit(url)
        self.events: list[dict] = []
        self.ended = False
        self._changed = threading.Condition()
        self._conn = http.client.HTTPConnection(parts.hostname, parts.port, timeout=120)
        self._conn.request("GET", "/events" + (f"?types={types}" if types else ""))
        self._response = self._conn.getresponse()
        assert self._response.status == 200, self._response.read()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        """The reader thread: every event but the hello, in order, until the stream ends."""
        kind, data = None, None
        try:
            for raw in iter(self._response.readline, b""):
                line = raw.decode().rstrip("\r\n")
                if line.startswith("event:"):
                    kind = line[6:].strip()
                elif line.startswith("data:"):
                    data = json.loads(line[5:])
                elif line == "" and data is not None:
                    if kind != "hello":
                        with self._changed:
                            self.events.append(data)
                            self._changed.notify_all()
                    kind, data = None, None
        except OSError:
            pass
        with self._changed:
            self.ended = True
            self._changed.notify_all()

    def wait(self, predicate, timeout: float = 60.0) -> dict:
        """The first event (so far or to come) for which ``predicate(event)`` holds."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while True:
                found = next((e for e in self.events if predicate(e)), None)
                if found is not None:
                    return found
                left = deadline - time.monotonic()
                assert left > 0 and not self.ended, f"no such event in {len(self.events)} events"
                self._changed.wait(left)

    def wait_ended(self, timeout: float = 60.0) -> None:
        with self._changed:
            assert self._changed.wait_for(lambda: self.ended, timeout), "the stream did not end"


def codels_with(tmp_path: Path, **appended: str) -> Path:
    """DALA's real codels copied to ``tmp_path``, with code appended to some components' modules (``LaserRF=...``)."""
    where = tmp_path / "codels"
    shutil.copytree(REAL_CODELS, where, ignore=shutil.ignore_patterns("__pycache__"))
    (tmp_path / "worlds").symlink_to(REAL_CODELS.parent / "worlds")  # the codels find their worlds beside them
    for component, code in appended.items():
        module = where / f"{component}.py"
        module.write_text(module.read_text() + "\n\n" + code)
    return where


def idle_subscribers(url: str, n: int, types: str | None = None) -> list[socket.socket]:
    """``n`` event-stream clients with small receive buffers that never read."""
    port = int(url.rsplit(":", 1)[1])
    query = f"?types={types}" if types else ""
    socks = []
    for _ in range(n):
        s = socket.socket()
        s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        s.connect(("127.0.0.1", port))
        s.sendall(f"GET /events{query} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n".encode())
        socks.append(s)
    return socks


def raw(url: str, request: bytes, timeout: float = 30.0) -> tuple[int, bytes]:
    """Send ``request`` as bytes on a connection of its own: (status, body) of the answer."""
    port = int(url.rsplit(":", 1)[1])
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
        s.sendall(request)
        answer = b""
        while b"\r\n\r\n" not in answer:
            chunk = s.recv(65536)
            if not chunk:
                break
            answer += chunk
        head, _, body = answer.partition(b"\r\n\r\n")
        length = next((int(line.split(b":")[1]) for line in head.split(b"\r\n")
                       if line.lower().startswith(b"content-length:")), 0)
        while len(body) < length:
            chunk = s.recv(65536)
            if not chunk:
                break
            body += chunk
    return int(head.split(b" ")[1]), body


def tasks(client) -> dict[str, dict]:
    """GET /tasks by task name."""
    return {t["task"]: t for t in client.tasks()}


def read_events(sock: socket.socket, until, timeout: float = 60.0) -> list[dict]:
    """Read a raw event-stream socket (HTTP head, chunked body) until ``until(events)`` holds: the events read."""
    sock.settimeout(timeout)
    deadline = time.monotonic() + timeout
    buffer, events = b"", []
    while not until(events):
        assert time.monotonic() < deadline, f"not there after {len(events)} events"
        chunk = sock.recv(1 << 16)
        assert chunk, f"the stream ended after {len(events)} events"
        buffer += chunk
        while b"\n\n" in buffer:
            frame, buffer = buffer.split(b"\n\n", 1)
            lines = frame.split(b"\n")
            kind = next((line[6:].strip().decode() for line in lines if line.startswith(b"event:")), None)
            data = [line[5:] for line in lines if line.startswith(b"data:")]
            if data and kind != "hello":
                events.append({"event": kind} | json.loads(data[-1]))
    return events
