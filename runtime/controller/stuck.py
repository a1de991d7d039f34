"""Codels that run past their bound: reported, and the engine goes on without them while their atoms wait.

Codels run in the engine thread, one at a time, as the BIP engine fires one
interaction at a time.  A codel that never returns would hold every task.
A watchdog thread (:class:`Watchdog`) looks at the codel under way every few
milliseconds; past its bound -- its declared WCET, else its task's period,
else :data:`DEFAULT_BOUND` for the codels of the control task, and
:data:`STARTUP_BOUND` while the level starts -- it reports it (a
``codel_overrun`` event naming the codel, its service or task and how long it
has run) and, as soon as it holds anything else up (another task's period is
due, a request waits), *detaches* it: the codel keeps its thread, a new
engine thread goes on from the state before the step, and the atoms of that step (the
activity, its task's scheduler, the poster it writes) are frozen until the
codel returns.  Then the step is fired again with the codel's outcome
(runtime.controller.binding, ``replay``).  Python cannot stop a thread: a
codel that never returns keeps its thread for ever.  The controller gives up
on it when a request would interrupt its service (the step fails naming the
codel, the interrupting request can run) and at the stop; it is listed when
the run ends.
"""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from typing import Any, Callable

from runtime.controller.binding import CodelCall
from runtime.controller.meaning import StepInfo
from runtime.controller.requests import Request
from runtime.engine import Interaction

#: Seconds a codel of the control task (validate, function, attribute) may run when it declares no WCET.
DEFAULT_BOUND = 0.1
#: Seconds any codel may run while the level starts (a device to open, a world to load).
STARTUP_BOUND = 10.0


@dataclass(frozen=True)
class Bound:
    """How long a codel may run (s), and why that long."""

    seconds: float
    why: str


def bounds(interface: dict[str, Any]) -> dict[str, Bound]:
    """The bound of every codel extern: its WCET, else its task's period, else the default."""
    out: dict[str, Bound] = {}
    for comp in interface["components"].values():
        periods = {name: t.get("period_us") for name, t in comp["tasks"].items()}
        owners = [(t["instance"], name, t["codels"]) for name, t in comp["tasks"].items()]
        owners += [(t_name and comp["tasks"][t_name]["instance"], t_name, s["codels"])
                   for s in comp["services"].values() for t_name in [s.get("task")]]
        for instance, task, codels in owners:
            for extern, codel in codels.items():
                if codel.get("wcet_us"):
                    out[extern] = Bound(codel["wcet_us"] / 1e6, "its declared WCET")
                elif task and periods.get(task) and codel.get("role") != "validate":
                    out[extern] = Bound(periods[task] / 1e6, f"the period of task {instance}; no WCET declared")
                else:
                    out.setdefault(extern, Bound(DEFAULT_BOUND, "the default for the control task; no WCET declared"))
    return out


@dataclass(eq=False)
class Detached:
    """A step whose codel the engine went on without: what to fire again, for whom, which atoms wait."""

    call: CodelCall
    inter: Interaction
    info: StepInfo
    req: Request | None
    taken: tuple[Any, Request] | None  # (service, request) the step took from a queue before its codel
    atoms: frozenset[str]
    at: float  # when the step began (controller clock)

    @property
    def service(self) -> str | None:
        return self.info.service.label if self.info.service is not None else None

    def describe(self) -> str:
        """``codel lrfAcquire of LaserRF.Start (request 5)``."""
        owner = self.service or (self.info.scope.label if self.info.scope is not None else None)
        return f"codel {self.call.codel}" + (f" of {owner}" if owner else "") + \
            (f" (request {self.req.id})" if self.req is not None else "")


def atoms_of(inter: Interaction) -> frozenset[str]:
    """The atoms taking part in ``inter`` (its ports are ``atom.port``)."""
    return frozenset(port.rsplit(".", 1)[0] for port in inter.ports)


class Watchdog:
    """A thread calling ``check()`` every ``tick`` seconds until :meth:`stop`."""

    def __init__(self, check: Callable[[], None], tick: float) -> None:
        self.check = check
        self.tick = tick
        self._stopped = threading.Event()
        self._thread = threading.Thread(target=self._run, name="codel-watchdog", daemon=True)

    def start(self) -> "Watchdog":
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stopped.set()

    def _run(self) -> None:
        while not self._stopped.wait(self.tick):
            self.check()


def overrun_event(d: Detached, bound: Bound, task: str | None, now: float) -> dict[str, Any]:
    """The ``codel_overrun`` event of a codel found past its bound."""
    ran = now - d.call.started
    return {"event": "codel_overrun", "codel": d.call.codel, "task": task, "service": d.service,
            "request": d.req.id if d.req is not None else None, "bound_ms": round(bound.seconds * 1e3, 3),
            "running_ms": round(ran * 1e3, 1), "state": "running",
            "message": f"{d.describe()} has run {ran * 1e3:.0f} ms, past its bound of {bound.seconds * 1e3:g} ms "
                       f"({bound.why}): the engine goes on without it; its task waits for it"}


def late_event(d: Detached, now: float) -> dict[str, Any]:
    """The ``codel_overrun`` event of a codel that returned after it was given up on."""
    ran = time.monotonic() - d.call.started
    return {"event": "codel_overrun", "codel": d.call.codel, "task": None, "service": d.service,
            "request": d.req.id if d.req is not None else None, "running_ms": round(ran * 1e3, 1),
            "state": "returned",
            "message": f"{d.describe()} returned after {ran:.1f} s, after it was abandoned: its outcome is dropped"}
