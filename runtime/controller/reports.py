"""The requests a controller remembers, the GenoM-style reports they get, and the events its listeners hear.

Each step that fires a service's port ends in a report: ``started``,
``ok`` with the outputs, ``failed`` or ``rejected`` with the codel's failure,
``interrupted`` naming who interrupted; a request held by a wait rule gets one
``held`` report (docs/runtime.md).  The service's own state (validating,
running, idle after an outcome) goes out as ``service`` events.  Reports and other events go to every
listener; a listener's bug does not stop the controller.
"""
from __future__ import annotations

import sys
import threading
from collections import deque
from typing import Any, Callable

from runtime.controller.data import Data
from runtime.controller.intake import outputs, store_inputs
from runtime.controller.meaning import StepInfo
from runtime.controller.requests import FINAL, REPORT_STATUSES, Request, RequestError, Service

Listener = Callable[[dict[str, Any]], None]
#: When a report is made: (the controller's step, seconds since its run started).
Stamp = Callable[[], tuple[int, float]]


def failure_fields(f: dict[str, Any]) -> dict[str, Any]:
    """What a report says of a codel's failure."""
    return {k: f[k] for k in ("exception", "detail", "codel", "error", "where") if k in f}


def status_of(services: list[Service], state: tuple) -> dict[str, dict[str, bool]]:
    """The (done, ok, running) status of ``services`` in ``state``: why a rule refused or holds a request."""
    out = {}
    for s in services:
        if s.status_slots is not None:
            out[s.label] = {k: bool(state[i]) for k, i in zip(("done", "ok", "running"), s.status_slots)}
    return out


class Reports:
    """Requests by id (the last ``keep`` ended ones are kept), their reports, and the event listeners.

    ``lock`` is the controller's: reports are made from the engine thread
    while other threads read the requests; ``done`` is notified when a
    request gets its final report.
    """

    def __init__(self, services: dict[str, Service], lock: threading.RLock, keep: int, stamp: Stamp) -> None:
        self.services = services
        self.lock = lock
        self.done = threading.Condition(lock)
        self.keep = keep
        self.stamp = stamp
        self.requests: dict[int, Request] = {}
        self.ended: deque[int] = deque()
        self.next_id = 1
        self.listeners: list[Listener] = []

    # -- requests -------------------------------------------------------------------------------------------
    def new(self, component: str, service: str, values: dict[str, Any], local: dict[str, Any]) -> Request:
        """A new request, remembered and reported ``queued`` (under the lock)."""
        req = Request(self.next_id, component, service, values, local)
        self.next_id += 1
        self.requests[req.id] = req
        self.report(req, "queued")
        return req

    def get(self, request_id: int) -> Request:
        req = self.requests.get(request_id)
        if req is None:
            known = f"requests 1 to {self.next_id - 1}" if self.next_id > 1 else "no request yet"
            raise RequestError(404, f"no request {request_id} ({known}; the last {self.keep} ended ones are kept)")
        return req

    # -- reports and events ---------------------------------------------------------------------------------
    def report(self, req: Request, status: str, **fields: Any) -> None:
        """Add a report to ``req``: a final one ends it (its service is free, waiters wake); every listener hears it."""
        if status not in REPORT_STATUSES:  # the OpenAPI document publishes that list: a new status goes there first
            raise ValueError(f"report status {status!r} is not one of {', '.join(REPORT_STATUSES)}")
        step, time = self.stamp()
        report = {"request": req.id, "component": req.component, "service": req.service, "status": status,
                  "final": status in FINAL, "step": step, "time": time, **fields}
        with self.lock:
            req.reports.append(report)
            if status in FINAL:
                req.status, req.final = status, report
                svc = self.services[req.label]
                if svc.incoming is req:
                    svc.incoming = None
                if svc.current is req:  # a request that interrupted it is next
                    svc.current, svc.incoming = svc.incoming, None
                self.ended.append(req.id)
                while len(self.ended) > self.keep:
                    self.requests.pop(self.ended.popleft(), None)
                self.done.notify_all()
            elif status == "started":
                req.status = "running"
            self.emit({"event": "report", **report})
            if status in FINAL:
                self.service_state(req, "idle", outcome=status)
            elif status == "started":
                self.service_state(req, "running")

    def service_state(self, req: Request, state: str, **fields: Any) -> None:
        """A ``service`` event: ``req``'s service is now validating it, running it, or idle after it (``outcome``)."""
        step, time = self.stamp()
        self.emit({"event": "service", "service": req.label, "state": state, "request": req.id, "step": step,
                   "time": time, **fields})

    def emit(self, event: dict[str, Any]) -> None:
        for listener in self.listeners:
            try:
                listener(event)
            except Exception as err:  # noqa: BLE001 - a listener's bug must not stop the controller
                print(f"warning: event listener failed: {type(err).__name__}: {err}", file=sys.stderr)

    def subscribe(self, listener: Listener) -> Callable[[], None]:
        """Call ``listener(event)`` for every event from now on; returns the unsubscribe."""
        self.listeners = self.listeners + [listener]

        def unsubscribe() -> None:
            self.listeners = [x for x in self.listeners if x is not listener]
        return unsubscribe

    def end_pending(self, why: str) -> None:
        """Every request still queued or running gets its final report when the controller stops."""
        for svc in self.services.values():
            with self.lock:
                pending = [r for r in (svc.current, svc.incoming) if r is not None] + list(svc.queue)
                svc.queue.clear()
            for req in pending:
                if req.final is None:
                    cut = f"; {req.failure['message']}" if req.failure else ""  # e.g. its codel, interrupted
                    self.report(req, "interrupted", by=None, by_request=None, message=f"{req.label}: {why}{cut}",
                                **failure_fields(req.failure or {}))

    def queue_heads(self, waits: dict[str, tuple[list[str], list[Service]]]) -> dict[str, Request]:
        """The first queued request of each service that a wait rule may hold, by service label."""
        with self.lock:
            return {label: svc.queue[0] for label in waits
                    if (svc := self.services.get(label)) is not None and svc.queue}

    def held(self, waits: dict[str, tuple[list[str], list[Service]]], answerable: set[str], state: tuple,
             seen: dict[str, Request]) -> None:
        """A queued request that only a wait rule keeps from starting gets one intermediate ``held`` report.

        ``seen``: the queue heads from before ``answerable`` was computed; a request queued since then
        may well be answerable, so it waits for the next look.
        """
        for label, (rules, reads) in waits.items():
            svc = self.services.get(label)
            if svc is None or not svc.queue or svc.current is not None or label in answerable:
                continue
            head = svc.queue[0]
            if head.held or seen.get(label) is not head:
                continue
            head.held = True
            self.report(head, "held", reason="rule", rules=rules, status_of=status_of(reads, state),
                        message=f"{label} held by rule {', '.join(rules)} until it allows the request")

    # -- what a step means for the requests ------------------------------------------------------------------
    def after_step(self, info: StepInfo, req: Request | None, failure: dict[str, Any] | None, state: tuple,
                   data: Data) -> None:
        """The reports a step makes: a codel's failure, a rule's or validate's refusal, a start, an end."""
        svc = info.service
        if svc is None:
            if info.scope is not None and failure is not None:  # the task's permanent activity ends
                scope = info.scope
                posters = data.stale(scope.component, scope.posters, {"task": scope.label, **failure_fields(failure),
                                                                      "message": failure.get("message")})
                self.emit({"event": "codel_error", "task": scope.label, **failure, "posters": posters})
            return
        if req is None:
            return
        kind = info.kind or ""
        if failure is not None and (kind == "trigger" or kind.startswith("exec_")):
            req.failure = failure
        if kind == "trigger":
            self.service_state(req, "validating")
        elif kind == "refuse":
            rule = (info.rule or {}).get("name", "a rule")
            self.report(req, "rejected", reason="rule", rule=rule, status_of=status_of(info.reads, state),
                        message=f"{req.label} refused by rule {rule}")
        elif kind == "preempt":  # the new request, accepted, interrupts the running one of the same service
            if svc.current is not None and svc.current is not req:
                svc.current.interrupted_by = (svc.label, req.id)
        elif kind == "reject":
            f = req.failure or {}
            self.report(req, "rejected", reason="validate", **failure_fields(f),
                        message=f.get("message", f"{req.label} rejected by its validate codel"))
        elif kind == "start":
            for lost in store_inputs(svc, req, data.ids[svc.scope.component]):
                req.failure = lost
                self.emit({"event": "codel_error", "request": req.id, "task": None, **lost})
            self.report(req, "started")
            for victim in info.victims:
                if victim.current is not None:
                    victim.current.interrupted_by = (svc.label, req.id)
            for victim in info.cancelled:  # accepted, not started: it ends here
                waiting = victim.incoming or victim.current
                if waiting is not None:
                    self.report(waiting, "interrupted", by=svc.label, by_request=req.id,
                                message=f"{victim.label} interrupted by {svc.label} before it started")
        elif kind == "finish":
            self.report(req, "ok", outputs=outputs(svc, req, data.ids[svc.scope.component]))
        elif kind == "fail":
            f = req.failure or {}
            message = f.get("message", f"{req.label} failed")
            data.stale(svc.scope.component, svc.scope.posters, {"service": svc.label, "request": req.id,
                                                                **failure_fields(f), "message": message})
            self.report(req, "failed", **failure_fields(f), message=message)
        elif kind == "interrupted":
            by, by_request = req.interrupted_by or (None, None)
            self.report(req, "interrupted", by=by, by_request=by_request,
                        message=f"{req.label} interrupted by {by}" if by else f"{req.label} interrupted")
