"""Who may talk to the services interface: a same-host check, no cross-site requests, an optional token.

An ASGI middleware in front of the application (docs/runtime.md, "Security"):

* the ``Host`` header must name this machine's loopback (``127.0.0.1``,
  ``localhost``, ``[::1]``), so a page served from another name that DNS
  rebinding points at 127.0.0.1 is refused; a server bound to another
  address takes any ``Host`` but then requires the token;
* an ``Origin`` header, which browsers add to cross-site requests, must be
  the server's own (``http://`` + its ``Host``);
* a request that acts (POST) must say ``Content-Type: application/json``,
  which a plain HTML form or a "simple" cross-site fetch cannot send;
* with a token (``--token-file`` or ``GENOM2BIP_TOKEN``), every request
  carries ``Authorization: Bearer TOKEN`` (compared as UTF-8 bytes, so that
  any token the operator can type works);
* the live page's own files (``/live/``, and ``/`` asked for by a browser)
  need no token: a browser cannot add one to a navigation, and they hold no
  data; what the page shows comes from the other routes, behind the token;
* each of these headers appears at most once: with two, which one a check
  read and which one a proxy or the application would read could differ.
"""
from __future__ import annotations

import hmac
import ipaddress
import json
import re
from typing import Any, Awaitable, Callable

#: The environment variable the server and the client take the token from.
TOKEN_ENV = "GENOM2BIP_TOKEN"
LOOPBACK_NAMES = ("127.0.0.1", "localhost", "::1")
#: The headers the guard reads: a request naming one of them twice is refused.
SINGLE = {b"host": "Host", b"origin": "Origin", b"content-type": "Content-Type", b"authorization": "Authorization"}

Scope = dict[str, Any]
ASGIApp = Callable[[Scope, Callable, Callable], Awaitable[None]]


def is_loopback(host: str) -> bool:
    """``127.0.0.1``, ``::1``, ``localhost``: only this machine can connect."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


#: A Host header as RFC 9110 writes it: a name or an IPv4 address, or an IPv6 address in brackets; then a port.
_HOST = re.compile(r"(?:\[(?P<v6>[0-9A-Fa-f:.]+)\]|(?P<name>[A-Za-z0-9._-]+))(?::[0-9]{1,5})?")


def host_name(header: str) -> str | None:
    """``"127.0.0.1:8080"`` → ``"127.0.0.1"``, ``"[::1]:8080"`` → ``"::1"``; None when it is not a Host header at all
    (``127.0.0.1:1@evil.com`` names no host a browser would send)."""
    match = _HOST.fullmatch(header)
    if match is None:
        return None
    return match["v6"] or match["name"]


def is_page(method: str, path: str, accept: str) -> bool:
    """A request for the page's files, or a browser opening ``/``: served without the token (no data in them)."""
    if method not in ("GET", "HEAD"):
        return False
    if path == "/":
        return accept.split(",", 1)[0].strip().lower() == "text/html"
    return path == "/live" or (path.startswith("/live/") and "/" not in path[len("/live/"):])


class Guard:
    """The checks above, before the application sees the request; refusals are JSON ``{"error", "status"}``."""

    def __init__(self, app: ASGIApp, token: str | None = None, loopback: bool = True) -> None:
        self.app = app
        self.token = token.encode("utf-8") if token else None
        self.loopback = loopback

    async def __call__(self, scope: Scope, receive: Callable, send: Callable) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        problem = self.problem(scope)
        if problem is None:
            await self.app(scope, receive, send)
            return
        status, message = problem
        body = json.dumps({"error": message, "status": status}).encode()
        headers = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]
        if status == 401:
            headers.append((b"www-authenticate", b'Bearer realm="genom2bip"'))
        await send({"type": "http.response.start", "status": status, "headers": headers})
        await send({"type": "http.response.body", "body": body})

    def problem(self, scope: Scope) -> tuple[int, str] | None:
        """(status, message) when the request is refused, else None."""
        raw: dict[bytes, bytes] = {}
        for k, v in scope.get("headers", []):
            name = k.lower()
            if name in SINGLE and name in raw:
                return 400, f"repeated {SINGLE[name]} header: refused (a request names it once)"
            raw[name] = v
        host = raw.get(b"host", b"").decode("latin-1")
        if host and host_name(host) is None:
            return 400, f"Host {host!r} is not a host name, an address or either with a port: refused"
        if self.loopback and not is_loopback(host_name(host) or ""):
            return 403, (f"Host {host!r} is not this server: a controller on the loopback answers only to "
                         f"{', '.join(LOOPBACK_NAMES)} (a guard against DNS rebinding)")
        origin = raw.get(b"origin")
        if origin is not None and origin.decode("latin-1") != f"http://{host}":
            return 403, (f"cross-site request from Origin {origin.decode('latin-1')!r} refused: only pages of "
                         f"http://{host} may call this interface")
        if self.token is not None and not is_page(scope["method"], scope.get("path", ""),
                                                   raw.get(b"accept", b"").decode("latin-1")):
            given = raw.get(b"authorization", b"")
            scheme, _, value = given.partition(b" ")
            if scheme.lower() != b"bearer" or not hmac.compare_digest(value.strip(), self.token):
                what = "a wrong token" if given else "no token"
                return 401, (f"{what}: this controller requires 'Authorization: Bearer TOKEN' "
                             f"(the client takes it from {TOKEN_ENV})")
        if scope["method"] == "POST":
            given = raw.get(b"content-type")
            kind = (given or b"").decode("latin-1").split(";", 1)[0].strip().lower()
            if kind != "application/json":
                shown = repr(given.decode("latin-1")) if given is not None else "none"
                return 415, (f"Content-Type {shown}: a request that acts must be sent as application/json "
                             "(a guard against cross-site form posts)")
        return None
