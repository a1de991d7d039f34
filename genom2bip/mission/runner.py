"""Running a mission's steps through the services-interface client; every wait is in controller time.

The controller may run faster than real time (a virtual clock), so a wait or
a timeout counts the controller's seconds (``GET /`` uptime), never the
wall clock's.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

from genom2bip.mission.spec import Mission, Step
from runtime.services.client import Client, ServiceError

POLL = 0.05  # s of real time between two looks at a request not yet started
LONG_POLL = 1.0  # s of real time the server may hold a look at a request awaited until its final report
INTERMEDIATE = {"queued": ("queued", "held", "started", "running"), "started": ("started", "running")}


@dataclass
class Outcome:
    """What became of one step: the request, its last report and whether it met the expectation."""

    step: Step
    request: int | None = None
    report: dict[str, Any] = field(default_factory=dict)
    problem: str | None = None  # the expectation not met, or why the step could not run

    @property
    def ok(self) -> bool:
        return self.problem is None


def unmet(expect: dict[str, str] | None, report: dict[str, Any]) -> str | None:
    """Why ``report`` does not meet ``expect`` (None when it does)."""
    if not expect:
        return None
    got = dict(report)
    if got.get("exception"):
        got["exception"] = str(got["exception"]).split("::")[-1]
    for key, want in expect.items():
        if key == "exception":
            want = want.split("::")[-1]
        if str(got.get(key)) != want:
            return f"expected {key} {want}, got {got.get(key)!r} ({report.get('message') or report.get('status')})"
    return None


class Runner:
    """``Runner(client).run(mission)`` -> the outcome of each step, in order; it stops at no failure."""

    def __init__(self, client: Client, log=None) -> None:
        self.client = client
        self.log = log or (lambda text: None)
        self.named: dict[str, int] = {}

    def now(self) -> float:
        return float(self.client.info()["uptime"])

    def run(self, mission: Mission) -> list[Outcome]:
        return [self.step(s) for s in mission.steps]

    def step(self, step: Step) -> Outcome:
        out = Outcome(step)
        if step.kind == "wait" or step.after:
            end = self.now() + (step.seconds if step.kind == "wait" else step.after)
            while self.now() < end:
                time.sleep(POLL / 5)
            if step.kind == "wait":
                return out
        if step.kind == "send":
            component, service = step.target.split(".")
            try:
                out.request = self.client.send(component, service, step.inputs)
            except ServiceError as exc:
                out.report = {"status": "error", "http": exc.status, "message": exc.message,
                              "component": component, "service": service}
                out.problem = None if step.expect and step.expect.get("status") == "error" else exc.message
                self.log(f"{step.target}: error {exc.status}: {exc.message}")
                return out
            if step.name:
                self.named[step.name] = out.request
            until = step.until
        else:
            out.request = self.named[step.target]
            until = "final"
        out.report = self.follow(out.request, until, step.timeout)
        status = out.report.get("status")
        if until != "final" and not out.report.get("final"):
            out.problem = None if status in INTERMEDIATE[until] else f"still {status} after {step.timeout:g} s"
            if out.problem is None and step.expect:
                out.problem = unmet(step.expect, out.report)
        elif not out.report.get("final"):
            out.problem = f"no final report after {step.timeout:g} s (last: {status})"
        else:
            out.problem = unmet(step.expect, out.report)
        self.log(_line(step, out))
        return out

    def follow(self, request: int, until: str, timeout: float) -> dict[str, Any]:
        """The request's last report once it is final, or has reached ``until``, or ``timeout`` controller s passed."""
        end = self.now() + timeout
        while True:
            data = self.client.request(request, wait=LONG_POLL if until == "final" else POLL)
            reports = data.get("reports") or [{}]
            last = data.get("final") or reports[-1]
            if data.get("final") or (until != "final" and any(r.get("status") in INTERMEDIATE[until][1:] or
                                                               r.get("status") == until for r in reports)):
                return data.get("final") or last
            if self.now() >= end:
                return last


def _line(step: Step, out: Outcome) -> str:
    r = out.report
    what = r.get("status", "?")
    extra = r.get("rule") or r.get("exception") or r.get("by") or ""
    mark = "" if out.ok else f"  <-- {out.problem}"
    return f"[{out.request}] {step.target or step.name}: {what} {extra}".rstrip() + mark
