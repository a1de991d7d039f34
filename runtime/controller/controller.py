"""The generated controller running for real: the engine in its own thread, task periods, Python codels, requests.

Execution uses the engine's own step (``enabled`` then ``fire``), the same
functions the explorer branches on; what real time adds is only *which*
enabled interaction fires and *when*: an interaction opening a task's period
waits for the task's deadline, a due period goes first, other interactions
fire at once, and when nothing may fire yet the thread sleeps until the next
deadline or until a request arrives.  Reports come from the labels and ports
of the interactions that fired (docs/runtime.md).
"""
from __future__ import annotations

import ctypes
import gc
import sys
import threading
from typing import Any, Callable

from runtime.codels import codel_specs
from runtime.controller.binding import Binder, CodelInterrupted
from runtime.controller.choice import Choice
from runtime.controller.codels import load_codels
from runtime.controller.data import Data, PosterValue
from runtime.controller.intake import checked_inputs, request_locals
from runtime.controller.meaning import Meanings, StepInfo
from runtime.controller.monitor import Monitor
from runtime.controller.reports import Listener, Reports
from runtime.controller.requests import Request, RequestError, Service
from runtime.controller.timing import MonotonicClock, Timers
from runtime.engine import Engine, Interaction, ModelError
from runtime.model import Package

#: The interpreter's switch interval while the engine thread runs (s): a thread woken for a period gets the
#: interpreter back within about this long, even while the services interface is busy (docs/runtime.md).
SWITCH_INTERVAL = 0.001


class Controller:
    """``Controller(package, root, interface, codels)``: ``start()``/``run()``, ``submit()``, ``wait()``, ``stop()``.

    ``interface`` is the generated package's ``INTERFACE``; ``codels`` a
    codels directory, dotted module name, module or dict (see
    runtime/controller/codels.py).  ``clock`` defaults to the monotonic
    clock (a :class:`~runtime.controller.timing.VirtualClock` runs as fast as
    possible); ``seed`` makes the choice among ready interactions random
    (default: the engine's order); ``keep`` bounds how many ended requests
    are remembered; ``max_queued`` how many requests may wait to be taken
    (beyond, :meth:`submit` answers 429: memory and latency stay bounded).
    """

    def __init__(self, package: Package, root: str, interface: dict[str, Any], codels: Any = None, *,
                 clock: Any = None, seed: int | None = None, keep: int = 10_000, max_queued: int = 1000) -> None:
        self.interface = interface
        self.types: dict[str, dict[str, Any]] = interface.get("types", {})
        comps = interface["components"]
        self.data = Data(interface)
        self.codels = load_codels(codels, list(comps))
        self.binder = Binder(interface, self.data, self.codels, codel_specs(package), on_poster=self._poster_written)
        externs: dict[str, Callable] = dict(self.binder.externs())
        externs["request_pending"] = self._pending
        externs["take_request"] = self._take
        self.engine = Engine(package, root, externs)
        self.clock = clock or MonotonicClock()
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
            if not svc.reentrant:
                busy = svc.busy_with()
                if busy is not None:
                    others = self.meanings.interrupters.get(svc.label, [])
                    hint = f" or interrupt it ({', '.join(others)})" if others else ""
                    raise RequestError(409, f"{svc.label} is busy with request {busy.id} ({busy.status}): an activity "
                                            f"takes one request at a time; wait for its report{hint}")
            waiting = sum(len(s.queue) for s in self.services.values())
            if waiting >= self.max_queued:
                raise RequestError(429, f"{waiting} requests are waiting to be taken: request to {svc.label} "
                                        "not accepted, send it again later")
            req = self.reports.new(component, service, values, local)
            svc.queue.append(req)
            self._epoch += 1
            self._wake.notify()
        return req

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
                svc.current = svc.queue.popleft()

    def _poster_written(self, component: str, port: str, value: PosterValue) -> None:
        if self.reports.listeners:
            self.reports.emit({"event": "poster", **value.as_json()})

    # -- running ------------------------------------------------------------------------------------------
    def start(self, limit: int | None = None, duration: float | None = None,
              then: Callable[[], None] | None = None) -> None:
        """Run in a thread of its own (``stop()`` ends it); ``then()`` is called when the run has ended."""
        real_time = not self.clock.virtual

        def body() -> None:
            try:
                self.run(limit, duration)
            finally:
                if real_time:
                    gc.unfreeze()  # what the run left behind is collected as usual
                if then is not None:
                    then()
        if real_time:
            sys.setswitchinterval(min(sys.getswitchinterval(), SWITCH_INTERVAL))
            # The model, codels and server are built: while the run lasts, full collections leave them out.  A
            # full collection walking them held the interpreter for up to 100 ms, a period missed by any task.
            gc.freeze()
        self._thread = threading.Thread(target=body, name="bip-controller", daemon=True)
        self._thread.start()

    def stop(self, timeout: float | None = None) -> None:
        """End the run after the step (and codel) under way; waits for the thread when there is one."""
        with self._lock:
            self._stopping = True
            self._wake.notify_all()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout)

    def run(self, limit: int | None = None, duration: float | None = None) -> str:
        """Run until ``stop()``, ``limit`` steps or ``duration`` seconds; returns the final status."""
        clock = self.clock
        self.started_at = t0 = clock.now()
        end = t0 + duration if duration is not None else None
        self.timers.start(t0)
        if self.monitor is not None:
            self.monitor.start(t0)
        self.status = "running"
        try:
            self.state = self.engine.initial_state()
            while True:
                with self._lock:
                    if self._stopping:
                        break
                    epoch = self._epoch
                if limit is not None and self.steps >= limit:
                    break
                now = clock.now()
                if end is not None and now >= end:
                    break
                chosen, info, wake_at = self._choose(now)
                if chosen is not None:
                    self._fire(chosen, info)
                    continue
                if end is not None:
                    wake_at = end if wake_at is None else min(wake_at, end)
                if clock.virtual and wake_at is not None:
                    clock.advance(wake_at)
                    continue
                with self._lock:
                    if self._epoch == epoch and not self._stopping:
                        self._wake.wait(None if wake_at is None else max(0.0, wake_at - clock.now()))
        except ModelError as err:
            self.error = f"model error: {err}"
        except CodelInterrupted:
            pass  # a stuck codel was interrupted just after it returned: the stop it was interrupted for goes on
        except Exception as err:  # noqa: BLE001 - a bug here must not leave requests without a report
            self.error = f"internal error: {type(err).__name__}: {err}"
        except BaseException as err:  # SystemExit, KeyboardInterrupt...: the run ends, reported, never silently
            self.error = f"the engine stopped on {type(err).__name__}{f': {err}' if str(err) else ''}"
            self._finish()
            if threading.current_thread() is threading.main_thread():
                raise
            return self.status
        self._finish()
        return self.status

    def _finish(self) -> None:
        """The run has ended: its status, a final report for every pending request, the ``controller`` event."""
        with self._lock:
            if self._finished:
                return
            self._finished = True
        self.status = "error" if self.error else "stopped"
        self.reports.end_pending(f"the controller stopped ({self.error})" if self.error else "the controller stopped")
        self.reports.emit({"event": "controller", "status": self.status, "steps": self.steps, "error": self.error})

    # -- a stop that the step under way does not let happen ----------------------------------------------
    def busy(self) -> str | None:
        """What the engine thread is doing that a stop waits for: ``codel X of M.S (request N)``, or None."""
        codel = self.binder.running
        if codel is None:
            return None
        scope = self.binder.scope
        req = self._firing
        return f"codel {codel}" + (f" of {scope.label}" if scope is not None else "") + \
            (f" (request {req.id})" if req is not None else "")

    def alive(self) -> bool:
        """The engine thread is still running (False when run without a thread)."""
        return self._thread is not None and self._thread.is_alive()

    def interrupt_codel(self) -> str | None:
        """Raise :class:`CodelInterrupted` in a codel that does not return after a stop; returns what it interrupted.

        It interrupts Python code only: a codel blocked in a system call
        (``time.sleep``, a read) sees it when the call returns.
        """
        what = self.busy()
        thread = self._thread
        if what is None or thread is None or not thread.is_alive() or not self._stopping:
            return None
        ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(thread.ident), ctypes.py_object(CodelInterrupted))
        return what

    def abandon(self, why: str) -> None:
        """Give up on an engine thread that does not stop: every pending request gets its final report now."""
        with self._lock:
            if self.status != "running" or self._finished:
                return
            self._stopping = True
            self.error = why
        self._finish()

    def _choose(self, now: float) -> tuple[Interaction | None, StepInfo | None, float | None]:
        """What fires next and when the next period is due (:class:`~runtime.controller.choice.Choice`)."""
        inter, info, wake_at, answerable = self.choice.choose(self.state, now, self.steps)
        if self.meanings.waits:
            self.reports.held(self.meanings.waits, answerable, self.state)
        return inter, info, wake_at

    def _fire(self, inter: Interaction, info: StepInfo) -> None:
        """Fire ``inter`` with its service's or task's codels bound, then report what it did."""
        b = self.binder
        b.failure = None
        svc = info.service
        req = None
        if svc is not None:
            b.scope = svc.scope
            req = (svc.queue[0] if svc.queue else None) if info.kind in ("trigger", "refuse") else svc.current
            b.locals = req.locals if req is not None else None
        else:
            b.scope, b.locals = info.scope, None
        now = self.clock.now()
        self._firing = req
        self.state = self.engine.fire(self.state, inter)
        self._firing = None
        self.steps += 1
        if info.opens is not None:
            info.opens.open(now)
        if info.closes is not None:
            overrun = info.closes.close(now)
            if overrun is not None:
                self.reports.emit({"event": "overrun", **overrun})
        self.reports.after_step(info, req, b.failure, self.state, self.data)
        if self.monitor is not None:
            for event in self.monitor.step(inter.ports, inter.label, now, self.clock.now()):
                self.reports.emit(event)

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
        return {"system": self.interface.get("system"), "status": status, "error": error, "steps": self.steps,
                "uptime": uptime,
                "requests": counts, "codels": {"source": self.codels.where or None, "missing": self.binder.missing}}
