"""Running a timed model: simulated time (jump to the next instant) or real time (the engine's clock).

Each step: the schedule (runtime/engine/timed.py) gives every enabled
interaction its window and how far time may pass; the policy chooses among
the interactions that can fire earliest, time passes to that instant (real
time: the engine sleeps until then), the interaction fires, atoms whose
transition has ``resume`` complete their action at a time their resume guard
allows (simulated: as soon as allowed; real time: when the action returns,
which must be allowed).  No candidate and a bounded wait is a time-lock; time
going past a bound is a violation of timing constraints (exit 7, as the
Verimag engine).  The trace speaks the reference engine's words.
"""
from __future__ import annotations

import math
import random
import time
from dataclasses import dataclass
from fractions import Fraction
from typing import Callable, TextIO

from runtime.engine.errors import ModelError
from runtime.engine.interaction import Interaction
from runtime.engine.timed import TimedEngine, Window, format_time, format_window, urgent_bound
from runtime.model.timing import URGENCIES

#: How a timed run ended -> its exit status (runtime/exits.py: 4 for what the run found wrong).
EXIT = {"deadlock": 0, "limit": 0, "stopped": 0, "time-lock": 0, "error": 4, "invariant": 4, "violation": 4}


@dataclass
class TimedSummary:
    """How a timed run ended, after ``steps`` steps at model time ``time`` (ns)."""

    steps: int
    outcome: str  # deadlock, limit, stopped, time-lock, violation, invariant, error
    time: Fraction
    message: str = ""

    def line(self) -> str:
        what = {"deadlock": "deadlock", "limit": "step limit reached", "stopped": "stopped",
                "time-lock": f"time-lock ({self.message})", "violation": f"timing constraint violated ({self.message})",
                "invariant": f"invariant violated ({self.message})", "error": f"model error: {self.message}"}
        s = "" if self.steps == 1 else "s"
        return f"{self.steps} step{s}, {what[self.outcome]}, at global time {format_time(self.time)}"


class SimulatedClock:
    """Model time that jumps: waiting costs nothing and actions take no time."""

    def __init__(self) -> None:
        self.now = 0

    def wait_until(self, t: Fraction) -> None:
        self.now = max(self.now, t)

    def elapsed(self) -> Fraction:
        return self.now


class RealClock:
    """The engine's clock: nanoseconds since the run started; waiting sleeps, actions take the time they take."""

    def __init__(self) -> None:
        self.start = time.monotonic_ns()

    def wait_until(self, t: Fraction) -> None:
        left = (t - self.elapsed()) / 10**9
        if left > 0:
            time.sleep(float(left))

    def elapsed(self) -> Fraction:
        return time.monotonic_ns() - self.start


def _describe(inter: Interaction) -> str:
    if inter.connector is None:
        return inter.label
    return f"{inter.label}: {' '.join(inter.ports)}"


def _count(connectors: int, lone: int) -> str:
    parts = []
    if connectors:
        parts.append(f"{connectors} interaction{'s' if connectors > 1 else ''}")
    if lone:
        parts.append(f"{lone} internal port{'s' if lone > 1 else ''}")
    return " and ".join(parts)


class Planner:
    """When in its window each candidate is planned: the earliest instant, or (with a random generator) an
    instant drawn as the Verimag engine draws it: uniform to the nanosecond in a bounded window, the start
    plus an exponential number of nanoseconds (mean 10) in an unbounded one."""

    def __init__(self, rng: random.Random | None = None) -> None:
        self.rng = rng

    def instant(self, w: Window):
        first = w.earliest()
        if self.rng is None:
            return first
        if w.hi is None:
            return first + int(-10.0 * math.log(1.0 - self.rng.random()))
        last = w.hi - 1 if w.hi_open else w.hi
        span = math.floor(last - first)
        return first + self.rng.randint(0, span) if span > 0 else first


def run_timed(te: TimedEngine, policy: Callable, limit: int | None = None, out: TextIO | None = None,
              real_time: bool = False, show_enabled: bool = True,
              record: Callable[[dict], None] | None = None, planner: Planner | None = None) -> TimedSummary:
    """Run ``te`` from its initial state; ``policy(state, interactions)`` chooses among those planned earliest.
    ``record`` receives one dict per step (step, time in ns, interaction, ports) and one for the end."""
    summary = _run(te, policy, limit, out, real_time, show_enabled, record or (lambda step: None),
                   planner or Planner())
    if record is not None:
        record({"end": summary.outcome, "steps": summary.steps, "time_ns": int(summary.time),
                "message": summary.message})
    return summary


def _run(te, policy, limit, out, real_time, show_enabled, record, planner) -> TimedSummary:
    clock = RealClock() if real_time else SimulatedClock()
    say = (lambda line: print(line, file=out)) if out is not None else (lambda line: None)
    steps = 0
    now = 0
    try:
        state = te.engine.initial_state()
        resuming = {a.index: a.initial_resume for a in te.atoms if a.initial_resume is not None}
        state, now, problem = _resume(te, state, now, resuming, clock, say, steps, planner)
        if problem:
            return problem
        while True:
            broken = te.invariants_broken(state)
            if broken:
                say(f"state #{steps} and global time {format_time(now)}: invariant violated: {', '.join(broken)}")
                return TimedSummary(steps, "invariant", now, ", ".join(broken))
            sched = te.schedule(state)
            ordered = sorted(sched.candidates, key=lambda i: (i.connector is None, i.index))
            head = f"state #{steps} and global time {format_time(now)}: "
            if not ordered:
                if sched.wait.hi is None:
                    say(head + "deadlock!")
                    return TimedSummary(steps, "deadlock", now)
                where = "right before " if sched.wait.hi_open else "at "
                at = format_time(now + sched.wait.hi)
                say(head + f"time-lock {where}{at}!")
                return TimedSummary(steps, "time-lock", now, f"{where}{at}")
            if limit is not None and steps >= limit:
                return TimedSummary(steps, "limit", now)
            lone = sum(1 for i in ordered if i.connector is None)
            say(head + _count(len(ordered) - lone, lone) + ":")
            if show_enabled:
                for k, inter in enumerate(ordered):
                    say(f"  [{k}] {_describe(inter)} {format_window(sched.candidates[inter], now)}")
            planned = {i: planner.instant(sched.candidates[i]) for i in ordered}
            first = min(planned.values())
            earliest = [i for i in ordered if planned[i] == first]
            chosen = policy(te.delay(state, first), earliest)
            if chosen is None:
                return TimedSummary(steps, "stopped", now)
            at = now + first
            clock.wait_until(at)
            before = te.delay(state, first)
            say(f"-> choose [{ordered.index(chosen)}] {_describe(chosen)} at global time {format_time(at)}")
            resumes = te.fired_resumes(before, chosen)
            state = te.engine.fire(before, chosen)
            steps += 1
            now = at
            record({"step": steps, "time_ns": int(at), "interaction": chosen.label, "ports": list(chosen.ports)})
            state, now, problem = _resume(te, state, now, resumes, clock, say, steps, planner)
            if problem:
                return problem
    except ModelError as err:
        say(f"state #{steps} and global time {format_time(now)}: model error: {err}")
        return TimedSummary(steps, "error", now, str(err))


def _resume(te: TimedEngine, state, now: Fraction, resumes: dict, clock, say, steps: int, planner: Planner):
    """Let time pass until the step completes: the atoms of ``resumes`` resume when their guard allows
    (simulated) or when their action returned (real time); check that no timing constraint was passed."""
    resuming = frozenset(resumes)
    wait = te.schedule(state, resuming).wait
    window = te.resume_window(state, resumes) if resumes else Window(0, None)
    if isinstance(clock, SimulatedClock):
        if window.empty():
            done = now
        else:
            done = now + planner.instant(window)
        clock.wait_until(done)
    done = clock.elapsed() if isinstance(clock, RealClock) else clock.now
    d = done - now
    allowed = wait & window
    ok = not allowed.empty() and allowed.contains(d)
    if ok:
        return te.delay(state, d), done, None
    lines = [f"state #{steps} and global time {format_time(done)}: violation of the following timing constraints:"]
    sched = te.schedule(state, resuming)
    for inter, w in sched.windows.items():
        urgency = URGENCIES[te.urgency(state, inter)]
        if not urgent_bound(w, urgency).contains(d):
            lines.append(f"  {_describe(inter)} {format_window(w, now)} {urgency}")
    for name in te.invariants_broken(te.delay(state, d), resuming):
        lines.append(f"  invariant {name}")
    for atom in resumes:
        if not window.contains(d):
            hi = "+INFTY" if window.hi is None else format_time(now + window.hi)
            lines.append(f"  {te.atoms[atom].name} resume [ -INFTY, {hi} {'[' if window.hi_open else ']'}")
    for line in lines:
        say(line)
    return state, done, TimedSummary(steps, "violation", done, "; ".join(x.strip() for x in lines[1:]) or "deadline")

