"""The services interface: JSON over HTTP on 127.0.0.1, in the spirit of genomix (Starlette on uvicorn).

Routes (docs/runtime.md has the shapes; ``/openapi.json`` describes them):

    GET  /                                     the controller: status, steps, requests by status, codels
    GET  /components                           components with their services and posters
    GET  /components/{c}                       one component: services with parameter schemas, ports, tasks
    GET  /components/{c}/services/{s}          one service
    POST /components/{c}/services/{s}          send a request (JSON object of inputs) -> 202 {"id": ...}
    GET  /requests                             recent requests (?status=running&limit=100)
    GET  /requests/{id}?wait=SECONDS           a request and its reports; waits for the final one
    GET  /components/{c}/ports/{p}             a poster's last value
    GET  /events?types=report,poster           server-sent events: reports, poster writes, overruns,
                                               codel errors, observers
    GET  /tasks                                periods, lateness and overruns of every task
    GET  /openapi.json                         OpenAPI 3.1 description

The engine runs in its own thread; it tells the event loop about reports
through ``loop.call_soon_threadsafe``, the only crossing between the two
(runtime.services.hub).  The routes are in runtime.services.routes, one
module per resource group; reading request bodies and parameters within
bounds in runtime.services.intake; this module assembles the application and
serves it with uvicorn, stopping the controller cleanly.
"""
from __future__ import annotations

import asyncio
import signal
import socket
import threading
import time

import uvicorn
from starlette.applications import Starlette
from starlette.exceptions import HTTPException
from starlette.middleware import Middleware
from starlette.requests import Request as HttpRequest
from starlette.responses import Response

from runtime.controller import Controller, RequestError
from runtime.services.guard import TOKEN_ENV, Guard, is_loopback
from runtime.services.hub import Hub
from runtime.services.intake import MAX_BODY, MAX_WAIT
from runtime.services.jsonio import error
from runtime.services.routes import routes

__all__ = ["INTERRUPT_GRACE", "MAX_BODY", "MAX_WAIT", "STOP_GRACE", "ServiceServer", "create_app"]

#: On a stop: how long the codel under way may take to return (s), then how long after it is interrupted.
STOP_GRACE = 2.0
INTERRUPT_GRACE = 1.0
#: How long event streams and long polls get to send their last events (s) before their connections are cut.
FLUSH_GRACE = 0.5


async def on_request_error(request: HttpRequest, exc: RequestError) -> Response:
    return error(exc.status, exc.message)


async def on_http_error(request: HttpRequest, exc: HTTPException) -> Response:
    if exc.status_code == 404:
        return error(404, f"no route {request.url.path} (see /openapi.json)")
    if exc.status_code == 405:
        return error(405, f"{request.method} is not allowed on {request.url.path}")
    return error(exc.status_code, str(exc.detail))


async def on_crash(request: HttpRequest, exc: Exception) -> Response:
    return error(500, f"internal error: {type(exc).__name__}: {exc}")


def create_app(controller: Controller, token: str | None = None, loopback: bool = True) -> Starlette:
    """The ASGI application serving ``controller``, behind its :class:`~runtime.services.guard.Guard`.

    Its routes (runtime.services.routes) find the controller and the event
    hub in ``app.state``; every error becomes a JSON answer.
    """
    app = Starlette(routes=routes(), middleware=[Middleware(Guard, token=token, loopback=loopback)],
                    exception_handlers={RequestError: on_request_error, HTTPException: on_http_error,
                                        Exception: on_crash})
    app.state.controller = controller
    app.state.hub = Hub()
    return app


class _Uvicorn(uvicorn.Server):
    """uvicorn, connecting the event hub to the controller while it serves, and ending both on a stop.

    This is done in the server's own startup and shutdown rather than in an
    ASGI lifespan task: on Ctrl-C uvicorn cancels a pending lifespan task and
    logs a traceback for it, which a clean stop must not print.  The shutdown
    ends the controller first (its final reports go out over every stream and
    long poll), then the streams, then the connections.  A second Ctrl-C
    calls ``on_force`` (the ``run`` command exits at once).
    """

    def __init__(self, config: uvicorn.Config, controller: Controller, hub: "Hub", on_exit) -> None:
        super().__init__(config)
        self.controller = controller
        self.hub = hub
        self.on_exit = on_exit
        self.on_force = None
        self._unsubscribe = None

    async def startup(self, sockets=None) -> None:
        self.hub.loop = asyncio.get_running_loop()
        self._unsubscribe = self.controller.subscribe(self.hub.listener)
        await super().startup(sockets=sockets)

    async def shutdown(self, sockets=None) -> None:
        try:
            await self._stop_controller()
            self.hub.close()
            await self._flush()
            await super().shutdown(sockets=sockets)
        finally:
            if self._unsubscribe is not None:
                self._unsubscribe()
                self._unsubscribe = None
            self.hub.close()

    async def _stop_controller(self) -> None:
        """End the run, interrupting a codel that does not return; its final reports reach the hub before it closes."""
        c = self.controller
        loop = asyncio.get_running_loop()
        c.stop(timeout=0)
        if c.alive():
            await loop.run_in_executor(None, c.stop, STOP_GRACE)
        if c.alive() and c.interrupt_codel() is not None:
            await loop.run_in_executor(None, c.stop, INTERRUPT_GRACE)
        if c.alive():
            c.abandon(f"{c.busy() or 'the engine thread'} did not return within "
                      f"{STOP_GRACE + INTERRUPT_GRACE:g} s of the stop: abandoned")
        await asyncio.sleep(0)  # the reports the engine thread handed over are published before the hub closes

    async def _flush(self) -> None:
        """Give streams and long polls a moment to send their last events, then cut the connections still busy."""
        loop = asyncio.get_running_loop()
        deadline = loop.time() + FLUSH_GRACE
        while self.hub.streams and loop.time() < deadline:
            await asyncio.sleep(0.02)
        for connection in list(self.server_state.connections):
            cycle = getattr(connection, "cycle", None)
            transport = getattr(connection, "transport", None)
            if cycle is not None and not cycle.response_complete and transport is not None:
                transport.abort()  # a client that does not read: it must not hold the stop

    def handle_exit(self, sig, frame) -> None:
        if self.should_exit and sig == signal.SIGINT and self.on_force is not None:
            self.on_force()
        self.on_exit()
        super().handle_exit(sig, frame)


class ServiceServer:
    """The HTTP server of a controller on 127.0.0.1: ``port=0`` picks a free port (see :attr:`url`).

    ``host`` another address than the loopback only with a ``token``
    (:class:`ValueError` otherwise): anyone who reaches the port could
    command the robot.
    """

    def __init__(self, controller: Controller, port: int = 0, host: str = "127.0.0.1",
                 token: str | None = None) -> None:
        loopback = is_loopback(host)
        if not loopback and not token:
            raise ValueError(f"listening on {host} lets other machines command the robot: give a token "
                             f"(--token or {TOKEN_ENV}) that every client must send")
        self.controller = controller
        self.app = create_app(controller, token, loopback)
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        self.socket = socket.socket(family, socket.SOCK_STREAM)
        self.socket.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        # accepted connections inherit it; without it a response written in two parts waits for a delayed ACK
        self.socket.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.socket.bind((host, port))
        self.socket.listen(2048)  # clients may connect as soon as the URL is printed; they wait in the backlog
        self.port = self.socket.getsockname()[1]
        shown = "127.0.0.1" if host in ("0.0.0.0", "localhost") else f"[{host}]" if ":" in host else host
        self.url = f"http://{shown}:{self.port}"
        config = uvicorn.Config(self.app, log_level="warning", access_log=False, lifespan="off",
                                timeout_graceful_shutdown=3, timeout_keep_alive=30)
        self.server = _Uvicorn(config, controller, self.app.state.hub, self._exiting)
        self._thread: threading.Thread | None = None

    def _exiting(self) -> None:
        """A stop was asked for: the controller ends after its current step (the shutdown waits for it)."""
        self.controller.stop(timeout=0)

    def serve(self) -> None:
        """Serve in this thread until Ctrl-C / SIGTERM (the main thread) or :meth:`stop`."""
        self.server.run(sockets=[self.socket])

    def start(self, timeout: float = 10.0) -> "ServiceServer":
        """Serve in a thread of its own; returns once the server accepts connections."""
        self._thread = threading.Thread(target=self.serve, name="services-http", daemon=True)
        self._thread.start()
        deadline = time.monotonic() + timeout
        while not self.server.started and self._thread.is_alive() and time.monotonic() < deadline:
            time.sleep(0.01)
        if not self.server.started:
            raise RuntimeError("the services interface did not start")
        return self

    def stop(self, timeout: float = 10.0) -> None:
        """Stop serving (event streams end); the controller is told to stop too."""
        self._exiting()
        self.server.should_exit = True
        if self._thread is not None:
            self._thread.join(timeout)
