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
import random
import sys
import threading
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Callable

from runtime.codels import codel_specs
from runtime.controller.binding import Binder, CodelInterrupted, Scope
from runtime.controller.codels import load_codels
from runtime.controller.data import Data, PosterValue, clone, get_path, path_steps, set_path
from runtime.controller.monitor import Monitor
from runtime.controller.requests import FINAL, Request, RequestError, Service
from runtime.controller.schema import completed, problems, zero
from runtime.controller.timing import MonotonicClock, Timer, Timers
from runtime.engine import Engine, Interaction, ModelError
from runtime.model import Package

Listener = Callable[[dict[str, Any]], None]

#: The interpreter's switch interval while the engine thread runs (s): a thread woken for a period gets the
#: interpreter back within about this long, even while the services interface is busy (docs/runtime.md).
SWITCH_INTERVAL = 0.001


@dataclass
class StepInfo:
    """What an interaction means at run time, worked out once per interaction from its ports."""

    # the service port it fires: trigger, refuse, reject, start, exec_<state>, finish, fail, interrupted
    kind: str | None = None
    service: Service | None = None
    scope: Scope | None = None  # a task whose permanent activity runs a codel
    victims: list[Service] = field(default_factory=list)  # services whose activity it aborts
    cancelled: list[Service] = field(default_factory=list)  # services whose accepted request it cancels
    reads: list[Service] = field(default_factory=list)  # services whose status it reads (rules)
    rule: dict[str, str] | None = None  # the connector's @rule annotation
    opens: Timer | None = None
    closes: Timer | None = None
    lazy_exec: str | None = None  # an untimed period: the exec port of its scheduler


def _unstorable(root: dict[str, Any], member: str) -> str | None:
    """Why a value cannot be stored at the ids path ``member`` (None when it can)."""
    steps = path_steps(member)
    if not steps:
        return f"{member!r} is not a member path"
    target: Any = root
    where = ""
    for i, step in enumerate(steps):
        if isinstance(step, int):
            if not isinstance(target, list):
                return f"{where or 'the ids'} is not an array"
            if step >= len(target):
                return f"{where}[{step}] is out of range (length {len(target)})"
        elif not isinstance(target, dict):
            return f"{where or 'the ids'} is not a struct"
        elif step not in target and i < len(steps) - 1:
            return f"no member {step!r} in {where or 'the ids'}"
        where += f"[{step}]" if isinstance(step, int) else (f".{step}" if where else step)
        if i < len(steps) - 1:
            target = target[step]
    return None


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
        self._roles = self._port_roles()
        self._interrupters = self._who_interrupts()
        self._info: dict[int, StepInfo] = {}
        self._connectors = {fc.path: fc for fc in self.engine.flat.connectors}
        self._waits = self._wait_rules()
        self._lock = threading.RLock()
        self._wake = threading.Condition(self._lock)
        self._done = threading.Condition(self._lock)
        self._epoch = 0
        self._stopping = False
        self._rng = random.Random(seed) if seed is not None else None
        self._last: dict[int, int] = {}  # interaction index -> step when it last fired (fair choice)
        self._work: dict[tuple, bool] = {}  # (untimed period, state) -> a codel would run in it
        self.keep = keep
        self.max_queued = max_queued
        self.requests: dict[int, Request] = {}
        self._ended: deque[int] = deque()
        self._next_id = 1
        self.listeners: list[Listener] = []
        self.state: tuple | None = None
        self.steps = 0
        self.status = "ready"  # ready, running, stopped, error
        self.error: str | None = None
        self.started_at: float | None = None
        self._thread: threading.Thread | None = None
        self._firing: Request | None = None  # the request whose step is under way (to say what a stop cut short)
        self._finished = False

    # -- the model's structure ---------------------------------------------------------------------------
    def _port_roles(self) -> dict[str, tuple[Any, str, str]]:
        """Atom port path -> (service or task scope, "control"/"activity"/"task", port name)."""
        by_instance = {svc.spec["instance"]: svc for svc in self.services.values()}
        tasks = {}
        for c, spec in self.interface["components"].items():
            for t, task in spec["tasks"].items():
                tasks[task["instance"]] = self.binder.tasks[f"{c}.{t}"]
        roles: dict[str, tuple[Any, str, str]] = {}
        for fa in self.engine.flat.atoms:
            base, _, part = fa.name.rpartition(".")
            if part in ("control", "activity") and base in by_instance:
                owner, role = by_instance[base], part
            elif part == "permanent" and base in tasks:
                owner, role = tasks[base], "task"
            else:
                continue
            for port in fa.ports:
                roles[f"{fa.name}.{port}"] = (owner, role, port)
            if part == "control" and all(v in (d.name for d in fa.variables) for v in ("done", "ok", "running")):
                owner.status_slots = (fa.slot("done"), fa.slot("ok"), fa.slot("running"))
        return roles

    def _leaves(self, fc) -> list[str]:
        """Atom ports under a connector, through its sub-connectors."""
        flat = self.engine.flat
        return [flat.ports[p].path for p in flat.leaves(fc)]

    def _who_interrupts(self) -> dict[str, list[str]]:
        """Service label -> the services whose start aborts it (the description's and the rules' interruptions)."""
        leaves = self._leaves
        found: dict[str, list[str]] = {}
        for fc in self.engine.flat.connectors:
            if not fc.top:
                continue
            roles = [self._roles.get(p) for p in leaves(fc)]
            starts = [r[0].label for r in roles if r is not None and r[1] == "control" and r[2] == "start"]
            for r in roles:
                if r is not None and r[2] == "abort" and starts and r[0].label not in starts:
                    found.setdefault(r[0].label, []).extend(x for x in starts if x not in found.get(r[0].label, []))
        return found

    def info(self, inter: Interaction) -> StepInfo:
        """The run-time meaning of ``inter`` (cached by its index)."""
        got = self._info.get(inter.index)
        if got is not None:
            return got
        info = StepInfo()
        t = self.timers
        for p in inter.ports:
            if p in t.by_trigger:
                info.opens = t.by_trigger[p]
            elif p in t.by_sleep:
                info.closes = t.by_sleep[p]
            elif p in t.lazy:
                info.lazy_exec = t.lazy[p]
            role = self._roles.get(p)
            if role is None:
                continue
            owner, kind, port = role
            if kind == "task":
                info.scope = owner
            elif port == "abort":
                info.victims.append(owner)
            elif port == "cancel":
                info.cancelled.append(owner)
            elif port == "status":
                info.reads.append(owner)
            else:
                info.service, info.kind = owner, port
        if info.service is not None and inter.connector in self._connectors:
            for a in self._connectors[inter.connector].instance.annotations:
                if a.name == "rule":
                    info.rule = dict(a.arguments)
        if info.service is not None:
            info.victims = [v for v in info.victims if v is not info.service]
        self._info[inter.index] = info
        return info

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
        values = self._inputs(svc, {} if inputs is None else inputs)
        local = {n: clone(spec["initial"]) for n, spec in svc.spec["locals"].items()}
        for p in svc.spec["parameters"]:
            local[p["name"]] = clone(values[p["name"]]) if p["name"] in values else zero(p["schema"], self.types)
        with self._lock:
            if self.status in ("stopped", "error") or self._stopping:
                state = f"has stopped on an error ({self.error})" if self.error else \
                    "is stopping" if self.status in ("ready", "running") else "has stopped"
                raise RequestError(503, f"the controller {state}; request to {svc.label} not accepted")
            if not svc.reentrant:
                busy = svc.busy_with()
                if busy is not None:
                    others = self._interrupters.get(svc.label, [])
                    hint = f" or interrupt it ({', '.join(others)})" if others else ""
                    raise RequestError(409, f"{svc.label} is busy with request {busy.id} ({busy.status}): an activity "
                                            f"takes one request at a time; wait for its report{hint}")
            waiting = sum(len(s.queue) for s in self.services.values())
            if waiting >= self.max_queued:
                raise RequestError(429, f"{waiting} requests are waiting to be taken: request to {svc.label} "
                                        "not accepted, send it again later")
            req = Request(self._next_id, component, service, values, local)
            self._next_id += 1
            self.requests[req.id] = req
            self._report(req, "queued")
            svc.queue.append(req)
            self._epoch += 1
            self._wake.notify()
        return req

    def _inputs(self, svc: Service, inputs: Any) -> dict[str, Any]:
        if not isinstance(inputs, dict):
            raise RequestError(422, f"the parameters of {svc.label} must be a JSON object, not {type(inputs).__name__}")
        params = [p for p in svc.spec["parameters"] if p["direction"] in ("in", "inout")]
        names = [p["name"] for p in params]
        errors = [f"unknown parameter {k!r} (parameters of {svc.label}: {', '.join(names) or 'none'})"
                  for k in inputs if k not in names]
        values: dict[str, Any] = {}
        for p in params:
            name = p["name"]
            if name in inputs:
                value = completed(inputs[name], p.get("default"))
                errors += problems(value, p["schema"], self.types, name)
                values[name] = value
            elif "default" in p:
                values[name] = clone(p["default"])
            else:
                errors.append(f"missing parameter {name!r}" + (f" ({p['doc']})" if p.get("doc") else ""))
        ids = self.data.ids[svc.scope.component]
        for p in params:
            if p["source"] == "ids" and p["name"] in values:
                problem = _unstorable(ids, p.get("member") or p["name"])
                if problem:
                    errors.append(f"parameter {p['name']!r} cannot be stored in ids member "
                                  f"{p.get('member') or p['name']}: {problem}")
        if errors:
            raise RequestError(422, f"bad request to {svc.label}: " + "; ".join(errors))
        return values

    def get(self, request_id: int) -> Request:
        req = self.requests.get(request_id)
        if req is None:
            known = f"requests 1 to {self._next_id - 1}" if self._next_id > 1 else "no request yet"
            raise RequestError(404, f"no request {request_id} ({known}; the last {self.keep} ended ones are kept)")
        return req

    def snapshot(self, request_id: int) -> dict[str, Any]:
        """The request as JSON data, consistent even while the engine thread reports on it."""
        req = self.get(request_id)
        with self._lock:
            return req.as_json()

    def wait(self, request_id: int, timeout: float | None = None) -> Request:
        """Block until the request has its final report (or ``timeout`` seconds); returns it either way."""
        req = self.get(request_id)
        with self._lock:
            self._done.wait_for(lambda: req.final is not None, timeout)
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
        self.listeners = self.listeners + [listener]

        def unsubscribe() -> None:
            self.listeners = [x for x in self.listeners if x is not listener]
        return unsubscribe

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
        if self.listeners:
            self._emit({"event": "poster", **value.as_json()})

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
        self._end_pending()
        self._emit({"event": "controller", "status": self.status, "steps": self.steps, "error": self.error})

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
        """A due period first (earliest deadline), else an untimed interaction, else a period with work to do."""
        due: tuple[float, Interaction, StepInfo] | None = None
        ready: list[tuple[Interaction, StepInfo]] = []
        lazy: list[tuple[Interaction, StepInfo]] = []
        wake_at = None
        answerable: set[str] = set()  # services whose queued request can be accepted or refused now
        for inter in self.engine.enabled(self.state):
            info = self._info.get(inter.index) or self.info(inter)
            if info.service is not None and info.kind in ("trigger", "refuse"):
                answerable.add(info.service.label)
            if info.opens is not None:
                d = info.opens.deadline
                if d <= now:
                    if due is None or d < due[0]:
                        due = (d, inter, info)
                elif wake_at is None or d < wake_at:
                    wake_at = d
            elif info.lazy_exec is not None:
                lazy.append((inter, info))
            else:
                ready.append((inter, info))
        if self._waits:
            self._report_held(answerable)
        if due is not None:
            return due[1], due[2], wake_at
        if ready:
            if self._rng is not None:
                inter, info = ready[self._rng.randrange(len(ready))]
            else:  # the least recently fired: a module stuck in a loop of codels cannot starve the others
                last = self._last
                inter, info = min(ready, key=lambda r: last.get(r[0].index, -1))
            self._last[inter.index] = self.steps
            return inter, info, wake_at
        for inter, info in lazy:
            if self._has_work(inter, info):
                return inter, info, wake_at
        return None, None, wake_at

    def _wait_rules(self) -> dict[str, tuple[list[str], list[Service]]]:
        """Service label -> (the rules that hold its requests, the services they read): ``@wait`` on its trigger."""
        out = {}
        for fc in self.engine.flat.connectors:
            if not fc.label.endswith(":trigger"):
                continue
            for a in fc.instance.annotations:
                if a.name == "wait" and a.arguments.get("rules"):
                    label = fc.label.rsplit(":", 1)[0]
                    ports = set(self._leaves(fc))
                    reads = [svc for svc in self.services.values() if f"{svc.label}.control.status" in ports]
                    out[label] = (a.arguments["rules"].split(","), reads)
        return out

    def _report_held(self, answerable: set[str]) -> None:
        """A queued request that only a wait rule keeps from starting gets one intermediate ``held`` report."""
        for label, (rules, reads) in self._waits.items():
            svc = self.services.get(label)
            if svc is None or not svc.queue or svc.current is not None or label in answerable:
                continue
            head = svc.queue[0]
            if head.held:
                continue
            head.held = True
            self._report(head, "held", reason="rule", rules=rules, status_of=self._status_of(reads),
                         message=f"{label} held by rule {', '.join(rules)} until it allows the request")

    def _has_work(self, inter: Interaction, info: StepInfo) -> bool:
        """Would opening this untimed period let one of its task's codels run?  (Memoised by state.)"""
        key = (inter.index, self.state)
        got = self._work.get(key)
        if got is None:
            after = self.engine.fire(self.state, inter)
            got = self._work[key] = any(info.lazy_exec in j.ports for j in self.engine.enabled(after))
            if len(self._work) > 50_000:
                self._work.clear()
        return got

    def _fire(self, inter: Interaction, info: StepInfo) -> None:
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
        self._observe(info, req, now)
        if self.monitor is not None:
            for event in self.monitor.step(inter.ports, inter.label, now, self.clock.now()):
                self._emit(event)

    def _observe(self, info: StepInfo, req: Request | None, now: float) -> None:
        """Timers (``now``: when the step began) and reports after a step."""
        if info.opens is not None:
            info.opens.open(now)
        if info.closes is not None:
            overrun = info.closes.close(now)
            if overrun is not None:
                self._emit({"event": "overrun", **overrun})
        failure = self.binder.failure
        svc = info.service
        if svc is None:
            if info.scope is not None and failure is not None:
                self._emit({"event": "codel_error", "task": info.scope.label, **failure})
            return
        if req is None:
            return
        kind = info.kind or ""
        if failure is not None and (kind == "trigger" or kind.startswith("exec_")):
            req.failure = failure
        if kind == "refuse":
            rule = (info.rule or {}).get("name", "a rule")
            self._report(req, "rejected", reason="rule", rule=rule, status_of=self._status_of(info.reads),
                         message=f"{req.label} refused by rule {rule}")
        elif kind == "reject":
            f = req.failure or {}
            self._report(req, "rejected", reason="validate", **self._failure_fields(f),
                         message=f.get("message", f"{req.label} rejected by its validate codel"))
        elif kind == "start":
            self._apply_inputs(svc, req)
            self._report(req, "started")
            for victim in info.victims:
                if victim.current is not None:
                    victim.current.interrupted_by = (svc.label, req.id)
            for victim in info.cancelled:  # accepted, not started: it ends here
                if victim.current is not None:
                    self._report(victim.current, "interrupted", by=svc.label, by_request=req.id,
                                 message=f"{victim.label} interrupted by {svc.label} before it started")
        elif kind == "finish":
            self._report(req, "ok", outputs=self._outputs(svc, req))
        elif kind == "fail":
            f = req.failure or {}
            self._report(req, "failed", **self._failure_fields(f),
                         message=f.get("message", f"{req.label} failed"))
        elif kind == "interrupted":
            by, by_request = req.interrupted_by or (None, None)
            self._report(req, "interrupted", by=by, by_request=by_request,
                         message=f"{req.label} interrupted by {by}" if by else f"{req.label} interrupted")

    @staticmethod
    def _failure_fields(f: dict[str, Any]) -> dict[str, Any]:
        return {k: f[k] for k in ("exception", "detail", "codel", "error", "where") if k in f}

    def _status_of(self, services: list[Service]) -> dict[str, dict[str, bool]]:
        out = {}
        for s in services:
            if s.status_slots is not None:
                out[s.label] = {k: bool(self.state[i]) for k, i in zip(("done", "ok", "running"), s.status_slots)}
        return out

    def _apply_inputs(self, svc: Service, req: Request) -> None:
        """Parameters bound to ids members are written to the ids once the request is accepted (GenoM attributes).

        :meth:`submit` refuses an input that has nowhere to go; should the ids
        have changed shape since, the input is not lost without a word: the
        request's failure and a ``codel_error`` event name it.
        """
        ids = self.data.ids[svc.scope.component]
        for p in svc.spec["parameters"]:
            if p["source"] == "ids" and p["direction"] in ("in", "inout") and p["name"] in req.locals:
                member = p.get("member") or p["name"]
                problem = _unstorable(ids, member)
                if problem is None:
                    set_path(ids, path_steps(member), clone(req.locals[p["name"]]))
                    continue
                message = f"{req.label} request {req.id}: parameter {p['name']!r} not stored in ids member {member}: " \
                          f"{problem}"
                req.failure = {"error": "bad input", "input": p["name"], "message": message}
                self._emit({"event": "codel_error", "request": req.id, "task": None, **req.failure})

    def _outputs(self, svc: Service, req: Request) -> dict[str, Any]:
        ids = self.data.ids[svc.scope.component]
        out = {}
        for p in svc.spec["parameters"]:
            if p["direction"] in ("out", "inout"):
                if p["source"] == "ids":
                    out[p["name"]] = clone(get_path(ids, path_steps(p.get("member") or p["name"])))
                else:
                    out[p["name"]] = clone(req.locals.get(p["name"]))
        return out

    # -- reports --------------------------------------------------------------------------------------------
    def _report(self, req: Request, status: str, **fields: Any) -> None:
        now = self.clock.now()
        report = {"request": req.id, "component": req.component, "service": req.service, "status": status,
                  "final": status in FINAL, "step": self.steps,
                  "time": round(now - self.started_at, 6) if self.started_at is not None else 0.0, **fields}
        with self._lock:
            req.reports.append(report)
            if status in FINAL:
                req.status, req.final = status, report
                svc = self.services[req.label]
                if svc.current is req:
                    svc.current = None
                self._ended.append(req.id)
                while len(self._ended) > self.keep:
                    self.requests.pop(self._ended.popleft(), None)
                self._done.notify_all()
            elif status == "started":
                req.status = "running"
            self._emit({"event": "report", **report})

    def _end_pending(self) -> None:
        """Every request still queued or running gets its final report when the controller stops."""
        why = f"the controller stopped ({self.error})" if self.error else "the controller stopped"
        for svc in self.services.values():
            with self._lock:
                pending = ([svc.current] if svc.current is not None else []) + list(svc.queue)
                svc.queue.clear()
            for req in pending:
                if req.final is None:
                    cut = f"; {req.failure['message']}" if req.failure else ""  # e.g. its codel, interrupted
                    self._report(req, "interrupted", by=None, by_request=None, message=f"{req.label}: {why}{cut}",
                                 **self._failure_fields(req.failure or {}))

    def _emit(self, event: dict[str, Any]) -> None:
        for listener in self.listeners:
            try:
                listener(event)
            except Exception as err:  # noqa: BLE001 - a listener's bug must not stop the controller
                print(f"warning: event listener failed: {type(err).__name__}: {err}", file=sys.stderr)

    # -- what the server shows ------------------------------------------------------------------------------
    def summary(self) -> dict[str, Any]:
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
