"""Exhaustive exploration: breadth-first (shortest traces) or depth-first, with limits, deadlocks and model errors.

``explore(space, ...)`` numbers every reachable state of a
:class:`~runtime.explore.space.StateSpace` and reports the deadlocks (states
without an enabled interaction), the first model error met (non-determinism,
1-safety, a variable leaving its declared domain...) and whether the
exploration was complete or stopped at ``max_states`` / ``max_depth`` /
``max_bytes`` (memory) or by Ctrl-C.
"""
from __future__ import annotations

import os
import time
from dataclasses import dataclass, field

from runtime.engine.errors import EngineError
from runtime.explore.progress import Progress, null_progress
from runtime.explore.space import LimitReached, StateSpace, Step


@dataclass
class Finding:
    """A deadlock or an error, with the state where it is and a trace reaching it."""

    kind: str  # "deadlock" or "error"
    state: int
    trace: list[Step]
    message: str = ""
    interaction: str = ""


@dataclass
class ExploreResult:
    """What an exploration found and what it cost."""

    states: int
    transitions: int
    depth: int
    complete: bool
    stopped_by: str = ""  # "max-states", "max-depth", "max-memory", "interrupted" or "error" when not complete
    deadlocks: list[int] = field(default_factory=list)
    error: Finding | None = None
    seconds: float = 0.0
    memory: int = 0
    bits: int = 0

    @property
    def rate(self) -> float:
        return self.states / self.seconds if self.seconds > 0 else 0.0

    @property
    def bytes_per_state(self) -> float:
        return self.memory / self.states if self.states else 0.0

    def summary(self) -> str:
        what = "complete" if self.complete else f"stopped at {self.stopped_by}"
        return (f"{self.states:,} states, {self.transitions:,} transitions, depth {self.depth}, {what}; "
                f"{self.seconds:.2f} s ({self.rate:,.0f} states/s), {self.bytes_per_state:.0f} bytes/state "
                f"({self.bits} bits packed)")


#: States expanded between two looks at the memory the search holds.
MEMORY_EVERY = 1024


def resident_bytes() -> int | None:
    """The process's resident memory in bytes (Linux ``/proc``; None where the system does not say)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return None


class MemoryBound:
    """The memory a search may take: the growth of the resident set since it began, or the visited set's size.

    The visited set's size (``space.memory()``: a state space, a zone explorer) counts where the resident set
    does not grow (memory freed earlier by the process, reused) or the system does not say.
    """

    def __init__(self, space, limit: int) -> None:
        self.space, self.limit = space, limit
        self.base = resident_bytes()

    def taken(self, reserve: int = 0) -> int:
        """The bytes the limit bounds, with ``reserve`` bytes kept for what comes after the search."""
        now = resident_bytes()
        grown = now - self.base if now is not None and self.base is not None else 0
        return max(grown, self.space.memory()) + reserve

    def exceeded(self, reserve: int = 0) -> bool:
        return self.taken(reserve) > self.limit


def explore(space: StateSpace, max_depth: int | None = None, dfs: bool = False,
            progress: Progress | None = None, stop_at_deadlock: bool = False,
            max_bytes: int | None = None) -> ExploreResult:
    """Number every reachable state (up to the limits); collect deadlocks; stop at the first model error.

    ``max_bytes`` bounds the memory the search takes (:class:`MemoryBound`):
    past it the search stops at ``max-memory``, what was explored reported.

    Breadth-first needs no queue: states are numbered in discovery order, so
    the frontier is the range of numbers not expanded yet, and a level ends
    where the numbers handed out during the previous level end.
    """
    progress = progress or null_progress()
    start = time.perf_counter()
    found = _Found(bound=MemoryBound(space, max_bytes) if max_bytes is not None else None)
    try:
        if dfs:
            _depth_first(space, max_depth, progress, found, stop_at_deadlock)
        else:
            _breadth_first(space, max_depth, progress, found, stop_at_deadlock)
    except LimitReached:
        found.stopped = "max-states"
    except KeyboardInterrupt:
        found.stopped = "interrupted"  # Ctrl-C: what was explored so far is still reported
    finally:
        progress.done()
    seconds = time.perf_counter() - start
    if found.error is not None:
        found.error.trace = space.trace_to(found.error.state)
    return ExploreResult(len(space), space.transitions, found.depth, not found.stopped, found.stopped,
                         found.deadlocks, found.error, seconds, space.memory(), space.codec.bits)


@dataclass
class _Found:
    deadlocks: list[int] = field(default_factory=list)
    error: Finding | None = None
    stopped: str = ""
    depth: int = 0
    bound: MemoryBound | None = None
    expanded: int = 0

    def out_of_memory(self) -> bool:
        """Every :data:`MEMORY_EVERY` expansions, whether the search has passed its memory bound."""
        self.expanded += 1
        if self.bound is None or self.expanded % MEMORY_EVERY or not self.bound.exceeded():
            return False
        self.stopped = "max-memory"
        return True


def _expand(space: StateSpace, sid: int, found: _Found, stop_at_deadlock: bool) -> tuple[int, ...] | None:
    """Successors of ``sid``, or None when the search must stop (model error, or the first deadlock if asked)."""
    try:
        succ = space.successors(sid)
    except EngineError as err:
        found.error = Finding("error", sid, [], str(err))
        found.stopped = "error"
        return None
    if not succ:
        found.deadlocks.append(sid)
        if stop_at_deadlock:
            found.stopped = "deadlock"
            return None
    return succ


def _breadth_first(space: StateSpace, max_depth, progress: Progress, found: _Found, stop_at_deadlock: bool) -> None:
    sid = 0
    level_end = len(space)
    depth = 0
    while sid < len(space):
        if sid == level_end:
            depth += 1
            level_end = len(space)
        found.depth = depth
        if max_depth is not None and depth >= max_depth:
            found.stopped = "max-depth"
            return
        if _expand(space, sid, found, stop_at_deadlock) is None or found.out_of_memory():
            return
        sid += 1
        progress.tick(len(space), space.transitions, len(space) - sid, space.memory, depth)


def _depth_first(space: StateSpace, max_depth, progress: Progress, found: _Found, stop_at_deadlock: bool) -> None:
    expanded = bytearray()
    stack = [(s, 0) for s in reversed(space.initial_ids)]
    while stack:
        sid, depth = stack.pop()
        if sid < len(expanded) and expanded[sid]:
            continue
        if len(expanded) < len(space):
            expanded.extend(bytes(len(space) - len(expanded)))
        expanded[sid] = 1
        found.depth = max(found.depth, depth)
        if max_depth is not None and depth >= max_depth:
            found.stopped = "max-depth"
            continue
        succ = _expand(space, sid, found, stop_at_deadlock)
        if succ is None or found.out_of_memory():
            return
        for k in range(len(succ) - 1, 0, -2):
            t = succ[k]
            if t >= len(expanded) or not expanded[t]:
                stack.append((t, depth + 1))
        progress.tick(len(space), space.transitions, len(stack), space.memory, found.depth)
