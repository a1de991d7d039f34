"""Requests sent to services and the GenoM-style reports they get.

A request is queued for its service until the module's acceptor takes it
(``take_request``), then follows the service's interactions.  Reports are
plain dicts (docs/runtime.md): intermediate ones (``queued``, ``started``) and
exactly one final one (``ok``, ``rejected``, ``failed``, ``interrupted``).
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Any

from runtime.controller.binding import Scope

FINAL = ("ok", "rejected", "failed", "interrupted")
#: Every status a report can have, in the order a request meets them; the OpenAPI document lists these.
REPORT_STATUSES = ("queued", "held", "started", *FINAL)
#: Every status a request can be in (``Request.status``).
REQUEST_STATUSES = ("queued", "running", *FINAL)


class RequestError(Exception):
    """A request the interface refuses before queueing it: ``status`` is the HTTP status (404, 409, 422...)."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.message = message


@dataclass
class Request:
    """One request: its inputs, the locals its codels see, its reports; ``final`` once it has ended."""

    id: int
    component: str
    service: str
    inputs: dict[str, Any]
    locals: dict[str, Any]
    reports: list[dict[str, Any]] = field(default_factory=list)
    status: str = "queued"  # one of REQUEST_STATUSES: queued, running, then one of FINAL
    final: dict[str, Any] | None = None
    failure: dict[str, Any] | None = None  # the last codel failure of this request
    interrupted_by: tuple[str, int | None] | None = None
    held: bool = False  # a "held" report was sent: a wait rule keeps it in its queue

    @property
    def label(self) -> str:
        return f"{self.component}.{self.service}"

    def as_json(self) -> dict[str, Any]:
        return {"id": self.id, "component": self.component, "service": self.service, "inputs": self.inputs,
                "status": self.status, "final": self.final, "reports": list(self.reports)}


@dataclass
class Service:
    """A service at run time: its interface entry, its queue of requests and the one it is handling."""

    scope: Scope
    spec: dict[str, Any]
    queue: deque = field(default_factory=deque)
    current: Request | None = None
    # a request accepted while ``current`` runs, by a service that interrupts itself: it starts once current ends
    incoming: Request | None = None
    # slots of (done, ok, running) of its controller atom, to say why a rule refused something
    status_slots: tuple[int, int, int] | None = None

    @property
    def label(self) -> str:
        return self.scope.label

    @property
    def reentrant(self) -> bool:
        """Attributes and functions queue their requests; an activity takes one at a time."""
        return self.spec["kind"] != "activity"

    @property
    def renews(self) -> bool:
        """An activity that interrupts itself: a new request interrupts the running one (GenoM3), never busy."""
        interrupts = self.spec.get("interrupts", [])
        return self.spec["kind"] == "activity" and (self.scope.name in interrupts or "all" in interrupts)

    def busy_with(self) -> Request | None:
        return self.current or (self.queue[0] if self.queue else None)
