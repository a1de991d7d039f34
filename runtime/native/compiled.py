"""A state space's step and search run in C: same states, numbers, deadlocks and traces as the Python explorer.

``compile_space(space)`` returns a :class:`CompiledSpace` or, when the
model cannot be compiled (no C compiler, a feature the C back end does not
take), None and a one-line note saying why.  The compiled search numbers
states exactly as :func:`runtime.explore.explore` does (same order of
interactions and outcomes), so state numbers, deadlocks and shortest traces
agree; traces are rebuilt by the Python step along the C parent links, with
their codel outcomes.
"""
from __future__ import annotations

import ctypes
import signal
import threading
import time
from dataclasses import dataclass
from typing import Any

from runtime.engine.errors import EngineError
from runtime.explore.choices import Choice, codel_choices
from runtime.explore.progress import Progress, null_progress
from runtime.explore.search import ExploreResult, Finding
from runtime.explore.space import StateSpace, Step
from runtime.native.build import (PROGRESS, STEP_LEVEL, BuildError, Result, build, cached, compiler, forced, load,
                                  say)
from runtime.native.cexpr import Unsupported
from runtime.native.cstep import generate
from runtime.native.values import from_words, to_words
from runtime.native.stores import DEFAULT_BITS, STORES, lossiness

STATUS = {0: "", 1: "max-states", 2: "max-depth", 3: "error", 4: "deadlock", 5: "interrupted", 6: "max-memory",
          8: "violated"}
S_ERROR, S_WIDEN, S_VIOLATED = 3, 7, 8
#: Seconds between progress reports from the C search (and checks for Ctrl-C).
PERIOD = 0.25


class Diverged(Exception):
    """The C step stopped where the Python step computes a value (an int past 64 bits): explore in Python."""


def exploration_choices(package, externs: dict[str, Any] | None) -> dict[str, Choice]:
    """The externs that are choice points during exploration, as :func:`bind_for_exploration` binds them."""
    user = dict(externs or {})
    out = {}
    for name, choice in codel_choices(package).items():
        if name not in user:
            out[name] = choice
    for name, given in user.items():
        if isinstance(given, Choice):
            out[name] = given
    return out


def compile_space(space: StateSpace, externs: dict[str, Any] | None = None, monitors=(), wide_numbers: bool = False,
                  wide_fields: bool = False, search: bool = False) -> tuple[CompiledSpace | None, str]:
    """The compiled step and search of ``space``, or None and why not (one line).

    ``monitors`` are ``(Monitor, statics)`` safety observers the search steps with every interaction;
    ``wide_numbers`` stores 64-bit interaction numbers even when 32 bits hold them (what tests and benches
    compare the two layouts with); ``wide_fields`` gives every int without a declared domain 64 bits from the
    start, for a step called one state at a time (whose packed size does not matter): it never widens, so it
    is generated and compiled once instead of once per field that outgrows its first bits; ``search``: the caller
    runs the C search (:meth:`CompiledSpace.explore`), so the library is built with it at once, at the search's
    level, rather than the step alone first (what a caller stepping one state at a time gets).
    """
    if space.engine.invariants:
        return None, "the compiled explorer does not check atom invariants: exploring with the Python step"
    cc = compiler()
    if cc is None:
        return None, "no C compiler on PATH (gcc or $CC): exploring with the Python step"
    cs = CompiledSpace(space, exploration_choices(space.engine.flat.package, externs), cc, monitors, wide_numbers)
    cs.searching = search
    if wide_fields:
        cs.widths.update({k: 64 for k, s in enumerate(space.slots) if s.kind == "int" and s.domain is None})
    try:
        cs.build()
    except Unsupported as exc:
        return None, f"compiled exploration does not take this model ({exc}): exploring with the Python step"
    except (BuildError, OSError) as exc:
        return None, f"compiling the step failed ({str(exc).splitlines()[0]}): exploring with the Python step"
    return cs, ""


@dataclass
class _Interrupt:
    hit: bool = False


class CompiledSpace:
    """The C library of one model bound to its Python :class:`StateSpace` (which words errors and traces)."""

    def __init__(self, space: StateSpace, choices: dict[str, Choice], cc: str, monitors=(),
                 wide_numbers: bool = False) -> None:
        self.space = space
        self.wide_numbers = wide_numbers  # 64-bit interaction numbers even where 32 bits hold them
        self.monitors = list(monitors)
        self.choices = choices
        self.cc = cc
        self.widths: dict[int, int] = {}
        self.engine = space.engine
        budget = space.environment.budget
        self.budget = -1 if budget is None else budget
        self.bools = [s.index for s in space.slots if s.kind == "bool"]
        self.kinds = {s.index: s.kind for s in space.slots}
        self.parallel = False  # the loaded library is the threaded build
        self.searching = False  # the loaded library runs the C search (built at -O2), not single steps (-O0)
        self.lossiness = None
        self._cap = 64  # successors one call of successors() has room for (the output is width words each)
        self._index: dict[int, int] = {}  # the compiled step's interaction numbers -> the engine's indices
        self.optimised = False  # the loaded library is built at -O2 (the search's level), or GENOM2BIP_OPT's
        self._later: tuple[str, threading.Thread, list] | None = None  # optimise_later's source, thread, result

    def build(self, parallel: bool | None = None) -> None:
        """Generate, compile (or find in the cache) and load the library for the current field widths.

        ``parallel``: the threaded build (search.c's PARALLEL) instead of the single-threaded one.
        """
        if parallel is not None:
            self.parallel = parallel
        model = generate(self.space, self.choices, self.widths, self.monitors, self.wide_numbers)
        faster = None if self.searching else (cached(model.source, self.cc, self.parallel)
                                              or cached(model.source, self.cc, self.parallel, step_only=True))
        self.optimised = self.searching or faster is not None or forced()
        self.lib = load(faster or build(model.source, self.cc, self.parallel, self._what(),
                                        None if self.searching else STEP_LEVEL, step_only=not self.searching))
        self.width, self.source, self.bits = model.width, model.source, model.bits
        self.model = model
        self._index = {}  # numbered by this build

    def _what(self) -> str:
        flat = self.engine.flat
        return f"compiled step: {flat.package.name} {flat.root}"

    def optimise_later(self) -> None:
        """Compile the loaded step at -O2 on another thread, for :meth:`adopt` to load: a long search called one
        state at a time (the zone search's) goes on meanwhile with the quick -O0 build."""
        if self.optimised or self._later is not None and self._later[0] == self.source:
            return
        source, parallel, done = self.source, self.parallel, []

        def work() -> None:
            start = time.perf_counter()
            try:
                done.append((build(source, self.cc, parallel, self._what(), None, told=False, step_only=True),
                             time.perf_counter() - start))
            except (BuildError, OSError):
                done.append(None)  # the -O0 build goes on serving

        thread = threading.Thread(target=work, name="genom2bip -O2 build", daemon=True)
        self._later = (source, thread, done)
        thread.start()

    def adopt(self) -> bool:
        """Load the -O2 build that :meth:`optimise_later` finished, if it is of the current step: True when
        ``self.lib`` changed (the same step, state words and numbers, only faster)."""
        if self._later is None or self._later[0] != self.source or not self._later[2]:
            return False
        got, self._later = self._later[2][0], None
        if got is None or self.optimised:
            return False
        self.lib, self.optimised = load(got[0]), True
        say(f"{self._what()}: the -O2 build, compiled in {got[1]:.1f} s beside the search, takes over")
        return True

    def _widen(self, slot: int) -> None:
        """A value outgrew the field of slot ``slot`` (position in the layout): twice as many bits, for it and for
        the variables of the same name in other atoms (the same data of another instance of a type mostly grows
        alike: one rebuild instead of one per instance, each a compile of the whole step)."""
        wider = min(64, 2 * self.lib.c_width(slot))
        slots = self.space.slots
        name = slots[slot].name if slot < len(slots) else None
        for k, s in enumerate(slots):
            if k != slot and name is not None and s.kind == "int" and s.name == name and s.domain is None \
                    and not s.never_live and self.lib.c_width(k) < wider:
                self.widths[k] = wider
        self.widths[slot] = wider
        self.build()

    # -- one step -------------------------------------------------------------------------------
    def _typed(self, values) -> tuple:
        out = from_words(self.model, values)
        for i in self.bools:
            out[i] = bool(out[i])
        return tuple(out)

    def interaction_index(self, number: int) -> int:
        """The engine's index of the interaction the compiled search numbers ``number`` (runtime.native.numbering)."""
        got = self._index.get(number)
        if got is None:
            src, mask = self.model.numbering.interaction(number)
            got = self._index[number] = self.engine._make(src, mask).index
        return got

    def successors(self, state: tuple) -> list[tuple[int, tuple]]:
        """``(interaction index, next state)`` for every successor of an explorer state, dead variables reset."""
        cap = self._cap  # room for this many successors: grown when a state has more (a few dozen, mostly)
        while True:
            s = (ctypes.c_int64 * self.width)(*to_words(self.model, state))
            out = (ctypes.c_int64 * (self.width * cap))()
            via = (ctypes.c_int64 * cap)()
            code, arg = ctypes.c_int(0), ctypes.c_int64(0)
            n = self.lib.c_successors(s, out, via, cap, self.budget, ctypes.byref(code), ctypes.byref(arg))
            if n >= 0:
                return [(self.interaction_index(via[i]), self._typed(out[i * self.width:(i + 1) * self.width]))
                        for i in range(n)]
            if code.value == 8:  # a field too narrow: widen and redo
                self._widen(arg.value)
                continue
            if code.value == 10 and cap < 65536:
                cap = self._cap = cap * 16
                continue
            raise _CError(code.value, arg.value)

    # -- the search ------------------------------------------------------------------------------
    def explore(self, max_states: int | None = None, max_depth: int | None = None, dfs: bool = False,
                progress: Progress | None = None, stop_at_deadlock: bool = False,
                max_bytes: int | None = None, max_seconds: float | None = None, por: bool = False,
                workers: int = 1, store: str = "exact", bits: int = DEFAULT_BITS) -> ExploreResult:
        """Like :func:`runtime.explore.explore`; raises :class:`Diverged` if the Python step must take over.

        ``workers`` > 1 searches breadth-first on that many threads (the threaded build, compiled on first
        use): same states, deadlocks and verdicts, traces still shortest, state numbers within a level
        depend on the threads.  ``store`` is ``exact``, ``compact`` or ``bitstate`` (2^``bits`` bits):
        lossy stores search breadth-first and set ``self.lossiness`` (runtime.native.stores).

        ``por`` explores ample sets (runtime.native.por): the same deadlocks and observer verdicts on fewer
        states; ``self.reduced`` is then the number of states expanded with a proper ample set.

        ``max_bytes`` bounds the visited set and ``max_seconds`` the time (stopped by ``max-memory``,
        ``max-seconds``); Ctrl-C stops the search as ``interrupted``, with everything found so far.
        """
        progress = progress or null_progress()
        interrupt, timed = _Interrupt(), _Interrupt()

        def report(states, transitions, depth, frontier, memory):
            progress.tick(states, transitions, frontier, lambda: memory, depth=depth)
            if max_seconds is not None and time.perf_counter() - start >= max_seconds:
                timed.hit = True
            return 1 if interrupt.hit or timed.hit else 0

        callback = PROGRESS(report)
        if (workers > 1) != self.parallel or not self.searching:  # the search's own build: threaded, at -O2
            self.searching = True
            self.build(parallel=workers > 1)
        previous = _catch_interrupt(interrupt)
        start = time.perf_counter()
        try:
            while True:
                r = Result()
                self.lib.c_set_por(int(por))
                status = self.lib.c_search(int(dfs), -1 if max_states is None else max_states,
                                           -1 if max_depth is None else max_depth,
                                           -1 if max_bytes is None else max_bytes, int(stop_at_deadlock),
                                           self.budget, PERIOD, callback, ctypes.byref(r), workers,
                                           STORES[store], bits)
                if status != S_WIDEN:
                    break
                self._widen(r.earg)
        finally:
            _restore_interrupt(previous)
            progress.done()
        seconds = time.perf_counter() - start
        deadlocks = [self.lib.c_deadlock(i) for i in range(r.deadlocks)]
        self.reduced = self.lib.c_reduced()
        self.lossiness = lossiness(store, r.states, self.lib.c_table_size())
        error = None
        self.violation = r.error_state if status == S_VIOLATED else -1  # the state an observer rejects
        if status == S_ERROR:
            error = self._error(r)
        stopped = "max-seconds" if timed.hit and status == 5 else STATUS[status]
        return ExploreResult(r.states, r.transitions, r.depth, not stopped, stopped, deadlocks, error, seconds,
                             r.memory, self.bits)

    def _error(self, r: Result) -> Finding:
        """The Python step's own words for the error the C step stopped at, with a shortest trace."""
        if r.error_state < 0:
            raise Diverged("the initial state")
        space = self.space
        state = self.state(r.error_state)[:space.width + len(space.services)]
        saved, space.max_states = space.max_states, None
        try:
            sid = space._add(space._pack(state), -1, -1)
            space.successors(sid)
        except EngineError as err:
            return Finding("error", r.error_state, self.trace_to(r.error_state), str(err))
        finally:
            space.max_states = saved
        raise Diverged(f"state {r.error_state}")

    # -- states and traces ---------------------------------------------------------------------------
    def state(self, sid: int) -> tuple:
        out = (ctypes.c_int64 * self.width)()
        self.lib.c_state(sid, out)
        return self._typed(out[:])

    def path_to(self, sid: int) -> list[int]:
        path = [sid]
        while self.lib.c_parent(path[-1]) >= 0:
            path.append(self.lib.c_parent(path[-1]))
        return path[::-1]

    def trace_to(self, sid: int) -> list[Step]:
        """The steps along the parent links to ``sid`` (shortest after a breadth-first search), with outcomes."""
        path = self.path_to(sid)
        space = self.space
        explorer = space.width + len(space.services)  # the observers' slots follow
        saved, space.max_states = space.max_states, None
        try:
            ids = [space._add(space._pack(self.state(k)[:explorer]), -1, -1) for k in path]
        finally:
            space.max_states = saved
        labels = [space.interaction(self.interaction_index(self.lib.c_via(k))).label for k in path[1:]]
        return space.steps_along(ids, labels)

    def concrete(self, steps: list[Step]) -> tuple:
        return self.space.concrete(steps)

    @property
    def por_available(self) -> bool:
        """False where the reduction is off: request counts are data every service shares."""
        return bool(self.lib.c_por_available())

    def release(self) -> None:
        self.lib.c_free()


class _CError(EngineError):
    def __init__(self, code: int, arg: int) -> None:
        super().__init__(f"compiled step stopped with error code {code} ({arg})")
        self.code, self.arg = code, arg


def _catch_interrupt(flag: _Interrupt):
    """Ctrl-C during the C search sets a flag the progress callback returns: the search stops and reports."""
    try:
        return signal.signal(signal.SIGINT, lambda *_: setattr(flag, "hit", True))
    except ValueError:  # not the main thread
        return None


def _restore_interrupt(previous) -> None:
    if previous is not None:
        signal.signal(signal.SIGINT, previous)
