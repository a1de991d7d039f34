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
through ``loop.call_soon_threadsafe``, the only crossing between the two.
"""
from __future__ import annotations

import asyncio
import json
import math
import signal
import socket
import threading
import time
from typing import Any

import uvicorn
from starlette.applications import Starlette
from starlette.exceptions import HTTPException
from starlette.middleware import Middleware
from starlette.requests import ClientDisconnect, Request as HttpRequest
from starlette.responses import Response, StreamingResponse
from starlette.routing import Route

from runtime.controller import Controller, RequestError
from runtime.services.guard import TOKEN_ENV, Guard, is_loopback
from runtime.services.openapi import openapi
from runtime.services.views import component_view, components_view, service_view

#: Longest a client may wait for a report in one HTTP call (s); it asks again for longer waits.
MAX_WAIT = 60.0
#: Largest request body accepted (bytes): refused as it streams in, so memory stays bounded.
MAX_BODY = 1 << 20
#: Deepest nesting of arrays and objects accepted in a request body.
MAX_DEPTH = 64
#: Events kept for a slow event-stream client before it is cut off.
QUEUE_SIZE = 10_000
EVENT_KINDS = ("report", "poster", "overrun", "codel_error", "controller", "observer")
#: On a stop: how long the codel under way may take to return (s), then how long after it is interrupted.
STOP_GRACE = 2.0
INTERRUPT_GRACE = 1.0
#: How long event streams and long polls get to send their last events (s) before their connections are cut.
FLUSH_GRACE = 0.5


def _finite(value: Any) -> Any:
    """JSON has no NaN or infinity: they become null."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    return value


def dumps(data: Any) -> str:
    try:
        return json.dumps(data, allow_nan=False)
    except ValueError:
        return json.dumps(_finite(data), allow_nan=False)


class JSONResponse(Response):
    media_type = "application/json"

    def render(self, content: Any) -> bytes:
        return dumps(content).encode()


def error(status: int, message: str) -> JSONResponse:
    return JSONResponse({"error": message, "status": status}, status_code=status)


async def read_body(request: HttpRequest, what: str) -> bytes:
    """The body, read as it streams in and refused (413) past :data:`MAX_BODY` bytes, whatever the client says."""
    declared = request.headers.get("content-length")
    if declared is not None:
        if not declared.isdigit():
            raise RequestError(400, f"Content-Length {declared!r} is not a number of bytes")
        if int(declared) > MAX_BODY:
            raise RequestError(413, f"request body of {declared} bytes to {what}: at most {MAX_BODY} accepted")
    chunks: list[bytes] = []
    size = 0
    try:
        async for chunk in request.stream():
            size += len(chunk)
            if size > MAX_BODY:
                raise RequestError(413, f"request body to {what} longer than {MAX_BODY} bytes: refused")
            chunks.append(chunk)
    except ClientDisconnect:
        raise RequestError(400, f"the client disconnected before sending the whole body to {what}") from None
    return b"".join(chunks)


def _depth(value: Any) -> int:
    """How deeply arrays and objects nest in ``value`` (without recursion: the value may come from anyone)."""
    deepest, todo = 0, [(value, 1)]
    while todo:
        v, d = todo.pop()
        if isinstance(v, (dict, list)):
            deepest = max(deepest, d)
            if d <= MAX_DEPTH:
                todo.extend((x, d + 1) for x in (v.values() if isinstance(v, dict) else v))
    return deepest


def parse_inputs(body: bytes, what: str) -> Any:
    """A request body as JSON data: 400 naming what is wrong, for anything the JSON parser or its limits refuse."""
    try:
        text = body.decode()
    except UnicodeDecodeError as err:
        raise RequestError(400, f"the body of the request to {what} is not UTF-8: {err}") from None
    if not text.strip():
        return {}
    try:
        value = json.loads(text)
    except json.JSONDecodeError as err:
        raise RequestError(400, f"malformed JSON in the body of the request to {what}: {err}") from None
    except RecursionError:
        raise RequestError(400, f"the body of the request to {what} nests arrays or objects too deeply "
                                f"(at most {MAX_DEPTH} levels)") from None
    except ValueError as err:  # e.g. an integer of more than 4300 digits
        raise RequestError(400, f"unreadable JSON in the body of the request to {what}: {err}") from None
    if _depth(value) > MAX_DEPTH:
        raise RequestError(400, f"the body of the request to {what} nests arrays or objects too deeply "
                                f"(at most {MAX_DEPTH} levels)")
    if value is None:
        raise RequestError(422, f"the parameters of {what} must be a JSON object, not null (send {{}} or "
                                "nothing for the defaults)")
    return value


class Subscriber:
    """One event-stream client: a bounded queue of events of the kinds it asked for."""

    def __init__(self, kinds: set[str]) -> None:
        self.kinds = kinds
        self.queue: asyncio.Queue = asyncio.Queue(maxsize=QUEUE_SIZE)


class Hub:
    """Lives in the event loop: wakes the clients waiting for a request's final report, feeds the event streams."""

    def __init__(self) -> None:
        self.waiters: dict[int, list[asyncio.Future]] = {}
        self.subscribers: set[Subscriber] = set()
        self.streams = 0  # event streams still sending
        self.loop: asyncio.AbstractEventLoop | None = None
        self.closed = False

    def listener(self, event: dict[str, Any]) -> None:
        """Called in the engine thread: hand the event to the loop."""
        loop = self.loop
        if loop is not None and not self.closed:
            try:
                loop.call_soon_threadsafe(self.publish, event)
            except RuntimeError:  # the loop has closed
                pass

    def publish(self, event: dict[str, Any]) -> None:
        if event.get("event") == "report" and event.get("final"):
            for fut in self.waiters.pop(event["request"], []):
                if not fut.done():
                    fut.set_result(None)
        for sub in list(self.subscribers):
            if event["event"] not in sub.kinds:
                continue
            try:
                sub.queue.put_nowait(event)
            except asyncio.QueueFull:
                self.subscribers.discard(sub)
                while not sub.queue.empty():
                    sub.queue.get_nowait()
                sub.queue.put_nowait({"event": "overflow", "message": f"more than {QUEUE_SIZE} events unread: "
                                                                       "this stream is closed"})
                sub.queue.put_nowait(None)

    def close(self) -> None:
        """End every event stream and long poll (the server is stopping)."""
        self.closed = True
        for sub in list(self.subscribers):
            try:
                sub.queue.put_nowait(None)
            except asyncio.QueueFull:
                pass
        self.subscribers.clear()
        for futs in self.waiters.values():
            for fut in futs:
                if not fut.done():
                    fut.set_result(None)
        self.waiters.clear()


def create_app(controller: Controller, token: str | None = None, loopback: bool = True) -> Starlette:
    """The ASGI application serving ``controller``, behind its :class:`~runtime.services.guard.Guard`."""
    hub = Hub()
    interface = controller.interface

    def request_id(text: str) -> int:
        try:
            return int(text)
        except ValueError:
            raise RequestError(400, f"request id {text!r} is not a number") from None

    def wait_time(request: HttpRequest) -> float | None:
        text = request.query_params.get("wait")
        if text is None:
            return None
        try:
            value = float(text) if text not in ("", "true") else MAX_WAIT
        except ValueError:
            raise RequestError(400, f"wait={text!r}: a number of seconds expected") from None
        if not value >= 0:
            raise RequestError(400, f"wait={text!r}: a number of seconds >= 0 expected")
        return min(value, MAX_WAIT)

    async def wait_final(rid: int, timeout: float) -> None:
        req = controller.get(rid)
        if req.final is not None or timeout <= 0 or hub.closed:
            return
        fut = asyncio.get_running_loop().create_future()
        hub.waiters.setdefault(rid, []).append(fut)
        try:
            await asyncio.wait_for(fut, timeout)
        except asyncio.TimeoutError:
            pass
        finally:
            futs = hub.waiters.get(rid)
            if futs is not None and fut in futs:
                futs.remove(fut)
                if not futs:
                    del hub.waiters[rid]

    async def index(request: HttpRequest) -> Response:
        return JSONResponse(controller.summary() | {"links": {
            "components": "/components", "requests": "/requests", "events": "/events", "tasks": "/tasks",
            "openapi": "/openapi.json"}})

    async def components(request: HttpRequest) -> Response:
        return JSONResponse(components_view(interface))

    async def component(request: HttpRequest) -> Response:
        c = request.path_params["component"]
        if c not in interface["components"]:
            raise RequestError(404, f"no component {c!r} (components: {', '.join(interface['components'])})")
        return JSONResponse(component_view(interface, c))

    async def service(request: HttpRequest) -> Response:
        c, s = request.path_params["component"], request.path_params["service"]
        controller.service(c, s)
        if request.method == "GET":
            return JSONResponse(service_view(interface, c, s))
        inputs = parse_inputs(await read_body(request, f"{c}.{s}"), f"{c}.{s}")
        timeout = wait_time(request)
        req = controller.submit(c, s, inputs)
        if timeout is None:
            return JSONResponse({"id": req.id, "status": "queued", "url": f"/requests/{req.id}"}, status_code=202,
                                headers={"Location": f"/requests/{req.id}"})
        await wait_final(req.id, timeout)
        return JSONResponse(controller.snapshot(req.id))

    async def requests_list(request: HttpRequest) -> Response:
        status = request.query_params.get("status")
        text = request.query_params.get("limit", "100")
        limit = int(text) if text.isdigit() and len(text) < 10 else 0
        if limit < 1:
            raise RequestError(400, f"limit={text!r}: a number of requests from 1 to 999999999 expected")
        ids = sorted(controller.requests, reverse=True)
        rows = []
        for rid in ids:
            req = controller.requests.get(rid)
            if req is None or (status and req.status != status):
                continue
            rows.append({"id": req.id, "component": req.component, "service": req.service, "status": req.status})
            if len(rows) >= limit:
                break
        return JSONResponse(rows)

    async def request_one(request: HttpRequest) -> Response:
        rid = request_id(request.path_params["id"])
        controller.get(rid)
        timeout = wait_time(request)
        if timeout:
            await wait_final(rid, timeout)
        return JSONResponse(controller.snapshot(rid))

    async def poster(request: HttpRequest) -> Response:
        value = controller.poster(request.path_params["component"], request.path_params["port"])
        return JSONResponse(value.as_json())

    async def tasks(request: HttpRequest) -> Response:
        return JSONResponse(controller.timers.stats())

    async def spec(request: HttpRequest) -> Response:
        return JSONResponse(openapi(interface))

    async def events(request: HttpRequest) -> Response:
        wanted = request.query_params.get("types")
        kinds = set(EVENT_KINDS) if not wanted else set(wanted.split(","))
        unknown = kinds - set(EVENT_KINDS)
        if unknown:
            raise RequestError(400, f"unknown event type(s) {', '.join(sorted(unknown))} "
                                    f"(types: {', '.join(EVENT_KINDS)})")
        sub = Subscriber(kinds)
        hub.subscribers.add(sub)

        async def stream():
            hub.streams += 1
            try:
                yield f"event: hello\ndata: {dumps(controller.summary())}\n\n"
                while True:
                    try:
                        event = await asyncio.wait_for(sub.queue.get(), 15.0)
                    except asyncio.TimeoutError:
                        yield ": keep-alive\n\n"
                        continue
                    if event is None:
                        break
                    yield f"event: {event['event']}\ndata: {dumps(event)}\n\n"
            finally:
                hub.subscribers.discard(sub)
                hub.streams -= 1

        return StreamingResponse(stream(), media_type="text/event-stream",
                                 headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"})

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

    routes = [
        Route("/", index),
        Route("/openapi.json", spec),
        Route("/components", components),
        Route("/components/{component}", component),
        Route("/components/{component}/services/{service}", service, methods=["GET", "POST"]),
        Route("/components/{component}/ports/{port}", poster),
        Route("/requests", requests_list),
        Route("/requests/{id}", request_one),
        Route("/events", events),
        Route("/tasks", tasks),
    ]
    app = Starlette(routes=routes, middleware=[Middleware(Guard, token=token, loopback=loopback)],
                    exception_handlers={RequestError: on_request_error, HTTPException: on_http_error,
                                        Exception: on_crash})
    app.state.hub = hub
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
