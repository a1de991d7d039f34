"""The generated controller running for real: the engine in its own thread, task periods, Python codels, requests.

``Controller`` builds the engine, codel binding and timers of a generated
package and takes requests from any thread; its run (the engine thread) is
runtime.controller.running.  An interaction opening a task's period waits
for the task's deadline, a due period goes first, other interactions fire at
once (runtime.controller.choice).  Reports come from the labels and ports of
the interactions that fired (runtime.controller.meaning, .reports;
docs/runtime.md).
"""
from __future__ import annotations

import threading
from typing import Any, Callable

from runtime.codels import codel_specs
from runtime.controller.binding import Binder
from runtime.controller.choice import Choice
from runtime.controller.codel_times import CodelTimes
from runtime.controller.codels import load_codels, with_c_codels
from runtime.controller.data import Data, PosterValue
from runtime.controller.intake import checked_inputs, request_locals
from runtime.controller.meaning import Meanings, StepInfo
from runtime.controller.monitor import Monitor
from runtime.controller.remote import NO_SUCH_REMOTE, REMOTE_IO, Remotes, remote_outcome
from runtime.controller.reports import Listener, Reports
from runtime.controller.requests import Request, RequestError, Service
from runtime.genom import Throw
from runtime.controller.running import Running
from runtime.controller.timing import MonotonicClock, Timers
from runtime.engine import Engine, Interaction
from runtime.model import Package


class Controller(Running):
    """``Controller(package, root, interface, codels)``: ``start()``/``run()``, ``submit()``, ``wait()``, ``stop()``.

    ``interface`` is the generated package's ``INTERFACE``; ``codels`` a
    codels directory, dotted module name, module or dict (see
    runtime/controller/codels.py).  ``clock`` defaults to the monotonic
    clock (a :class:`~runtime.controller.timing.VirtualClock` runs as fast as
    possible); ``seed`` makes the choice among ready interactions random
    (default: the engine's order); ``keep`` bounds how many ended requests
    are remembered; ``max_queued`` how many requests may wait to be taken
    (beyond, :meth:`submit` answers 429: memory and latency stay bounded);
    ``times`` records how long each codel runs (:meth:`codel_times`).
    """

    def __init__(self, package: Package, root: str, interface: dict[str, Any], codels: Any = None, *,
                 clock: Any = None, seed: int | None = None, keep: int = 10_000, max_queued: int = 1000,
                 times: bool = False) -> None:
        self.interface = interface
        self.types: dict[str, dict[str, Any]] = interface.get("types", {})
        comps = interface["components"]
        self.data = Data(interface)
        self.clock = clock or MonotonicClock()
        self.codels = with_c_codels(load_codels(codels, list(comps)), interface, self.clock)
        self.binder = Binder(interface, self.data, self.codels, codel_specs(package), on_poster=self._poster_written)
        self.binder.times = CodelTimes(interface) if times else None
        self.remotes = Remotes(interface, self.call_remote)
        self.binder.remotes = self.remotes.handle
        externs: dict[str, Callable] = dict(self.binder.externs())
        externs["request_pending"] = self._pending
        externs["take_request"] = self._take
        self.engine = Engine(package, root, externs)
        self.timers = Timers.of(self.engine.flat, {c["instance"]: c.get("clock_rate_us") for c in comps.values()})
        self.monitor = Monitor.of(self.engine.flat, package)  # the model's observers on this clock (None: none)
        self.services: dict[str, Service] = {
            label: Service(scope, comps[scope.component]["services"][scope.name])
            for label, scope in self.binder.services.items()}
        self.meanings = Meanings(self.engine.flat, interface, self.binder, self.services, self.timers)
        self.choice = Choice(self.engine, self.meanings, seed)
        self._lock = threading.RLock()
        self._wake = threading.Condition(self._lock)
        self._epoch = 0
        self._stopping = False
        self.reports = Reports(self.services, self._lock, keep, self._stamp)
        self.max_queued = max_queued
        self.state: tuple | None = None
        self.steps = 0
        self.status = "ready"  # ready, running, stopped, error
        self.error: str | None = None
        self.started_at: float | None = None
        self._thread: threading.Thread | None = None
        self._firing: Request | None = None  # the request whose step is under way (to say what a stop cut short)
        self._finished = False
        self._threaded = False  # run by start(): in a thread of its own, which may be taken over
        self._then: Callable[[], None] | None = None
        self._limit: int | None = None
        self._end: float | None = None
        self._init_takeover()

    @property
    def requests(self) -> dict[int, Request]:
        """Requests by id: every one not ended yet and the last ``keep`` ended ones."""
        return self.reports.requests

    @property
    def keep(self) -> int:
        return self.reports.keep

    @property
    def listeners(self) -> list[Listener]:
        return self.reports.listeners

    def info(self, inter: Interaction) -> StepInfo:
        """The run-time meaning of ``inter`` (cached by its index)."""
        return self.meanings.info(inter)

    def _stamp(self) -> tuple[int, float]:
        """The step and the time since the run started, for a report."""
        now = self.clock.now()
        return self.steps, round(now - self.started_at, 6) if self.started_at is not None else 0.0

    # -- requests (any thread) -------------------------------------------------------------------------
    def service(self, component: str, service: str) -> Service:
        comps = self.interface["components"]
        if component not in comps:
            raise RequestError(404, f"no component {component!r} (components: {', '.join(comps)})")
        svc = self.services.get(f"{component}.{service}")
        if svc is None:
            names = ", ".join(comps[component]["services"])
            raise RequestError(404, f"component {component} has no service {service!r} (services: {names})")
        return svc

    def submit(self, component: str, service: str, inputs: dict[str, Any] | None = None) -> Request:
        """Queue a request; raises :class:`RequestError` (404 unknown, 422 bad parameters, 409 busy, 503 stopped)."""
        svc = self.service(component, service)
        values = checked_inputs(svc, {} if inputs is None else inputs, self.types, self.data.ids[svc.scope.component])
        local = request_locals(svc, values, self.types)
        with self._lock:
            if self.status in ("stopped", "error") or self._stopping:
                state = f"has stopped on an error ({self.error})" if self.error else \
                    "is stopping" if self.status in ("ready", "running") else "has stopped"
                raise RequestError(503, f"the controller {state}; request to {svc.label} not accepted")
            if not svc.reentrant and not svc.renews:
                busy = svc.busy_with()
                if busy is not None:
                    others = self.meanings.interrupters.get(svc.label, [])
                    hint = f" or interrupt it ({', '.join(others)})" if others else ""
                    raise RequestError(409, f"{svc.label} is busy with request {busy.id} ({busy.status}): an activity "
                                            f"takes one request at a time; wait for its report{hint}")
            waiting = sum(len(s.queue) for s in self.services.values())
            if waiting >= self.max_queued and svc.queue:  # a service with none waiting always gets one (a Stop)
                raise RequestError(429, f"{waiting} requests are waiting to be taken: request to {svc.label} "
                                        "not accepted, send it again later")
            req = self.reports.new(component, service, values, local)
            svc.queue.append(req)
            self._epoch += 1
            self._wake.notify()
        return req

    def call_remote(self, component: str, remote: str, inputs: dict[str, Any]) -> dict[str, Any]:
        """A codel of ``component`` calls its remote ``remote``: a request to the service that serves it, the
        engine going on without the codel until the request's final report; its outputs, or :class:`Throw`."""
        target = self.remotes.target(component, remote)
        if target is None:
            raise Throw(NO_SUCH_REMOTE, what=self.remotes.why_unconnected(component, remote))
        label = f"{target[0]}.{target[1]}"
        if not self.can_let_go():
            raise Throw(REMOTE_IO, what=f"{label}: a remote call needs the controller's engine in a thread of its "
                                        "own (Controller.start()), which it leaves while the codel waits")
        try:
            req = self.submit(target[0], target[1], inputs)
        except RequestError as err:
            raise Throw(REMOTE_IO, what=f"{label} did not accept the request ({err.status}): {err}") from None
        self.let_go()
        with self._lock:
            self.reports.done.wait_for(lambda: req.final is not None or self._stopping)
        return remote_outcome(req.final, label)

    def get(self, request_id: int) -> Request:
        """The request ``request_id``; :class:`RequestError` 404 when it is unknown or forgotten."""
        return self.reports.get(request_id)

    def snapshot(self, request_id: int) -> dict[str, Any]:
        """The request as JSON data, consistent even while the engine thread reports on it."""
        req = self.get(request_id)
        with self._lock:
            return req.as_json()

    def wait(self, request_id: int, timeout: float | None = None) -> Request:
        """Block until the request has its final report (or ``timeout`` seconds); returns it either way."""
        req = self.get(request_id)
        with self._lock:
            self.reports.done.wait_for(lambda: req.final is not None, timeout)
        return req

    def poster(self, component: str, port: str) -> PosterValue:
        comps = self.interface["components"]
        if component not in comps:
            raise RequestError(404, f"no component {component!r} (components: {', '.join(comps)})")
        try:
            return self.data.poster(component, port)
        except KeyError:
            outs = [p for p, x in comps[component]["ports"].items() if x["direction"] == "out"]
            raise RequestError(404, f"component {component} has no poster {port!r} "
                                    f"(posters: {', '.join(outs) or 'none'})") from None

    def subscribe(self, listener: Listener) -> Callable[[], None]:
        """Call ``listener(event)`` for every report, poster write, overrun and codel error; returns the unsubscribe."""
        return self.reports.subscribe(listener)

    # -- the model's externs (engine thread) ----------------------------------------------------------
    def _pending(self, name: str) -> bool:
        svc = self.services.get(name)
        return svc is not None and bool(svc.queue)

    def _take(self, name: str) -> None:
        svc = self.services.get(name)
        if svc is not None and svc.queue:
            with self._lock:
                taken = svc.queue.popleft()
                if svc.current is not None and svc.current.final is None:  # it interrupts the running one
                    svc.incoming = taken
                else:
                    svc.current = taken
            self._taken = (svc, taken)  # a step fired again after a detached codel takes it again

    def _poster_written(self, component: str, port: str, value: PosterValue) -> None:
        if self.reports.listeners:
            self.reports.emit({"event": "poster", **value.as_json()})

    def codel_times(self) -> dict[str, Any] | None:
        """How long each codel ran so far (runtime.controller.codel_times), None unless made with ``times``."""
        times = self.binder.times
        return times.as_json("virtual" if self.clock.virtual else "real") if times is not None else None

    # -- what the server shows ------------------------------------------------------------------------------
    def summary(self) -> dict[str, Any]:
        """The controller at a glance: status, steps, uptime, requests by status, where its codels come from."""
        counts: dict[str, int] = {}
        with self._lock:
            for req in self.requests.values():
                counts[req.status] = counts.get(req.status, 0) + 1
        now = self.clock.now()
        status, error = self.status, self.error
        if status == "running" and self._thread is not None and not self._thread.is_alive():
            status, error = "error", error or "the engine thread has died"
        uptime = round(now - self.started_at, 3) if self.started_at is not None else 0.0
        startup = self.timers.startup
        return {"system": self.interface.get("system"), "status": status, "error": error, "steps": self.steps,
                "uptime": uptime, "startup_ms": round(startup * 1e3, 1) if startup is not None else None,
                "requests": counts, "codels": {"source": self.codels.where or None, "missing": self.binder.missing}}
