"""Random runs of a tick model: the exhaustive model's own runs, chosen by a stochastic policy (docs/smc.md).

A run starts in the initial state and fires, at each step, one of the
interactions the model enables (the compiled step lists them, with one
successor per codel outcome).  The policy only *chooses* among them:

* when a scheduler's ``exec`` starts a codel (the scheduler is BUSY, ``x``
  counting its ticks in ``[lo, hi]``), its duration ``D`` is drawn in that
  interval from the codel's distribution; the codel's end (``done``) is then
  taken when ``x`` reaches ``D`` and not before, and time (``tick``) does not
  pass while a codel has reached its ``D``;
* a *window* (an atom waiting in a place for a clock to reach a time drawn
  in ``[lo, hi]``: a task's suspension, its first period's delay) is drawn
  uniformly the same way when the atom enters the place, and its end port
  is taken when the clock reaches it;
* among the codel outcomes of one interaction, the outcome is drawn with the
  weights given for it (a GenoM3 ``.proba`` file), uniformly where none is
  given;
* every other choice (which enabled interaction fires, time passing
  included: the scheduler's ties, the environment's requests) is uniform.

A run is identified by ``(seed, index)`` alone (:func:`run_seed`): the same
run comes out on any worker, in any order.

Two things make runs cheap without changing their distribution: ticks that
change nothing but clocks are taken in one *leap* (runtime/smc/leaps.py),
the ticks a race with other interactions lets pass drawn at once from the
geometric law the tick-by-tick choice gives; and on the compiled step the
loop runs in C (runtime/smc/srun.c, from other random numbers).
"""
from __future__ import annotations

import ctypes
import math
import random
from dataclasses import dataclass, field
from typing import Any

from runtime.smc.leaps import FAR, Leaps, _nearer
from runtime.smc.sampling import UNIFORM, Distribution
from runtime.zones.model import Unsupported

#: Steps a run may take per tick of its horizon (and a floor) before it is stopped as time-blocked (Zeno).
STEPS_PER_TICK = 1000
MIN_STEPS = 100_000
#: Places and variables of a platform scheduler atom that the duration draws read.
BUSY, CLOCK, LOW, HIGH = "BUSY", "x", "lo", "hi"


def run_seed(seed: int, index: int) -> random.Random:
    """The random source of run ``index`` under ``seed``: the same whoever computes it (str seeds are hashed
    by SHA-512, stable across processes and machines)."""
    return random.Random(f"genom2bip-smc/{seed}/{index}")


@dataclass(frozen=True)
class Goal:
    """phi: atom ``atom`` has place ``place`` marked (an observer in ERROR); or, with ``label``, ``psi U chi``:
    an interaction labelled ``label`` is taken before any labelled in ``before`` (``atom`` then only names the
    goal)."""

    name: str
    atom: str
    place: str = "ERROR"
    label: str = ""
    before: tuple[str, ...] = ()


@dataclass(frozen=True)
class Watch:
    """A response time: from an interaction of ``opens`` to one of ``closes`` (labels); a second opening while
    one is watched keeps the first, as the response-time observers do."""

    name: str
    opens: tuple[str, ...]
    closes: tuple[str, ...]


@dataclass(frozen=True)
class Window:
    """Atom ``atom`` waits in ``place`` until its clock ``clock`` reaches a time in ``[lo, hi]`` (constants or
    variables of the atom) and leaves by port ``end``: the time is drawn when it enters."""

    atom: str
    place: str
    clock: str
    lo: str
    hi: str
    end: str


@dataclass
class SimConfig:
    """What a simulator needs beside the model: plain data, sent to the workers as is."""

    tick_us: int
    horizon: int  # ticks: Pr[<= horizon]
    goals: list[Goal] = field(default_factory=list)
    watches: list[Watch] = field(default_factory=list)
    schedulers: list[str] = field(default_factory=list)  # atoms whose BUSY codel duration is drawn
    windows: list[Window] = field(default_factory=list)  # waits whose end is drawn uniformly
    durations: dict[str, Distribution] = field(default_factory=dict)  # "Component.Owner.codel"
    weights: dict[tuple[str, str, str], float] = field(default_factory=dict)  # ("Comp.Owner", state, outcome)
    tick_label: str = "tick"
    keep_going: bool = False  # run to the horizon even when every goal is reached (response times)
    leap: bool = True  # take the ticks that change nothing but clocks in one leap (runtime/smc/leaps.py)
    native: bool = True  # the run loop in C (runtime/smc/srun.c) when the step is compiled


@dataclass
class RunOutcome:
    """One run: the tick at which each goal was first reached (None: not by the horizon), the response times
    seen (ticks, per watch), the ticks and steps it took, and how it ended."""

    index: int
    reached: list[int | None]
    responses: list[list[int]]
    ticks: int
    steps: int
    end: str  # "horizon", "goals", "deadlock", "zeno"
    choices: list[tuple[int, int]] | None = None  # (interaction index, rank among its successors) per step
    reached_steps: list[int | None] = field(default_factory=list)  # the step count when each goal was reached
    start: int = 0  # the initial state it started from (a number of the state space)


@dataclass
class _Info:
    """What the policy needs of one interaction."""

    index: int
    label: str
    tick: bool
    execs: tuple[int, ...]  # schedulers it starts a codel of
    dones: tuple[int, ...]  # schedulers it ends the codel of
    opens: tuple[int, ...]
    closes: tuple[int, ...]
    ends: tuple[int, ...] = ()  # windows it ends
    hits: tuple[int, ...] = ()  # goals ``label U`` it reaches
    cancels: tuple[int, ...] = ()  # goals it makes unreachable (one of their ``before``)
    prefix: str = ""  # "Comp.Owner" of an exec_<state> label
    state: str = ""
    made: list[tuple[tuple[Any, int], ...]] | None = None  # per successor rank: the codel calls and outcomes


class Simulator:
    """Runs of ``space`` (a :class:`runtime.explore.StateSpace`) under ``config``, on the compiled step when
    ``compiled`` (a :class:`runtime.native.compiled.CompiledSpace`) is given, else on the Python step."""

    def __init__(self, space, compiled, config: SimConfig) -> None:
        self.space, self.config = space, config
        flat = space.engine.flat
        atoms = {fa.name: fa for fa in flat.atoms}
        self.goal_slots = []
        for g in config.goals:
            if g.label:
                self.goal_slots.append((-1, 0))  # reached by an interaction (_Info.hits), not by a place
                continue
            fa = atoms[g.atom]
            self.goal_slots.append((fa.offset, 1 << fa.places.index(g.place)))
        self.scheds = []  # (name, marking slot, BUSY bit, x, lo, hi)
        for name in config.schedulers:
            fa = atoms[name]
            self.scheds.append((name, fa.offset, 1 << fa.places.index(BUSY), fa.slot(CLOCK), fa.slot(LOW),
                                fa.slot(HIGH)))
        self.windows = []  # (marking slot, place bit, clock slot, lo, hi): lo and hi a constant or a slot
        for w in config.windows:
            fa = atoms[w.atom]
            bounds = [("const", fa.constants[b][0]) if b in fa.constants else ("slot", fa.slot(b))
                      for b in (w.lo, w.hi)]
            self.windows.append((fa.offset, 1 << fa.places.index(w.place), fa.slot(w.clock), *bounds))
        self.infos: dict[int, _Info] = {}
        self.step = _CStep(compiled) if compiled is not None else _PyStep(space)
        self.weighted = {(p, s) for p, s, _ in config.weights}
        self.leaps: Leaps | None = None
        self.no_leaps = ""  # why the runs go tick by tick (config.leap asked for leaps)
        if config.leap:
            try:
                self.leaps = Leaps(flat.package, flat.root, flat)
            except Unsupported as exc:
                self.no_leaps = f"runs tick by tick: {exc}"
        self.native = None  # the runs in C (CRuns), when the step is compiled and a C compiler is found
        if compiled is not None and config.native:
            from runtime.smc.crun import CRuns, library

            lib = library()
            if lib is not None:
                self.native = CRuns(self, lib)

    # -- interactions ---------------------------------------------------------------------------------
    def info(self, number: int) -> _Info:
        got = self.infos.get(number)
        if got is None:
            inter = self.space.interaction(self.step.index(number))
            ports = set(inter.ports)
            label = inter.label
            execs = tuple(k for k, s in enumerate(self.scheds) if f"{s[0]}.exec" in ports)
            dones = tuple(k for k, s in enumerate(self.scheds) if f"{s[0]}.done" in ports)
            opens = tuple(k for k, w in enumerate(self.config.watches) if label in w.opens)
            closes = tuple(k for k, w in enumerate(self.config.watches) if label in w.closes)
            prefix, _, port = label.partition(":")
            state = port[len("exec_"):] if port.startswith("exec_") else ""
            ends = tuple(k for k, w in enumerate(self.config.windows) if f"{w.atom}.{w.end}" in ports)
            hits = tuple(k for k, g in enumerate(self.config.goals) if g.label and g.label == label)
            cancels = tuple(k for k, g in enumerate(self.config.goals) if g.label and label in g.before)
            got = self.infos[number] = _Info(inter.index, label, label == self.config.tick_label, execs, dones,
                                             opens, closes, ends, hits, cancels, prefix, state)
        return got

    def _made(self, info: _Info, count: int) -> list | None:
        """The codel calls of each successor of ``info`` here (the Python step's odometer order, which the
        compiled step keeps); None when they do not line up (the compiled step merged equal successors)."""
        if info.made is not None and len(info.made) == count:
            return info.made
        state = self.step.current()
        made = [m for inter, _, m in self.space._fire_all(state) if inter.index == info.index]
        if len(made) != count:
            return None
        info.made = made
        return made

    def _weight(self, info: _Info, made) -> float:
        w = 1.0
        if (info.prefix, info.state) not in self.weighted:
            return w
        for choice, pos in made:
            name = choice.names[pos] if pos < len(choice.names) else str(choice.values[pos])
            w *= self.config.weights.get((info.prefix, info.state, name), 0.0)
        return w

    def _duration(self, info: _Info, made) -> Distribution:
        if not self.config.durations or not made:
            return UNIFORM
        return self.config.durations.get(f"{info.prefix}.{made[0][0].name}", UNIFORM)

    def _enter(self, waits: dict[int, int], rng: random.Random, step, tick_us: int) -> None:
        """Draw the end of every window just entered; forget those left."""
        for k, (mark, bit, _, lo, hi) in enumerate(self.windows):
            inside = step.value(mark) & bit
            if inside and k not in waits:
                low = lo[1] if lo[0] == "const" else step.value(lo[1])
                high = hi[1] if hi[0] == "const" else step.value(hi[1])
                waits[k] = UNIFORM.draw_ticks(rng, low, high, tick_us)
            elif not inside and k in waits:
                del waits[k]

    def _leap(self, step, handle: int, drawn: dict[int, int], waits: dict[int, int]) -> int:
        """How many ticks from here compare every clock alike (Leaps.length), the drawn ends of codels and waits
        included; ``self.rates`` becomes each clock's change by one tick (read on the tick successor ``handle``)."""
        value = step.value
        rates = {slot: step.peek(handle, slot) - value(slot) for slot in self.leaps.clocks}
        self.rates = rates
        span = self.leaps.length(value, rates)
        for k, d in drawn.items():
            x = self.scheds[k][3]
            if rates.get(x):
                span = _nearer(span, d - value(x))
        for k, d in waits.items():
            c = self.windows[k][2]
            if rates.get(c):
                span = _nearer(span, d - value(c))
        return span

    # -- one run --------------------------------------------------------------------------------------------
    def run(self, seed: int, index: int, record: bool = False) -> RunOutcome:
        """Run ``index`` under ``seed``, up to the horizon (or until every goal is reached)."""
        cfg = self.config
        rng = run_seed(seed, index)
        step = self.step
        initial = self.space.initial_ids
        start = initial[rng.randrange(len(initial))] if len(initial) > 1 else initial[0]
        horizon, tick_us = cfg.horizon, cfg.tick_us
        limit = max(MIN_STEPS, STEPS_PER_TICK * (horizon + 1))
        if self.native is not None:
            words = [rng.getrandbits(64) for _ in range(4)]
            end, reached, at_step, responses, ticks, steps, made = self.native.run(
                words, self.space.state(start), horizon, limit, record)
            choices = None if made is None else [((self.infos.get(n) or self.info(n)).index, r) for n, r in made]
            return RunOutcome(index, reached, responses, ticks, steps, end, choices, at_step, start)
        step.start(self.space.state(start))
        goals = self.goal_slots
        reached: list[int | None] = [None] * len(goals)
        at_step: list[int | None] = [None] * len(goals)
        left = len(goals)
        cancelled: set[int] = set()  # goals ``U`` whose ``before`` came first
        responses: list[list[int]] = [[] for _ in cfg.watches]
        since: list[int | None] = [None] * len(cfg.watches)
        drawn: dict[int, int] = {}  # scheduler -> drawn duration of its running codel
        waits: dict[int, int] = {}  # window -> drawn time of its end
        windows = self.windows
        if windows:
            self._enter(waits, rng, step, tick_us)
        scheds = self.scheds
        now = steps = 0
        choices: list[tuple[int, int]] | None = [] if record else None
        end = "horizon"
        leaps = self.leaps
        forced = False  # the last leap ended where the race with time is lost: one of the others fires now
        while True:
            groups = step.expand()
            if not groups:
                end = "deadlock"
                break
            allowed = groups
            if drawn or waits:
                due = False
                for k, d in drawn.items():
                    if step.value(scheds[k][3]) >= d:
                        due = True
                        break
                for k, d in waits.items():
                    if step.value(windows[k][2]) >= d:
                        due = True
                        break
                allowed = []
                for number, handles in groups:
                    info = self.infos.get(number) or self.info(number)
                    if info.tick:
                        if due:
                            continue
                    elif _early(step, info.dones, drawn, scheds, 3):
                        continue
                    if _early(step, info.ends, waits, windows, 2):
                        continue
                    allowed.append((number, handles))
                if not allowed:  # the policy found nothing the model allows: keep to the model
                    allowed = groups
            if leaps is not None:
                tick = next((k for k, (n, _) in enumerate(allowed) if (self.infos.get(n) or self.info(n)).tick),
                            None)
                if tick is not None:
                    others = len(allowed) - 1
                    # the ticks the tick path takes before one of the others: P(at least j) = (1/(others+1))^j
                    passing = 0 if forced else FAR if not others else _geometric(rng, 1 / (others + 1))
                    forced = False
                    if passing:
                        if now >= horizon:
                            break
                        handle = allowed[tick][1][0]
                        span = self._leap(step, handle, drawn, waits)
                        n = min(passing, span, horizon - now)
                        if n == span and n > 1:
                            # the tick that ends the span may do more than add to clocks: stop one before it (the
                            # race starts again there; the ticks still to pass are geometric again, memoryless)
                            n -= 1
                            step.advance(self.rates, n)
                            forced = False
                        else:
                            step.take(handle)
                            if n > 1:
                                step.advance(self.rates, n - 1)
                            forced = n == passing and n < span  # the race is lost at the n-th tick
                        now += n
                        steps += 1
                        if record:
                            choices.extend([(self.infos[allowed[tick][0]].index, 0)] * n)
                        if left:
                            left -= _places_reached(goals, reached, at_step, step, now,
                                                    len(choices) if record else steps)
                            if not left and not cfg.keep_going:
                                end = "goals"
                                break
                        if steps >= limit:
                            end = "zeno"
                            break
                        continue
                    allowed = allowed[:tick] + allowed[tick + 1:]
                forced = False
            number, handles = allowed[rng.randrange(len(allowed))] if len(allowed) > 1 else allowed[0]
            info = self.infos.get(number) or self.info(number)
            if info.tick and now >= horizon:
                break
            rank = 0
            made = None
            if len(handles) > 1:
                made = self._made(info, len(handles))
                weights = [self._weight(info, m) for m in made] if made is not None else None
                if weights is not None and sum(weights) > 0:
                    rank = rng.choices(range(len(handles)), weights)[0]
                else:
                    rank = rng.randrange(len(handles))
            elif info.execs and cfg.durations:
                made = self._made(info, 1)
            step.take(handles[rank])
            steps += 1
            if record:
                choices.append((info.index, rank))
            if info.tick:
                now += 1
            for k in info.dones:
                drawn.pop(k, None)
            for k in info.execs:
                _, mark, busy, _, lo, hi = scheds[k]
                if step.value(mark) & busy:
                    dist = self._duration(info, made[rank] if made is not None else None)
                    drawn[k] = dist.draw_ticks(rng, step.value(lo), step.value(hi), tick_us)
            if windows:
                self._enter(waits, rng, step, tick_us)
            for w in info.opens:
                if since[w] is None:
                    since[w] = now
            for w in info.closes:
                if since[w] is not None:
                    responses[w].append(now - since[w])
                    since[w] = None
            if left:
                for g in info.cancels:
                    if reached[g] is None and g not in cancelled:
                        cancelled.add(g)
                        left -= 1
                for g in info.hits:
                    if reached[g] is None and g not in cancelled:
                        reached[g], at_step[g] = now, len(choices) if record else steps
                        left -= 1
                left -= _places_reached(goals, reached, at_step, step, now, len(choices) if record else steps)
                if not left and not cfg.keep_going:
                    end = "goals"
                    break
            if steps >= limit:
                end = "zeno"
                break
        return RunOutcome(index, reached, responses, now, steps, end, choices, at_step, start)


def _places_reached(goals, reached, at_step, step, now: int, at: int) -> int:
    """The goals given as a place (``(slot, bit)``, slot >= 0) that the step's state is in, marked reached now at
    step ``at``: how many were not reached before."""
    met = 0
    for g, (slot, bit) in enumerate(goals):
        if reached[g] is None and slot >= 0 and step.value(slot) & bit:
            reached[g], at_step[g] = now, at
            met += 1
    return met


class _CStep:
    """The compiled step, one state at a time: the current state stays in C words."""

    def __init__(self, compiled) -> None:
        from runtime.native.values import to_words

        if not compiled.searching:  # the optimised build (the search's) has the same one-step entry
            compiled.searching = True
            compiled.build(parallel=False)
        self.cs, self.to_words = compiled, to_words
        self.w = compiled.width
        self.cap = 64
        self._alloc()
        self.cur = (ctypes.c_int64 * self.w)()
        self.numbers: dict[int, int] = {}

    def _alloc(self) -> None:
        self.out = (ctypes.c_int64 * (self.w * self.cap))()
        self.via = (ctypes.c_int64 * self.cap)()

    def index(self, number: int) -> int:
        got = self.numbers.get(number)
        if got is None:
            got = self.numbers[number] = self.cs.interaction_index(number)
        return got

    def start(self, state: tuple) -> None:
        self.cur[:] = self.to_words(self.cs.model, state)
        self.src = self.cur
        self.base = 0

    def value(self, slot: int) -> int:
        return self.src[self.base + slot]

    def current(self) -> tuple:
        return self.cs._typed(self.src[self.base:self.base + self.w])

    def expand(self) -> list[tuple[int, list[int]]]:
        cs, code, arg = self.cs, ctypes.c_int(0), ctypes.c_int64(0)
        if self.src is not self.cur:
            ctypes.memmove(self.cur, ctypes.byref(self.out, self.base * 8), self.w * 8)
            self.src, self.base = self.cur, 0
        while True:
            n = cs.lib.c_successors(self.cur, self.out, self.via, self.cap, cs.budget, ctypes.byref(code),
                                    ctypes.byref(arg))
            if n >= 0:
                break
            if code.value == 8:  # a field too narrow: widen (a rebuild) and redo
                cs._widen(arg.value)
                self.numbers.clear()
                continue
            if code.value == 10 and self.cap < 65536:
                self.cap *= 16
                self._alloc()
                continue
            from runtime.native.compiled import _CError
            raise _CError(code.value, arg.value)
        groups: list[tuple[int, list[int]]] = []
        via = self.via
        last = None
        for i in range(n):
            v = via[i]
            if v != last:
                groups.append((v, [i]))
                last = v
            else:
                groups[-1][1].append(i)
        return groups

    def take(self, handle: int) -> None:
        self.src, self.base = self.out, handle * self.w

    def peek(self, handle: int, slot: int) -> int:
        """The value of ``slot`` in successor ``handle`` of the last expansion."""
        return self.out[handle * self.w + slot]

    def advance(self, rates: dict[int, int], times: int) -> None:
        """Add ``times`` ticks' worth of each clock's rate to the current state."""
        if self.src is not self.cur:
            ctypes.memmove(self.cur, ctypes.byref(self.out, self.base * 8), self.w * 8)
            self.src, self.base = self.cur, 0
        cur = self.cur
        for slot, r in rates.items():
            if r:
                cur[slot] += r * times


class _PyStep:
    """The Python step (no C compiler): the engine's own successors."""

    def __init__(self, space) -> None:
        self.space = space
        self.state: tuple = ()
        self.succ: list = []

    def index(self, number: int) -> int:
        return number

    def start(self, state: tuple) -> None:
        self.state = state

    def value(self, slot: int):
        return self.state[slot]

    def current(self) -> tuple:
        return self.state

    def expand(self) -> list[tuple[int, list[int]]]:
        self.succ = self.space._fire_all(self.state)
        groups: list[tuple[int, list[int]]] = []
        for i, (inter, _, _) in enumerate(self.succ):
            if groups and groups[-1][0] == inter.index:
                groups[-1][1].append(i)
            else:
                groups.append((inter.index, [i]))
        return groups

    def take(self, handle: int) -> None:
        self.state = self.succ[handle][1]

    def peek(self, handle: int, slot: int):
        return self.succ[handle][1][slot]

    def advance(self, rates: dict[int, int], times: int) -> None:
        state = list(self.state)
        for slot, r in rates.items():
            if r:
                state[slot] += r * times
        self.state = tuple(state)


def _geometric(rng: random.Random, q: float) -> int:
    """A count ``G`` with ``P(G >= j) = q^j`` (``0 < q < 1``): the ticks that pass before a race with time is lost."""
    u = 1.0 - rng.random()  # in (0, 1]
    return int(math.log(u) / math.log(q))


def _early(step, keys, drawn_at: dict, table, column: int) -> bool:
    """Some of ``keys`` has a drawn time its clock (``table[k][column]``, a slot of ``step``) has not reached yet."""
    return any(drawn_at.get(k) is not None and step.value(table[k][column]) < drawn_at[k] for k in keys)
