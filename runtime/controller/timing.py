"""Real time: the task timers of a model, their deadlines on a monotonic clock, lateness and overruns.

A timer is an atom whose type is annotated ``@timer(period="period",
trigger="trigger", sleep="sleep")``: the parameter holding its period in µs
and the ports that open and close a period.  An interaction containing the
trigger port may fire only once the timer's deadline has passed; a period
whose closing (sleep) comes after the next period should have started is an
overrun.  The level starts when every task has ended its first period (its
drivers opened, its world loaded): until then nothing is counted late,
missed or overrun, and a task behind its deadlines then starts afresh.
Schedulers (``@scheduler(period=..., exec=..., sleep=...)``)
without a timer open a period only when a codel is waiting to run in it.
"""
from __future__ import annotations

import math
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any


class MonotonicClock:
    """Wall time for the controller: ``time.monotonic``; waiting is done on the controller's condition."""

    virtual = False

    def now(self) -> float:
        return time.monotonic()


class VirtualClock:
    """Time that jumps to the next deadline instead of waiting: runs a controller as fast as it can."""

    virtual = True

    def __init__(self, start: float = 0.0) -> None:
        self.t = start

    def now(self) -> float:
        return self.t

    def advance(self, to: float) -> None:
        self.t = max(self.t, to)


def _annotation(atom_type, name: str) -> dict[str, str] | None:
    for a in atom_type.annotations:
        if a.name == name:
            return a.arguments
    return None


@dataclass
class Timer:
    """The timer of one task: its period (s, after the clock-rate), next deadline, and what happened so far."""

    task: str  # the task compound's instance path, e.g. "NDD.motion"
    trigger: str  # port paths
    sleep: str
    period: float
    base: float = 0.0  # when period 0 started: period k starts at base + k * period (no drift)
    index: int = 0  # the next period's number
    opened: float | None = None  # ideal start of the period now open
    periods: int = 0
    missed: int = 0
    overruns: int = 0
    lateness: deque = field(default_factory=lambda: deque(maxlen=100_000))
    counting: bool = False  # the level has started: lateness, missed periods and overruns count
    counted: bool = False  # the period now open opened while counting
    closed_once: bool = False  # its first period has ended

    @property
    def deadline(self) -> float:
        """When the next period may start."""
        return self.base + self.index * self.period

    def open(self, now: float) -> None:
        """The period interaction fired at ``now``: record the lateness, skip whole periods missed."""
        late = now - self.deadline
        self.periods += 1
        missed = int(late // self.period) if late >= self.period else 0
        if self.counting:
            self.lateness.append(late)
            self.missed += missed
        self.index += missed
        self.opened = self.deadline
        self.counted = self.counting
        self.index += 1

    def close(self, now: float) -> dict[str, Any] | None:
        """The period closed at ``now``: an overrun report when it lasted longer than the period."""
        if self.opened is None:
            return None
        took = now - self.opened
        self.opened = None
        self.closed_once = True
        if took <= self.period or not self.counted:
            return None
        self.overruns += 1
        return {"task": self.task, "period_ms": round(self.period * 1e3, 3), "took_ms": round(took * 1e3, 3),
                "overruns": self.overruns,
                "message": f"task {self.task} overran its {self.period * 1e3:g} ms period: "
                           f"the period took {took * 1e3:.1f} ms"}

    def stats(self) -> dict[str, Any]:
        lat = sorted(self.lateness)

        def pct(q: float) -> float | None:
            return round(lat[min(len(lat) - 1, int(q * len(lat)))] * 1e3, 3) if lat else None

        return {"task": self.task, "period_ms": round(self.period * 1e3, 3), "periods": self.periods,
                "missed": self.missed, "overruns": self.overruns,
                "lateness_ms": {"p50": pct(0.5), "p99": pct(0.99), "max": round(lat[-1] * 1e3, 3) if lat else None}}


@dataclass
class Timers:
    """Every timer and timer-less scheduler of a flat system, found by their annotations."""

    timers: list[Timer]
    by_trigger: dict[str, Timer]
    by_sleep: dict[str, Timer]
    lazy: dict[str, str]  # period port of a scheduler without timer -> its exec port
    t0: float = 0.0
    ready: bool = False  # every task has ended its first period
    startup: float | None = None  # seconds from the start to the level ready

    @classmethod
    def of(cls, flat, clock_rates: dict[str, int | None] | None = None) -> "Timers":
        """``clock_rates``: µs per module instance name (first path segment), periods rounded up to a multiple."""
        timers: list[Timer] = []
        tasks_with_timer: set[str] = set()
        schedulers = []
        for atom in flat.atoms:
            t = _annotation(atom.type, "timer")
            if t is not None:
                period_us = atom.constants[t.get("period", "period")][0]
                task = atom.name.rsplit(".", 1)[0] if "." in atom.name else atom.name
                rate = (clock_rates or {}).get(atom.name.split(".")[0])
                if rate:
                    period_us = max(1, math.ceil(period_us / rate)) * rate
                timers.append(Timer(task, f"{atom.name}.{t.get('trigger', 'trigger')}",
                                    f"{atom.name}.{t.get('sleep', 'sleep')}", period_us / 1e6))
                tasks_with_timer.add(task)
            s = _annotation(atom.type, "scheduler")
            if s is not None:
                schedulers.append((atom.name, s))
        lazy = {}
        for name, s in schedulers:
            task = name.rsplit(".", 1)[0] if "." in name else ""
            if task not in tasks_with_timer:
                lazy[f"{name}.{s.get('period', 'period')}"] = f"{name}.{s.get('exec', 'exec')}"
        return cls(timers, {t.trigger: t for t in timers}, {t.sleep: t for t in timers}, lazy)

    def start(self, now: float) -> None:
        """Every task's first period starts now."""
        self.t0, self.ready, self.startup = now, False, None
        for t in self.timers:
            t.base, t.index, t.opened = now, 0, None
            t.counting = t.counted = t.closed_once = False
        if not self.timers:
            self.ready_at(now)

    def started_up(self) -> bool:
        """Every task has ended its first period."""
        return all(t.closed_once for t in self.timers)

    def ready_at(self, now: float) -> None:
        """The level is ready: from now on periods count; a task behind its deadlines starts afresh now."""
        self.ready, self.startup = True, now - self.t0
        for t in self.timers:
            t.counting = True
            if t.deadline < now:
                t.base += now - t.deadline

    def stats(self) -> list[dict[str, Any]]:
        return [t.stats() for t in self.timers]
