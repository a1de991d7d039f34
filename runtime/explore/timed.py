"""Exploring a timed BIP2 model in discrete time: a tick of fixed length, clocks capped past their constants.

From a state, every interaction enabled now may fire (the engine's
``successors``), and time may pass by one tick when the schedule allows it
(no eager interaction enabled, no delayable one at the end of its window, the
invariants still hold one tick later).  An atom whose transition has
``resume`` completes as early as its resume guard allows, as in simulated
execution.  A clock compared only with constants is capped just above the
largest of them, so the state space is finite; docs/verification/timed-bip2.md
says what this preserves.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from fractions import Fraction

from runtime.bip2.timed_checks import uses_clock
from runtime.engine.cexpr import evaluate
from runtime.engine.errors import EngineError
from runtime.engine.timed import TimedEngine, _clock_comparisons
from runtime.model import Var

TICK = "tick"


@dataclass
class TimedExploreResult:
    """What the discrete-time exploration found: states, transitions, deadlocks, time-locks, the first error."""

    states: int
    transitions: int
    complete: bool
    tick_ns: int
    deadlocks: list[int] = field(default_factory=list)
    time_locks: list[int] = field(default_factory=list)
    error: str | None = None
    uncapped: list[str] = field(default_factory=list)
    traces: dict[int, list[str]] = field(default_factory=dict)

    def summary(self) -> str:
        what = "complete" if self.complete else "stopped at the state limit"
        return (f"{self.states:,} states, {self.transitions:,} transitions ({what}), tick {self.tick_ns} ns; "
                f"{len(self.deadlocks)} deadlock(s), {len(self.time_locks)} time-lock(s)"
                + (f"; error: {self.error}" if self.error else ""))


def clock_caps(te: TimedEngine, tick_ns: int) -> tuple[dict[int, Fraction], list[str]]:
    """Slot -> cap for every clock compared only as ``clock op constant``; the names of the other clocks."""
    caps: dict[int, Fraction] = {}
    uncapped: list[str] = []
    for fa in te.engine.flat.atoms:
        a = fa.type
        names = {c.name for c in a.clocks}
        exprs = [t.guard for t in a.transitions] + [i.guard for i in a.invariants]
        exprs += [t.resume.guard for t in a.transitions if t.resume is not None]
        for c in a.clocks:
            top: Fraction | None = Fraction(0)
            for e in exprs:
                for cmp in _clock_comparisons(e, names):
                    other = _constant_side(cmp, c.name, names, fa.constants)
                    if other is False:
                        continue  # does not read this clock
                    if other is None:
                        top = None
                        break
                    top = max(top, Fraction(other))
                if top is None:
                    break
            if top is None:
                uncapped.append(f"{fa.name}.{c.name}")
            else:
                caps[fa.slot(c.name)] = top + Fraction(tick_ns, c.nanoseconds)
    return caps, uncapped


def _constant_side(cmp, clock: str, clocks: set[str], constants):
    """The constant ``clock`` is compared with in ``cmp``; False when ``cmp`` does not read it; None when the
    other side is not a constant or the clock is not alone on its side."""
    sides = [(cmp.left, cmp.right), (cmp.right, cmp.left)]
    for mine, other in sides:
        if isinstance(mine, Var) and mine.name == clock:
            try:
                value = evaluate(other, constants, "clock bound")
            except EngineError:
                return None
            return value if isinstance(value, (int, float)) and not isinstance(value, bool) else None
    return None if uses_clock(cmp, {clock}) else False


def explore_timed(te: TimedEngine, tick_ns: int, max_states: int = 1_000_000) -> TimedExploreResult:
    """Breadth-first over the discrete-time state space of ``te``; traces reach each deadlock and time-lock."""
    caps, uncapped = clock_caps(te, tick_ns)

    def cap(state: tuple) -> tuple:
        if not caps:
            return state
        s = list(state)
        for slot, top in caps.items():
            if s[slot] > top:
                s[slot] = top.numerator if top.denominator == 1 else top
        return tuple(s)

    def settle(state: tuple, resumes: dict) -> tuple:
        if not resumes:
            return state
        w = te.resume_window(state, resumes)
        return cap(te.delay(state, w.earliest())) if not w.empty() else state

    result = TimedExploreResult(0, 0, True, tick_ns, uncapped=uncapped)
    try:
        first = cap(settle(te.engine.initial_state(),
                           {a.index: a.initial_resume for a in te.atoms if a.initial_resume is not None}))
    except EngineError as err:
        result.error = str(err)
        return result
    ids = {first: 0}
    parent: list[tuple[int, str]] = [(-1, "")]
    queue = deque([first])
    while queue:
        state = queue.popleft()
        sid = ids[state]
        try:
            succ = [(inter.label, cap(settle(new, te.fired_resumes(state, inter))))
                    for inter, new in te.engine.successors(state)]
            wait = te.schedule(state).wait
        except EngineError as err:
            result.error = f"{err} (state {sid})"
            result.traces[sid] = _trace(parent, sid)
            result.complete = False
            break
        if wait.contains(Fraction(tick_ns)):
            after = cap(te.delay(state, tick_ns))
            if after != state or succ:
                succ.append((TICK, after))
        if not succ:
            kind = result.time_locks if wait.hi is not None else result.deadlocks
            kind.append(sid)
            result.traces[sid] = _trace(parent, sid)
        for label, new in succ:
            result.transitions += 1
            if new not in ids:
                if len(ids) >= max_states:
                    result.complete = False
                    queue.clear()
                    break
                ids[new] = len(ids)
                parent.append((sid, label))
                queue.append(new)
    result.states = len(ids)
    return result


def _trace(parent: list[tuple[int, str]], sid: int) -> list[str]:
    steps = []
    while sid > 0:
        sid, label = parent[sid]
        steps.append(label)
    return steps[::-1]
