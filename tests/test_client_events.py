"""``Client.events()``: a long stream holds one event at a time, the events the server dropped are counted, and a
server that never ends an event is cut instead of read until memory runs out (runtime/services/client.py)."""
from __future__ import annotations

import json
import socket
import threading
import tracemalloc
from typing import Callable, Iterator

import pytest

from runtime.services import client as client_module
from runtime.services.client import BadReply, Client, ServiceError

HEAD = b"HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nConnection: close\r\n\r\n"


def frame(kind: str, data: dict) -> bytes:
    return f"event: {kind}\ndata: {json.dumps(data)}\n\n".encode()


class FakeStream:
    """One connection on 127.0.0.1 answered with the bytes ``chunks()`` yields, then closed."""

    def __init__(self, chunks: Callable[[], Iterator[bytes]]) -> None:
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.url = f"http://127.0.0.1:{self.sock.getsockname()[1]}"
        self.request = b""
        self.thread = threading.Thread(target=self._serve, args=(chunks,), daemon=True)
        self.thread.start()

    def _serve(self, chunks) -> None:
        conn, _ = self.sock.accept()
        with conn:
            while b"\r\n\r\n" not in self.request:
                self.request += conn.recv(4096)
            try:
                for chunk in chunks():
                    conn.sendall(chunk)
            except OSError:  # the client closed the stream
                pass
        self.sock.close()


@pytest.fixture
def serve():
    made: list[FakeStream] = []

    def start(chunks) -> FakeStream:
        made.append(FakeStream(chunks))
        return made[-1]

    yield start
    for fake in made:
        fake.thread.join(10)


N = 50_000


def long_run() -> Iterator[bytes]:
    yield HEAD + frame("hello", {"status": "running"})
    for k in range(N):
        yield frame("poster", {"event": "poster", "seq": k, "value": {"x": float(k), "pad": "p" * 200}})
        if k == 30_000:
            yield frame("gap", {"event": "gap", "dropped": 1500, "by_kind": {"poster": 1500}, "message": "behind"})
        if k == 40_000:
            yield frame("gap", {"event": "gap", "dropped": 7, "by_kind": {"poster": 7}, "message": "behind"})


def test_a_long_stream_is_read_in_constant_memory_and_its_drops_are_counted(serve):
    fake = serve(long_run)
    stream = Client(fake.url).events(types="poster", timeout=30)
    tracemalloc.start()
    try:
        seen, last, peak_at_10k = 0, -1, None
        for event in stream:
            if event["event"] == "poster":
                assert event["seq"] == last + 1  # in order, none lost on the client's side
                last, seen = event["seq"], seen + 1
                if seen == 10_000:
                    peak_at_10k = tracemalloc.get_traced_memory()[1]
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert seen == N and stream.events == N + 2  # the hello is not an event of the stream; both gaps are
    assert (stream.dropped, stream.gaps) == (1507, 2)
    assert peak < 1024 * 1024, peak  # one event at a time: far below the 14 MB the events weigh together
    assert peak - peak_at_10k < 256 * 1024  # and the 40 000 events after the first 10 000 added nothing
    assert b"GET /events?types=poster " in fake.request


def test_a_stream_without_gaps_drops_nothing(serve):
    fake = serve(lambda: iter([HEAD, frame("report", {"event": "report", "request": 1, "final": True})]))
    with Client(fake.url).events(timeout=10) as stream:
        assert [e["request"] for e in stream] == [1]
    assert (stream.dropped, stream.gaps, stream.events) == (0, 0, 1)


def endless_event() -> Iterator[bytes]:
    yield HEAD + b"event: poster\n"
    for _ in range(8 * 1024):  # 8 MB of data lines and never the blank line that ends the event
        yield b"data: " + b"7" * 1017 + b"\n"


def endless_line() -> Iterator[bytes]:
    yield HEAD + b"data: "
    for _ in range(8 * 1024):  # 8 MB and never a newline
        yield b"7" * 1024


@pytest.mark.parametrize("chunks", [endless_event, endless_line])
def test_a_server_that_never_ends_an_event_is_cut(serve, monkeypatch, chunks):
    monkeypatch.setattr(client_module, "MAX_EVENT_BYTES", 64 * 1024, raising=False)
    fake = serve(chunks)
    stream = Client(fake.url).events(timeout=30)
    tracemalloc.start()
    try:
        with pytest.raises(BadReply, match="an event of the stream goes on past 64 kB"):
            next(stream)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 1024 * 1024, peak


def test_an_event_that_is_not_a_json_object_is_a_bad_reply(serve):
    fake = serve(lambda: iter([HEAD + b"event: poster\ndata: [1, 2]\n\n"]))
    with pytest.raises(BadReply, match="an event expected in the reply, got list"):
        next(Client(fake.url).events(timeout=10))


def test_a_refused_stream_raises_the_servers_message(serve):
    body = b'{"error": "a token is needed"}'
    fake = serve(lambda: iter([b"HTTP/1.1 401 Unauthorized\r\nContent-Type: application/json\r\nContent-Length: "
                               + str(len(body)).encode() + b"\r\n\r\n" + body]))
    with pytest.raises(ServiceError, match="401: a token is needed"):
        next(Client(fake.url).events(timeout=10))
