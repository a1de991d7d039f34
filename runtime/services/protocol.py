"""HTTP/1.1 connections of the services interface: uvicorn's h11 protocol with read timeouts and a connection limit.

uvicorn has neither a header nor a body read timeout: a client sending one
byte a second holds a connection (and its task) for ever, and enough of them
exhaust the process's file descriptors.  Here a request must arrive whole,
head and body, within ``read_timeout`` seconds of its first byte (or of the
connection): else ``408`` and the connection is closed (silently when
nothing came).  Beyond ``max_connections`` open connections a new one gets
``503`` and is closed at once.  Each connection's send buffers are bounded
(:data:`SEND_BUFFER` in the kernel, :data:`WRITE_BUFFER` above it), so that
a client that does not read holds little memory and soon costs nothing; the
shutdown raises the kernel's to hand the last events over.  A
malformed request after a response was already sent (an oversize chunked
body that then turns malformed) closes the connection instead of failing
inside uvicorn.
"""
from __future__ import annotations

import asyncio
import json
import socket

import h11
from uvicorn.protocols.http.h11_impl import H11Protocol

#: Seconds for a request to arrive whole, head and body, from its first byte.
READ_TIMEOUT = 10.0
#: Connections open at once; a new one beyond is answered 503 and closed.
MAX_CONNECTIONS = 512
#: Kernel send buffer of a connection, and what waits above it in the process (bytes): what a client that does
#: not read holds before its stream stops being written to.
SEND_BUFFER = 32 * 1024
WRITE_BUFFER = 16 * 1024
_READ = (h11.IDLE, h11.SEND_BODY)  # the client's states while its request is still coming


def refusal(status: int, reason: str, message: str) -> bytes:
    """A whole HTTP answer with a JSON error, written before h11 knows of any request."""
    body = json.dumps({"error": message, "status": status}).encode()
    return (f"HTTP/1.1 {status} {reason}\r\ncontent-type: application/json\r\ncontent-length: {len(body)}\r\n"
            f"connection: close\r\n\r\n").encode() + body


def guarded(read_timeout: float = READ_TIMEOUT, max_connections: int = MAX_CONNECTIONS) -> type[H11Protocol]:
    """The protocol class for uvicorn's ``http=`` with these bounds."""
    return type("GuardedH11Protocol", (GuardedH11Protocol,),
                {"read_timeout": read_timeout, "max_connections": max_connections})


class GuardedH11Protocol(H11Protocol):
    """uvicorn's h11 protocol, with the read timeout, the connection limit and the bounded send buffer above."""

    read_timeout = READ_TIMEOUT
    max_connections = MAX_CONNECTIONS

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        """Bound the send buffers, refuse a connection beyond the limit, start the read timeout."""
        super().connection_made(transport)
        self._timer: asyncio.TimerHandle | None = None
        self._started = False  # bytes of the current request have come
        sock = transport.get_extra_info("socket")
        if sock is not None:
            try:
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, SEND_BUFFER)
            except OSError:
                pass
        transport.set_write_buffer_limits(high=WRITE_BUFFER)
        if len(self.connections) > self.max_connections:
            transport.write(refusal(503, "Service Unavailable",
                                    f"more than {self.max_connections} connections are open: this one is closed, "
                                    "try again later"))
            transport.close()
            return
        self._arm()

    def data_received(self, data: bytes) -> None:
        if self.conn.their_state is h11.IDLE and not self._started:
            self._started = True
            self._arm()
        super().data_received(data)
        if self.conn.their_state not in _READ:
            self._disarm()  # the request has come whole (or the connection is done with)
            self._started = False

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm()
        super().connection_lost(exc)

    def on_response_complete(self) -> None:
        super().on_response_complete()
        if self.conn.their_state is h11.IDLE and not self.transport.is_closing():
            self._started = False  # the keep-alive timeout runs until the next request's first byte

    def _arm(self) -> None:
        self._disarm()
        self._timer = self.loop.call_later(self.read_timeout, self._timed_out)

    def _disarm(self) -> None:
        timer = getattr(self, "_timer", None)
        if timer is not None:
            timer.cancel()
            self._timer = None

    def _timed_out(self) -> None:
        """The request did not come whole in time: 408 (unless nothing came, or an answer has begun), then close."""
        self._timer = None
        if self.transport.is_closing() or self.conn.their_state not in _READ:
            return
        answered = self.cycle is not None and self.cycle.response_started
        if self._started and not answered:
            self.transport.write(refusal(408, "Request Timeout",
                                         f"the request did not arrive whole within {self.read_timeout:g} s"))
        self.transport.close()

    def send_400_response(self, msg: str) -> None:
        """A malformed request: 400, or only a close when an answer was already sent on this connection."""
        if self.conn.our_state in (h11.IDLE, h11.SEND_RESPONSE) and not (self.cycle and self.cycle.response_started):
            try:
                super().send_400_response(msg)
                return
            except h11.LocalProtocolError:
                pass
        self.transport.close()
