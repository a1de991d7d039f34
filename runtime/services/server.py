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
    GET  /live/                                the live page (a browser opening / is sent there)
    GET  /pictures/level.svg, /pictures/modules/{m}.svg   the model's pictures, for the page
    GET  /scene                                the world of a mission run with --view

The engine runs in its own thread; it tells the event loop about reports
through ``loop.call_soon_threadsafe``, the only crossing between the two
(runtime.services.hub).  The routes are in runtime.services.routes, one
module per resource group; reading request bodies and parameters within
bounds in runtime.services.intake; this module assembles the application and
serves it with uvicorn, stopping the controller cleanly.
"""
from __future__ import annotations

import asyncio
import contextlib
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
from runtime.services.protocol import MAX_CONNECTIONS, READ_TIMEOUT, guarded
from runtime.services.routes import routes

__all__ = ["INTERRUPT_GRACE", "MAX_BODY", "MAX_WAIT", "STOP_GRACE", "ServiceServer", "create_app"]

#: On a stop: how long the codel under way may take to return (s), then how long after it is interrupted.
STOP_GRACE = 2.0
INTERRUPT_GRACE = 1.0
#: At the stop, a connection still sending its last events is cut after this long (s) without progress, and all
#: after FLUSH_LIMIT: a client that does not read cannot hold the stop, one that reads gets its final reports.
FLUSH_IDLE = 1.0
FLUSH_LIMIT = 10.0
#: The kernel send buffer asked for at the stop (bytes): what is in it still reaches the client after the exit.
HANDOVER_BUFFER = 4 << 20


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


def create_app(controller: Controller, token: str | None = None, loopback: bool = True,
               scene: dict | None = None) -> Starlette:
    """The ASGI application serving ``controller``, behind its :class:`~runtime.services.guard.Guard`.

    Its routes (runtime.services.routes) find the controller and the event
    hub in ``app.state``; every error becomes a JSON answer.  ``scene``: the
    world a mission shows on the live page (``/scene``), if any.
    """
    app = Starlette(routes=routes(), middleware=[Middleware(Guard, token=token, loopback=loopback)],
                    exception_handlers={RequestError: on_request_error, HTTPException: on_http_error,
                                        Exception: on_crash})
    app.state.controller = controller
    app.state.hub = Hub()
    app.state.scene = scene
    app.state.structure = None  # the live page's pictures: derived from the model on first use, then kept
    app.state.pictures = {}
    return app


class _Uvicorn(uvicorn.Server):
    """uvicorn, connecting the event hub to the controller while it serves, and ending both on a stop.

    This is done in the server's own startup and shutdown rather than in an
    ASGI lifespan task: on Ctrl-C uvicorn cancels a pending lifespan task and
    logs a traceback for it, which a clean stop must not print.  The shutdown
    ends the controller first (its final reports go out over every stream and
    long poll), then the streams, then the connections.  SIGTERM stops it as
    Ctrl-C does; a second one calls ``on_force(signal)`` (the ``run``
    command exits at once).
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

    async def _flush(self) -> None:
        """Let streams and answers still under way send their last bytes; cut a connection that makes no progress.

        Each connection's kernel buffer is raised first: what is in it is
        delivered even after the process has exited, so that a client that
        reads slowly still gets its final reports.
        """
        loop = asyncio.get_running_loop()
        connections = self.server_state.connections
        for connection in list(connections):
            sock = connection.transport.get_extra_info("socket") if connection.transport else None
            with contextlib.suppress(OSError, AttributeError):
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, HANDOVER_BUFFER)
        start = loop.time()
        seen: dict[object, tuple[tuple, float]] = {}  # connection -> (what it had left, since when)
        while True:
            now = loop.time()
            busy = [c for c in list(connections) if _sending(c)]
            progress = sum(sub.cursor for sub in self.hub.subscribers)  # streams that wrote without waiting
            stuck = [c for c in busy if _stalled(c, seen, now, progress)]
            if not busy or len(stuck) == len(busy) or now - start > FLUSH_LIMIT:
                break
            await asyncio.sleep(0.02)
        for connection in busy:
            connection.transport.abort()  # a client that does not read: it must not hold the stop

    @contextlib.contextmanager
    def capture_signals(self):
        """SIGINT and SIGTERM stop the server (uvicorn's own would raise the signal again once stopped)."""
        if threading.current_thread() is not threading.main_thread():
            yield
            return
        previous = {sig: signal.signal(sig, self.handle_exit) for sig in (signal.SIGINT, signal.SIGTERM)}
        try:
            yield
        finally:
            for sig, handler in previous.items():
                signal.signal(sig, handler)

    def handle_exit(self, sig, frame) -> None:
        if self.should_exit and self.on_force is not None:
            self.on_force(sig)
        self.on_exit()
        super().handle_exit(sig, frame)


def _sending(connection) -> bool:
    """A connection with an answer still under way, or bytes not yet handed to the kernel."""
    transport = getattr(connection, "transport", None)
    if transport is None or transport.is_closing():
        return False
    cycle = getattr(connection, "cycle", None)
    return (cycle is not None and not cycle.response_complete) or transport.get_write_buffer_size() > 0


def _stalled(connection, seen: dict, now: float, progress: int) -> bool:
    """Whether ``connection`` has had the same bytes left to send, and no stream moved, for :data:`FLUSH_IDLE` s."""
    left = (connection.transport.get_write_buffer_size(), id(connection.cycle), progress)
    last = seen.get(connection)
    if last is None or last[0] != left:
        seen[connection] = (left, now)
        return False
    return now - last[1] >= FLUSH_IDLE


class ServiceServer:
    """The HTTP server of a controller on 127.0.0.1: ``port=0`` picks a free port (see :attr:`url`).

    ``host`` another address than the loopback only with a ``token``
    (:class:`ValueError` otherwise): anyone who reaches the port could
    command the robot.
    """

    def __init__(self, controller: Controller, port: int = 0, host: str = "127.0.0.1",
                 token: str | None = None, read_timeout: float = READ_TIMEOUT,
                 max_connections: int = MAX_CONNECTIONS, scene: dict | None = None) -> None:
        loopback = is_loopback(host)
        if not loopback and not token:
            raise ValueError(f"listening on {host} lets other machines command the robot: give a token "
                             f"(--token-file or {TOKEN_ENV}) that every client must send")
        self.controller = controller
        self.app = create_app(controller, token, loopback, scene)
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
                                timeout_graceful_shutdown=3, timeout_keep_alive=30,
                                http=guarded(read_timeout, max_connections))
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
