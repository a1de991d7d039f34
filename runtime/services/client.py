"""A Python client of the services interface, on the standard library alone (a decisional layer needs nothing else).

    from runtime.services.client import Client

    ndd = Client("http://127.0.0.1:8080")
    rid = ndd.send("NDD", "GoTo", goal={"x": 1.0, "y": 0.0, "theta": 0.0})
    report = ndd.wait(rid)            # {"status": "ok", "outputs": {...}, ...}
    report = ndd.call("NDD", "SetSpeed", max_speed={"v": 0.2, "w": 0.4})
    ndd.poster("NDD", "Speed")["value"]
    for event in ndd.events(types="report"): ...

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
from typing import Any, Iterator
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

    def events(self, types: str | None = None, timeout: float | None = None) -> Iterator[dict[str, Any]]:
        """The event stream, one dict per event (``{"event": "report", ...}``), on a connection of its own."""
        conn = http.client.HTTPConnection(self.host, self.port, timeout=timeout)
        path = "/events" + (f"?{urlencode({'types': types})}" if types else "")
        try:
            conn.request("GET", path, headers={"Accept": "text/event-stream", **self._auth})
            response = conn.getresponse()
            if response.status >= 400:
                raw = response.read()
                raise ServiceError(response.status, json.loads(raw).get("error", raw.decode()))
            kind, data = None, []
            while True:
                line = response.readline()
                if not line:
                    return
                text = line.decode().rstrip("\r\n")
                if text == "":
                    if data and kind != "hello":
                        yield json.loads("\n".join(data))
                    kind, data = None, []
                elif text.startswith("event:"):
                    kind = text[6:].strip()
                elif text.startswith("data:"):
                    data.append(text[5:].strip())
        finally:
            conn.close()


def parse_target(text: str) -> tuple[str, str]:
    """``"NDD.GoTo"`` → ``("NDD", "GoTo")``."""
    component, dot, service = text.partition(".")
    if not dot or not component or not service:
        raise ValueError(f"{text!r}: Component.Service expected (e.g. NDD.GoTo)")
    return component, service
