"""Timing checks of a platform model by clock zones: period observers, latencies and response times in one run.

One exploration by :class:`runtime.zones.search.ZoneExplorer` decides every
observer (is its ERROR condition reachable?) and gives the largest value of
every response-time observer; each verdict's trace is made concrete and
replayed on the tick model (runtime/zones/trace.py), so the trace printed is
the reference semantics' own.  docs/verification/platform.md (*Clock zones*) says why
zones and not ticks for these models.
"""
from __future__ import annotations

import dataclasses
import itertools
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, ClassVar

from genom2bip.verify.interrupts import CtrlC
from genom2bip.verify.model import Model, tick_us
from genom2bip.verify.options import Listener, SearchOptions
from genom2bip.verify.results import CheckResult, Figures, ObserverResult, Trace, Verdict
from genom2bip.verify.timing import observers, subject

#: Response-time observers: a clock up to a cap, or a pending request (a service whose codels can cycle).
RESPONSE_KINDS = ("response", "pending")
#: A response time not decided when the search stopped, but already past the observer's cap.
ABOVE_CAP = "above the cap so far"
#: Why a service has no bound when only an interruption ends it (a tracking service that pauses for ever).
UNTIL_STOPPED = "runs until stopped: once started, no final report without an interruption"
#: Why a service has no bound when its lasso keeps running the service itself (a tracking or polling service that
#: may end by itself, but need not): not a fault, unlike a request that waits.
KEEPS_RUNNING = "runs until stopped: works every period once started, may go on for ever (not a fault)"
#: Why a service's response time is not decided though the search ended: a cycle of zones keeps one of its requests
#: open, but no run found goes round one (a cycle closing through a covering zone need not be one any clock value
#: takes), so "no bound" is not shown, and neither is a bound.
NO_LASSO = "no bound shown: a cycle of zones keeps a request open, but no run found goes round one"
#: Lassos tried for a response without a bound: the first ``LASSO_CYCLES`` cycles of zones found, of which the first
#: ``LASSO_ROUNDS`` that clock values can go round, each reached by up to ``LASSO_PATHS`` paths.
LASSO_CYCLES, LASSO_ROUNDS, LASSO_PATHS = 200, 20, 8
#: Why a task's period holds and its response time is 0 without a search of its releases (build/timed.py idle_tasks).
IDLE = "nothing to run for this client: each period closes at the instant it opens, taking no core"


@dataclass
class ResponseResult(CheckResult):
    """The largest response time of a task (release to end of cycle) or a service (request to final report)."""

    check: ClassVar[str] = "response"

    observer: str = ""
    owner: str = ""  # the task or service: ``NDD.motion``, ``NDD.GoTo``
    kind: str = ""  # "task" or "service"
    value_ticks: int | None = None  # None: more than the cap, or no bound at all (``unbounded``)
    unbounded: bool = False  # a lasso: a request (or a cycle of the task) can wait for ever
    until_stopped: bool = False  # unbounded, and a service that once started ends only when interrupted
    keeps_running: bool = False  # unbounded, and the lasso's loop runs the service's own codels: it works, not waits
    cap_ticks: int = 0
    tick_us: int | None = None
    period_ticks: int | None = None  # a task's period

    def ms(self, ticks: int | None) -> float | None:
        return ticks * self.tick_us / 1000 if ticks is not None and self.tick_us else None

    @property
    def value_ms(self) -> float | None:
        return self.ms(self.value_ticks)

    @property
    def no_lasso(self) -> bool:
        """Not decided though the search ended: a cycle of zones keeps a request open, no run found goes round one
        (:data:`NO_LASSO`), rather than a limit stopping the search."""
        return self.verdict is Verdict.INCONCLUSIVE and self.message.startswith(NO_LASSO)

    def details(self) -> dict[str, Any]:
        return {"observer": self.observer, "owner": self.owner, "kind": self.kind, "value_ticks": self.value_ticks,
                "unbounded": self.unbounded, "until_stopped": self.until_stopped,
                "keeps_running": self.keeps_running,
                "value_ms": self.value_ms, "cap_ticks": self.cap_ticks, "cap_ms": self.ms(self.cap_ticks),
                "period_ms": self.ms(self.period_ticks)}


class ZonesUnsupported(Exception):
    """The model is outside what the zone explorer takes: the tick explorer decides it (the message says why)."""


#: The discrete states' programs may hold this share of the memory budget (at least search.py's PROGRAM_BYTES)
#: before those of the states already expanded are let go (written again when a new zone of theirs arrives).
PROGRAM_SHARE = 1 / 4


def explorer(model: Model, options: SearchOptions | None = None):
    """The zone explorer of a platform model; :class:`ZonesUnsupported` when it does not take the model."""
    from runtime.zones.model import Unsupported
    from runtime.zones.search import PROGRAM_BYTES, ZoneExplorer

    options = options or SearchOptions()
    budget = options.max_bytes
    programs = max(PROGRAM_BYTES, int(budget * PROGRAM_SHARE)) if budget else PROGRAM_BYTES
    try:
        return ZoneExplorer(model.package, model.root, options.externs, program_bytes=programs)
    except Unsupported as exc:
        raise ZonesUnsupported(str(exc)) from None


def _steps(timed_steps) -> tuple[list, list[int]]:
    """Runtime steps with one ``tick`` step per tick, and the ticks elapsed at each (the tick printers' shape)."""
    from genom2bip.build.timed import TICK
    from runtime.explore.space import Step

    steps, ticks, now = [], [], 0
    for ts in timed_steps:
        for _ in range(ts.ticks):
            now += 1
            steps.append(Step(TICK, -1, (), ()))
            ticks.append(now)
        if ts.step.label:
            steps.append(ts.step)
            ticks.append(now)
    return steps, ticks


def check_timing(model: Model, kinds=("overrun", "latency"), responses: bool = False,
                 options: SearchOptions | None = None, listener: Listener | None = None,
                 z=None) -> list[CheckResult]:
    """Every observer of ``kinds`` and, with ``responses``, every response time, from one zone exploration (by
    ``z``, a zone explorer of ``model`` that has not searched yet, if given).

    A violation is told to ``listener`` as soon as the search finds it (with its trace); the search ends when
    every observer asked for is violated and no response time is asked for.  Past ``options.time_limit``, past
    ``options.max_bytes`` (what the search holds or the process's growth, whichever is larger, with what reading it
    back will take: :data:`READ_BACK`), or at the first Ctrl-C (the second stops at once), it stops: the
    verdicts found are kept, the others are inconclusive, and each response time reached so far is kept as a
    lower bound (``limit`` says why).
    """
    from runtime.explore import StateSpace

    options = options or SearchOptions()
    listener = listener or Listener()
    if z is None or z.result is not None:
        z = explorer(model, options)
    tick = tick_us(model.package)
    space = StateSpace(model.package, model.root, options.externs, None, True, set())
    by_path = {fa.name: fa for fa in z.flat.atoms}
    atoms = observers(model, kinds)
    progress = listener.progress()
    watch = _Watch(z, model, atoms, responses, options, listener, progress, (space, tick, by_path))
    if options.max_states is None and options.time_limit is None and watch.memory is not None:
        listener.unbounded(watch.memory.limit, "--max-states or --time-limit")
    start = time.perf_counter()
    with watch.ctrl_c.watching():  # the first Ctrl-C stops the search once what it found is reported
        try:
            result = z.explore(max_states=options.max_states,
                               progress=_Budgeted(progress, watch) if watch.memory else progress)
        except _Stop as stop:
            progress.done()
            result = watch.stopped(stop.reason, time.perf_counter() - start)
        return _results(z, model, result, atoms, responses, watch, start, (space, tick, by_path))


#: Seconds between two lines of what a search has found so far (with --progress).
SO_FAR_PERIOD = 5.0
#: Bytes per node and per transition that a zone search stopped at --max-memory still needs: its end reads the
#: nodes and edges back from C as arrays (and the words its checks ask for) to make the traces.  Measured on whole
#: DALA at two cores: 0.73 GB for 4.0 million nodes and 12.7 million transitions.
READ_BACK = (120, 20)


def read_back(nodes: int, transitions: int) -> int:
    """The bytes a search of ``nodes`` nodes and ``transitions`` transitions needs to be read back (:data:`READ_BACK`),
    kept free under --max-memory."""
    return READ_BACK[0] * nodes + READ_BACK[1] * transitions


class _Budgeted:
    """The listener's progress line, its memory the figure --max-memory bounds (what reading back will take
    included)."""

    def __init__(self, progress, watch: "_Watch") -> None:
        self.progress, self.watch = progress, watch

    def tick(self, states, transitions, frontier, memory, depth=None) -> None:
        bound = self.watch.memory
        self.progress.tick(states, transitions, frontier, lambda: bound.taken(read_back(states, transitions)), depth)

    def done(self) -> None:
        self.progress.done()


class _Stop(Exception):
    """Raised in the search by :class:`_Watch`: a budget is spent, Ctrl-C was pressed, or all is decided."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


class _Watch:
    """Looks at a zone search as it goes: violations told as found, budgets, Ctrl-C, lines so far.

    It is the explorer's ``watcher``, which sees the search's live result (runtime/zones/search.py); the search
    itself is not changed.
    """

    def __init__(self, z, model, atoms, responses, options, listener, progress, where) -> None:
        from runtime.explore.search import MemoryBound

        self.z, self.model, self.atoms, self.responses = z, model, atoms, responses
        self.listener, self.progress, self.where = listener, progress, where
        self.by_index = {where[2][a.path].index: a for a in atoms}
        self.deadline = time.monotonic() + options.time_limit if options.time_limit else None
        #: --max-memory: what the search holds or the process's growth, and what reading it back will take
        self.memory = MemoryBound(z, options.max_bytes) if options.max_bytes is not None else None
        self.start = time.perf_counter()
        self.next_line = time.monotonic() + SO_FAR_PERIOD
        self.result = None
        self.ctrl_c = CtrlC()
        self.told: dict[str, ObserverResult] = {}  # observer -> its violation, told as found
        self.shown = ""
        self.clocks = {}  # response clock -> (owner, cap)
        names = _owners(model)
        for atom in observers(model, ("response",)) if responses else []:
            owner = names.get(atom.path) or atom.path.rsplit(".", 1)[0]
            self.clocks[z.model.measures[where[2][atom.path].index][1]] = (owner, atom.bound)
        z.watcher = self.seen

    def seen(self, result) -> None:
        self.result = result
        for index, node in result.violations.items():
            atom = self.by_index.get(index)
            if atom is not None and atom.path not in self.told:
                self.told[atom.path] = found = self.violation(atom, node, len(self.z.nodes))
                self.progress.done()
                self.listener.found(found)
        if self.atoms and len(self.told) == len(self.atoms) and not self.responses:
            raise _Stop("decided")
        if self.ctrl_c.pressed:
            raise _Stop("interrupted")
        now = time.monotonic()
        if self.deadline is not None and now >= self.deadline:
            raise _Stop("time-limit")
        if self.memory is not None and self.memory.exceeded(read_back(result.states, result.transitions)):
            raise _Stop("max-memory")
        if now >= self.next_line and self.progress.on:
            self.next_line = now + SO_FAR_PERIOD
            line = self.so_far(result)
            if line and line != self.shown:
                self.shown = line
                self.progress.done()
                self.listener.so_far(line)

    def violation(self, atom, node: int, states: int) -> ObserverResult:
        """The verdict of an observer whose ERROR the search reached at ``node``, with its trace."""
        seconds = time.perf_counter() - self.start
        space, tick, by_path = self.where
        clock = self.z.model.observers[by_path[atom.path].index][1]
        trace, message = _trace_to(self.z, node, [(0, clock, -(atom.bound + 1))], space, tick)
        return ObserverResult(subject(atom, tick), Verdict.VIOLATED, trace=trace, message=message,
                              figures=Figures(states=states, seconds=seconds),
                              method="zones, found on the way", observer=atom.path,
                              kind=atom.kind, bound_ticks=atom.bound, tick_us=tick)

    def so_far(self, result) -> str:
        """``A.x ≥ 40 ms, B.y ≥ 12 ms``: the largest response times reached, lower bounds while the search runs."""
        tick = self.where[1]
        parts = []
        for clock, (owner, cap) in self.clocks.items():
            top = result.maxima.get(clock, (-1.0, -1))[0]
            if top > cap:
                parts.append(f"{owner} > {cap * tick / 1000:g} ms")
            elif top >= 0:
                parts.append(f"{owner} ≥ {top * tick / 1000:g} ms")
        return ", ".join(parts)

    def stopped(self, reason: str, seconds: float):
        """The search's result where :class:`_Stop` left it."""
        from runtime.zones.search import ZoneResult

        result = self.result or ZoneResult(0, 0, 0, 0.0, False)
        result.complete, result.stopped = False, reason
        result.states, result.seconds = len(self.z.nodes), seconds
        if not result.discrete:  # the C search counts them; the Python one only at its end
            result.discrete = len({n.state for n in self.z.nodes})
        return result


def _results(z, model, result, atoms, responses, watch, start, where) -> list[CheckResult]:
    """The verdicts and response times of a search that ended (complete or not)."""
    space, tick, by_path = where
    figures = Figures(states=result.states, transitions=result.transitions, seconds=time.perf_counter() - start)
    method = f"zones, {result.discrete:,} discrete states"
    out: list[CheckResult] = []
    idle = idle_owners(model)
    decided = result.stopped == "decided"
    inconclusive = Verdict.INCONCLUSIVE if not result.complete and not decided else None
    for atom in atoms:
        fa = by_path[atom.path]
        node = result.violations.get(fa.index)
        common = dict(figures=figures, method=method, observer=atom.path, kind=atom.kind, bound_ticks=atom.bound,
                      tick_us=tick)
        if atom.path.rsplit(".", 1)[0] in idle:
            out.append(ObserverResult(subject(atom, tick), Verdict.HOLDS, message=IDLE, **common))
        elif atom.path in watch.told:  # told as found: the same verdict and trace, with the whole search's figures
            out.append(dataclasses.replace(watch.told[atom.path], figures=figures, method=method))
        elif node is not None:
            clock = z.model.observers[fa.index][1]
            trace, message = _trace_to(z, node, [(0, clock, -(atom.bound + 1))], space, tick)
            out.append(ObserverResult(subject(atom, tick), Verdict.VIOLATED, trace=trace, message=message, **common))
        else:
            out.append(ObserverResult(subject(atom, tick), inconclusive or Verdict.HOLDS,
                                      limit=result.stopped if inconclusive else "", **common))
    if responses:
        for atom in observers(model, ("response", "pending")):
            out.append(_response(z, model, result, atom, by_path, space, tick, figures, method, inconclusive))
    return out


def _trace_to(z, node: int, goal: list, space, tick) -> tuple[Trace | None, str]:
    """A trace to ``node`` where ``goal`` holds at its end (:func:`_trace` of the paths there)."""
    from runtime.zones.trace import paths_to

    return _trace(z, ((p, None) for p in paths_to(z, node, goal)), goal, space, tick)


def _trace(z, paths, goal, space, tick) -> tuple[Trace | None, str]:
    """The first of ``paths`` that replays on the tick model, as a timed trace: ``(path, loop)`` pairs, ``loop``
    the index of a lasso's entry in ``path`` (None for a path)."""
    from runtime.zones.trace import ConcretizeError, replay

    problem = "no path"
    for path, loop in paths:
        try:
            timed_steps, _ = replay(z, path, goal, space)
            break
        except ConcretizeError as exc:
            problem = str(exc)
    else:
        return None, f"no concrete trace: {problem}"
    steps, ticks = _steps(timed_steps)
    at = None
    if loop is not None:  # the printed step after which the loop starts: the entry's own step, ticks included
        at = sum(ts.ticks + (1 if ts.step.label else 0) for ts in timed_steps[:loop])
    return Trace(steps, loop=at, ticks=ticks, tick_us=tick), ""


def _timed(model: Model, key: str) -> list[str]:
    """The comma-separated argument ``key`` of the model's ``@timed`` annotation (none for an untimed model)."""
    ann = next((a for a in model.package.annotations if a.name == "timed"), None)
    return [x for x in (ann.arguments.get(key, "") if ann is not None else "").split(",") if x]


def idle_owners(model: Model) -> set[str]:
    """The tasks with nothing to run for the model's client, whose releases were not searched (``IDLE``)."""
    return set(_timed(model, "idle"))


def _owners(model: Model) -> dict[str, str]:
    """Observer instance -> the service it measures, for the service observers at the root (``@timed``)."""
    return dict(p.split("=", 1) for p in _timed(model, "responses") if "=" in p)


def _response(z, model, result, atom, by_path, space, tick, figures, method, inconclusive) -> ResponseResult:
    """One response time: the largest value of the observer's clock, or no bound shown by a lasso."""
    from runtime.zones.search import lassos
    from runtime.zones.trace import loop_needs, paths_to

    fa = by_path[atom.path]
    owner = _owners(model).get(atom.path) or atom.path.rsplit(".", 1)[0]
    timer = by_path.get(owner + ".timer")  # a task's observer sits beside its timer
    period = int(timer.constants["ticks"][0]) if timer is not None else None
    common = dict(figures=figures, method=method, observer=atom.path, owner=owner,
                  kind="task" if timer is not None else "service",
                  cap_ticks=atom.bound, tick_us=tick, period_ticks=period,
                  limit=result.stopped if inconclusive else "")
    subject_text = f"response time of {owner}"
    if owner in idle_owners(model):
        return ResponseResult(subject_text, Verdict.HOLDS, value_ticks=0, message=IDLE, **common)
    watch = fa.place_mask(["WATCH"])
    offset = fa.offset
    if atom.kind == "response":
        place, clock = z.model.measures[fa.index]
        top, node = result.maxima.get(clock, (-1.0, -1))
        if node >= 0 and not math.isinf(top) and top <= atom.bound:
            value = max(0, int(top))
            trace, message = _trace_to(z, node, [(0, clock, -value)], space, tick)
            return ResponseResult(subject_text, inconclusive or Verdict.HOLDS, trace=trace, message=message,
                                  value_ticks=value, **common)
        if node < 0:
            return ResponseResult(subject_text, inconclusive or Verdict.HOLDS, value_ticks=None,
                                  message="never requested", **common)
    elif not inconclusive and not (z.node_words(offset) == watch).any():  # no state watches a request of it
        return ResponseResult(subject_text, Verdict.HOLDS, value_ticks=None, message="never requested", **common)
    if inconclusive:
        above = atom.kind == "response" and node >= 0
        return ResponseResult(subject_text, inconclusive, value_ticks=None, message=ABOVE_CAP if above else "",
                              **common)
    cycles = lassos(z, offset, watch)
    first = next(cycles, None)
    if first is None:
        message = ("every request ends, after more than the cap" if atom.kind == "response" else
                   "every request ends (not measured: its codels can cycle)")
        return ResponseResult(subject_text, Verdict.HOLDS, value_ticks=None, message=message, **common)
    # the builder read the service's codels: none reached from its start yields ether or throws
    stopped = owner in _timed(model, "until_stopped")
    # a cycle of zones whose round no clock value can take (it closes through a covering zone) is passed over
    cycles = itertools.chain([first], cycles)
    rounds = itertools.islice(((entry, loop, need) for entry, loop in itertools.islice(cycles, LASSO_CYCLES)
                               for need in [loop_needs(z, loop)] if need is not None), LASSO_ROUNDS)
    ways = ((head + loop, len(head) - 1) for entry, loop, need in rounds
            for head in itertools.islice(paths_to(z, entry, need=need), LASSO_PATHS))
    trace, message = _trace(z, ways, [], space, tick)
    if trace is None and not stopped:  # a cycle of zones alone shows no run that waits for ever
        return ResponseResult(subject_text, Verdict.INCONCLUSIVE, value_ticks=None, message=f"{NO_LASSO} ({message})",
                              **common)
    running = not stopped and common["kind"] == "service" and _runs_in_loop(trace, owner)
    word = UNTIL_STOPPED if stopped else KEEPS_RUNNING if running else "a request can wait for ever"
    return ResponseResult(subject_text, Verdict.VIOLATED, trace=trace, value_ticks=None, unbounded=True,
                          until_stopped=stopped, keeps_running=running,
                          message=f"{word} ({message})" if message else word, **common)


def _runs_in_loop(trace: Trace | None, owner: str) -> bool:
    """The lasso's loop executes ``owner``'s codels: the request was started and keeps working, period after period
    (a request that waits for a start or a core it never gets does not)."""
    if trace is None or trace.loop is None:
        return False
    return any(getattr(step, "label", "").startswith(f"{owner}:exec") for step in trace.steps[trace.loop:])


@dataclass
class ResponseTimes(CheckResult):
    """Every response time of a model from one exploration: holds when each one has a bound, violated when one
    has none (``trace``: its lasso), inconclusive when the search stopped (the values so far are not maxima) or
    when no run shows whether one has a bound (:data:`NO_LASSO`)."""

    check: ClassVar[str] = "response-times"

    responses: list[ResponseResult] = field(default_factory=list)

    def values(self) -> dict[str, float | str]:
        """Each owner's response time in ms, or in words where there is no number (``unbounded``, ``until
        stopped``, ``never requested``, ``more than 200 ms``, ``inconclusive``, ``bounded, not measured``)."""
        return {r.owner: response_value(r) for r in self.responses}

    def details(self) -> dict[str, Any]:
        return {"values": self.values(), "responses": [r.to_json() for r in self.responses]}


def response_value(r: ResponseResult) -> float | str:
    """A response time as a number of ms, or a word saying why there is none."""
    if r.verdict is Verdict.INCONCLUSIVE:
        return "inconclusive"
    if r.until_stopped or r.keeps_running:
        return "until stopped"
    if r.unbounded:
        return "unbounded"
    if r.value_ticks is not None:
        return r.value_ms
    if r.message == "never requested":
        return r.message
    if r.kind == "service" and "not measured" in r.message:
        return "bounded, not measured"
    return f"more than {r.ms(r.cap_ticks):g} ms"


def check_response_times(model: Model, options: SearchOptions | None = None, listener: Listener | None = None,
                         owners: Callable[[ResponseResult], bool] | None = None) -> ResponseTimes:
    """Every task's and service's response time (:func:`check_timing` with ``responses``), as one result;
    ``owners`` keeps some (the tasks): the verdict is theirs."""
    found = [r for r in check_timing(model, (), True, options, listener) if isinstance(r, ResponseResult)]
    if not found:
        raise LookupError("no response-time observer in this model: build it with TimeSettings(responses=True)")
    found = [r for r in found if owners is None or owners(r)]
    if not found:
        raise LookupError("no task or service of this model is among those asked for")
    first = found[0]
    unbounded = [r for r in found if r.unbounded]
    stopped = [r for r in found if r.verdict is Verdict.INCONCLUSIVE and not r.no_lasso]
    undecided = [r.owner for r in found if r.no_lasso]
    waiting = [r.owner for r in unbounded if not (r.until_stopped or r.keeps_running)]
    running = [r.owner for r in unbounded if r.until_stopped or r.keeps_running]
    if stopped:
        verdict, message = Verdict.INCONCLUSIVE, f"stopped by {first.limit or 'a limit'}: the values are not maxima"
    elif unbounded:
        verdict, message = Verdict.VIOLATED, "; ".join(
            ([f"no bound: {', '.join(waiting)}"] if waiting else [])
            + ([f"run until stopped: {', '.join(running)}"] if running else [])
            + ([f"not decided: {', '.join(undecided)}"] if undecided else []))
    elif undecided:
        verdict, message = Verdict.INCONCLUSIVE, f"not decided: {', '.join(undecided)} (no run found goes round " \
                                                 f"the cycles of zones that keep a request open)"
    else:
        verdict, message = Verdict.HOLDS, "every response time has a bound"
    return ResponseTimes(f"response times of {model.title}", verdict, first.figures,
                         unbounded[0].trace if unbounded and not stopped else None, first.method,
                         first.limit if stopped else "", message, responses=found)


def response_owners(model: Model) -> dict[str, str]:
    """The tasks and services whose response times the model measures: owner -> ``task`` or ``service``."""
    names = _owners(model)
    out = {}
    for atom in observers(model, RESPONSE_KINDS):
        owner = names.get(atom.path) or atom.path.rsplit(".", 1)[0]
        out[owner] = "service" if atom.path in names else "task"
    return out
