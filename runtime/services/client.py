"""A Python client of the services interface, on the standard library alone (a decisional layer needs nothing else).

    from runtime.services.client import Client

    ndd = Client("http://127.0.0.1:8080")
    rid = ndd.send("NDD", "GoTo", goal={"x": 1.0, "y": 0.0, "theta": 0.0})
    report = ndd.wait(rid)            # {"status": "ok", "outputs": {...}, ...}
    report = ndd.call("NDD", "SetSpeed", max_speed={"v": 0.2, "w": 0.4})
    ndd.poster("NDD", "Speed")["value"]
    for event in ndd.events(types="report"): ...   # ndd.events(...).dropped: events the server dropped

Each thread gets its own keep-alive connection, so one client may be shared
by threads.  Every 4xx/5xx answer raises :class:`ServiceError` with the
server's message.
"""
from __future__ import annotations

import http.client
import json
import os
import threading
import time
from typing import Any
from urllib.parse import quote, urlencode, urlsplit

from runtime.services.guard import TOKEN_ENV


class ServiceError(Exception):
    """The server refused a call: ``status`` (400, 401, 403, 404, 409, 413, 415, 422, 429, 503...) and its message."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(f"{status}: {message}")
        self.status = status
        self.message = message


class BadReply(Exception):
    """What answered is not a services interface: not HTTP, a body too large, not JSON, or not of the shape asked."""


#: Bytes of one answer's body: the largest the interface sends (a component's description, a page of requests) is
#: tens of kB; a server streaming without end is cut here, not read until memory runs out.
MAX_REPLY_BYTES = 16 * 1024 * 1024


def _read_body(response: http.client.HTTPResponse) -> bytes:
    """The body of ``response``, at most MAX_REPLY_BYTES (BadReply beyond: the connection cannot be reused)."""
    length = response.getheader("Content-Length")
    if length is not None and length.strip().isdigit() and int(length) > MAX_REPLY_BYTES:
        raise BadReply(f"the reply announces {int(length):,} bytes, more than the {MAX_REPLY_BYTES // 1024 // 1024} MB "
                       "a services interface sends")
    raw = response.read(MAX_REPLY_BYTES + 1)
    if len(raw) > MAX_REPLY_BYTES:
        raise BadReply(f"the reply goes on past {MAX_REPLY_BYTES // 1024 // 1024} MB, more than a services interface "
                       "sends")
    return raw


def _decode(raw: bytes) -> Any:
    """The JSON of a body (None when empty); BadReply when it is not JSON or nests too deep to be read."""
    if not raw:
        return None
    try:
        return json.loads(raw)
    except RecursionError:
        raise BadReply("the reply's JSON nests too deep to be read") from None
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise BadReply("the reply is not JSON") from None


def _expect(payload: Any, kind: type, what: str) -> Any:
    """``payload`` when it is a ``kind``; else BadReply naming ``what`` was expected."""
    if not isinstance(payload, kind) or isinstance(payload, bool):
        raise BadReply(f"{what} expected in the reply, got {type(payload).__name__}")
    return payload


class Client:
    """Talks to one controller's services interface at ``url`` (``http://127.0.0.1:PORT``).

    ``token``: the controller's token, if it has one (default: the
    ``GENOM2BIP_TOKEN`` environment variable).
    """

    def __init__(self, url: str, timeout: float = 30.0, token: str | None = None) -> None:
        parts = urlsplit(url if "://" in url else f"http://{url}")
        if parts.scheme != "http" or not parts.hostname:
            raise ValueError(f"{url!r}: an http://HOST:PORT address expected")
        self.host = parts.hostname
        self.port = parts.port or 80
        self.url = f"http://{self.host}:{self.port}"
        self.timeout = timeout
        token = os.environ.get(TOKEN_ENV) if token is None else token
        # as bytes: http.client would encode a str as Latin-1, which many tokens are not
        self._auth = {"Authorization": b"Bearer " + token.encode("utf-8")} if token else {}
        self._local = threading.local()

    # -- plumbing ------------------------------------------------------------------------------------
    def _connection(self, timeout: float) -> http.client.HTTPConnection:
        conn = getattr(self._local, "conn", None)
        if conn is None:
            conn = self._local.conn = http.client.HTTPConnection(self.host, self.port, timeout=timeout)
        conn.timeout = timeout
        if conn.sock is not None:
            conn.sock.settimeout(timeout)
        return conn

    def _call(self, method: str, path: str, body: Any = None, timeout: float | None = None) -> Any:
        data = None if body is None else json.dumps(body).encode()
        headers = {"Content-Type": "application/json"} if data is not None else {}
        headers.update(self._auth)
        timeout = self.timeout if timeout is None else timeout
        for attempt in (1, 2):
            conn = self._connection(timeout)
            try:
                conn.request(method, path, body=data, headers=headers)
                response = conn.getresponse()
                raw = _read_body(response)
                break
            except (http.client.RemoteDisconnected, BrokenPipeError, ConnectionResetError):
                conn.close()  # a kept-alive connection the server had closed: once more on a new one
                self._local.conn = None
                if attempt == 2:
                    raise
            except http.client.HTTPException as exc:  # not HTTP: a status line or headers that cannot be read
                conn.close()
                self._local.conn = None
                raise BadReply(f"the reply is not HTTP ({type(exc).__name__})") from None
            except (OSError, BadReply):
                conn.close()
                self._local.conn = None
                raise
        if response.status >= 400:
            try:
                payload = _decode(raw)
            except BadReply:
                payload = {"error": raw.decode(errors="replace")}
            message = payload.get("error", str(payload)) if isinstance(payload, dict) else str(payload)
            raise ServiceError(response.status, str(message))
        return _decode(raw)

    @staticmethod
    def _service_path(component: str, service: str) -> str:
        return f"/components/{quote(component, safe='')}/services/{quote(service, safe='')}"

    # -- the interface -----------------------------------------------------------------------------------
    def info(self) -> dict[str, Any]:
        """The controller: status, steps, requests by status, codels."""
        return self._call("GET", "/")

    def components(self) -> list[dict[str, Any]]:
        return self._call("GET", "/components")

    def component(self, component: str) -> dict[str, Any]:
        return self._call("GET", f"/components/{quote(component, safe='')}")

    def service(self, component: str, service: str) -> dict[str, Any]:
        """Kind, inputs and outputs (with JSON schemas), exceptions and constraints of a service."""
        return self._call("GET", self._service_path(component, service))

    def openapi(self) -> dict[str, Any]:
        return self._call("GET", "/openapi.json")

    def send(self, component: str, service: str, inputs: dict[str, Any] | None = None, **kw: Any) -> int:
        """Send a request; returns its id. Inputs as a dict and/or keyword arguments."""
        body = {**(inputs or {}), **kw}
        reply = _expect(self._call("POST", self._service_path(component, service), body), dict, "a request")
        return _expect(reply.get("id"), int, "a request id")

    def request(self, request_id: int, wait: float | None = None) -> dict[str, Any]:
        """The request with its reports (``status``, ``final``, ``reports``); ``wait`` s for the final one."""
        query = f"?wait={wait}" if wait else ""
        timeout = self.timeout + (wait or 0)
        return self._call("GET", f"/requests/{int(request_id)}{query}", timeout=timeout)

    def wait(self, request_id: int, timeout: float | None = None) -> dict[str, Any]:
        """The final report, waiting as long as needed (or ``timeout`` s, then :class:`TimeoutError`)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            left = 30.0 if deadline is None else min(30.0, deadline - time.monotonic())
            req = _expect(self.request(request_id, wait=max(left, 0.0) or None), dict, "a request")
            if req.get("final") is not None:
                return _expect(req["final"], dict, "a final report")
            if deadline is not None and time.monotonic() >= deadline:
                raise TimeoutError(f"request {request_id} has no final report after {timeout} s "
                                   f"(status {req.get('status')})")

    def call(self, component: str, service: str, inputs: dict[str, Any] | None = None,
             timeout: float | None = None, **kw: Any) -> dict[str, Any]:
        """Send a request and wait for its final report."""
        return self.wait(self.send(component, service, inputs, **kw), timeout)

    def requests(self, status: str | None = None, limit: int = 100) -> list[dict[str, Any]]:
        query = urlencode({k: v for k, v in (("status", status), ("limit", limit)) if v is not None})
        return self._call("GET", f"/requests?{query}")

    def poster(self, component: str, port: str) -> dict[str, Any]:
        """``{"value": ..., "seq": n, "written": bool}``: the poster's last written value."""
        return self._call("GET", f"/components/{quote(component, safe='')}/ports/{quote(port, safe='')}")

    def tasks(self) -> list[dict[str, Any]]:
        """Period, periods run, lateness (p50/p99/max ms) and overruns of every task."""
        return self._call("GET", "/tasks")

    def events(self, types: str | None = None, timeout: float | None = None) -> "EventStream":
        """The event stream, one dict per event (``{"event": "report", ...}``), on a connection of its own, opened at
        the first ``next``.  It holds one event at a time; how many events the server dropped because this client fell
        behind (``gap`` events) is counted in the stream's ``dropped``."""
        path = "/events" + (f"?{urlencode({'types': types})}" if types else "")
        return EventStream(self.host, self.port, path, self._auth, timeout)


#: Bytes of one event of a stream (its ``data:`` lines together): the largest the interface sends is a poster's value,
#: far below; a server that never ends an event (or a line) is cut here, not read until memory runs out.
MAX_EVENT_BYTES = 1024 * 1024


class EventStream:
    """``GET /events`` as an iterator of dicts, on a connection of its own; memory is one event, however long it runs.

    The server keeps at most 1 024 events for a client that reads slowly and
    sends a ``gap`` event (``{"event": "gap", "dropped": n, "by_kind": {...}}``)
    for those it had to drop; the stream yields it like any other event and
    adds ``n`` to :attr:`dropped` (and one to :attr:`gaps`), so a long run can
    tell whether it saw everything.  Iterating ends when the server closes
    the stream; :meth:`close` (or ``with``) ends it earlier.
    """

    def __init__(self, host: str, port: int, path: str, headers: dict, timeout: float | None) -> None:
        self._conn = http.client.HTTPConnection(host, port, timeout=timeout)
        self._path, self._headers = path, headers
        self._response: http.client.HTTPResponse | None = None
        self.events = 0  # events yielded
        self.dropped = 0  # events the server said it dropped for this stream (its ``gap`` events)
        self.gaps = 0  # gap events received

    def __iter__(self) -> "EventStream":
        return self

    def __enter__(self) -> "EventStream":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self._conn.close()

    def _open(self) -> http.client.HTTPResponse:
        self._conn.request("GET", self._path, headers={"Accept": "text/event-stream", **self._headers})
        response = self._conn.getresponse()
        if response.status >= 400:
            raw = _read_body(response)
            self.close()
            try:
                payload = _decode(raw)
            except BadReply:
                payload = None
            message = payload.get("error", str(payload)) if isinstance(payload, dict) else raw.decode(errors="replace")
            raise ServiceError(response.status, str(message))
        return response

    def __next__(self) -> dict[str, Any]:
        try:
            if self._response is None:
                self._response = self._open()
            event = self._read_event(self._response)
        except BaseException:
            self.close()
            raise
        if event is None:
            self.close()
            raise StopIteration
        self.events += 1
        if event.get("event") == "gap":
            self.gaps += 1
            dropped = event.get("dropped")
            self.dropped += dropped if isinstance(dropped, int) and not isinstance(dropped, bool) else 0
        return event

    @staticmethod
    def _read_event(response: http.client.HTTPResponse) -> dict[str, Any] | None:
        """The next event but ``hello`` (None at the end of the stream); BadReply past MAX_EVENT_BYTES."""
        kind, data, size = None, [], 0
        while True:
            line = response.readline(MAX_EVENT_BYTES + 1)
            if not line:
                return None
            size += len(line)
            if size > MAX_EVENT_BYTES:
                raise BadReply(f"an event of the stream goes on past {MAX_EVENT_BYTES // 1024} kB, more than a "
                               "services interface sends")
            text = line.decode(errors="replace").rstrip("\r\n")
            if text == "":
                if data and kind != "hello":
                    return _expect(_decode("\n".join(data).encode()), dict, "an event")
                kind, data, size = None, [], 0
            elif text.startswith("event:"):
                kind = text[6:].strip()
            elif text.startswith("data:"):
                data.append(text[5:].strip())


def parse_target(text: str) -> tuple[str, str]:
    """``"NDD.GoTo"`` → ``("NDD", "GoTo")``."""
    component, dot, service = text.partition(".")
    if not dot or not component or not service:
        raise ValueError(f"{text!r}: Component.Service expected (e.g. NDD.GoTo)")
    return component, service
