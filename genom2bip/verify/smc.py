"""Statistical model checking of a timed platform model: ``Pr[<= T](<> phi)`` for each timing observer, and the
distribution of each task's and service's response time, from random runs (docs/smc.md).

The runs are :class:`runtime.smc.Simulator`'s: the exhaustive model's own
runs, with codel durations drawn in their intervals (the platform file's
``distributions``) and codel outcomes weighted by a GenoM3 ``.proba`` file.
Runs are computed in batches of consecutive indices by a *runner* (this
process by default; a Dask cluster with
:class:`genom2bip.campaign.smc.DaskRunner`) and read back in index order, so
that an estimate depends on the seed and the run count only.
"""
from __future__ import annotations

import math
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, Iterator

from genom2bip.loading import InputError, UsageError
from genom2bip.verify.interrupts import CtrlC
from genom2bip.verify.model import Model, tick_us
from genom2bip.verify.results import Figures, Verdict
from genom2bip.verify.smc_results import ResponseDistribution, SmcReport, SmcResult, SmcSummary, summary
from genom2bip.verify.smc_traces import replay, witness
from genom2bip.verify.timing import observers, subject
from runtime.smc import Goal, SimConfig, Simulator, Sprt, Watch, Window, chernoff_runs, hoeffding_epsilon

__all__ = ["BATCH", "BatchResult", "LocalRunner", "ResponseDistribution", "SmcReport", "SmcResult", "SmcSettings",
           "SmcSummary", "estimate", "replay", "run_batch", "sim_config", "simulator", "summary", "witness"]

#: Runs per batch: what one worker computes at a time (fixed: it is not a function of the number of workers).
BATCH = 250
#: Wald's test gives up (inconclusive) past this many times the Chernoff–Hoeffding run count.
SPRT_CAP = 10
#: The waits of a platform model whose end is drawn uniformly (genom2bip/build/platform.py): a task's suspension
#: (place, clock, bounds, end port of its scheduler) and the delay of its first period (of its timer).
WINDOWS = (("SUSPENDED", "x", "s_lo", "s_hi", "back"), ("START", "t", "first_lo", "first_hi", "first"))
#: The final reports that end a service's response time.
FINALS = ("finish", "fail", "interrupted", "reject")


@dataclass
class SmcSettings:
    """How to estimate: the time bound, the bound's epsilon and delta (or Wald's threshold), the seed, the runs."""

    horizon_us: int
    epsilon: float = 0.01
    delta: float = 0.05
    threshold: float | None = None  # Wald's SPRT of Pr >= threshold, epsilon its indifference region
    runs: int | None = None  # a fixed run count (the interval is then the one it gives); None: from epsilon, delta
    seed: int = 1
    batch: int = BATCH
    kinds: tuple[str, ...] = ("overrun", "latency")
    responses: bool = True
    proba: str | None = None

    def check(self) -> None:
        """UsageError for values no estimate can take."""
        wrong = []
        if not (0 < self.epsilon < 1) or math.isnan(self.epsilon):
            wrong.append(f"--epsilon is {self.epsilon:g}; expected a number between 0 and 1 (e.g. 0.01)")
        if not (0 < self.delta < 1) or math.isnan(self.delta):
            wrong.append(f"--delta is {self.delta:g}; expected a number between 0 and 1 (e.g. 0.05)")
        if self.threshold is not None and (not (0 < self.threshold < 1) or math.isnan(self.threshold)):
            wrong.append(f"--threshold is {self.threshold:g}; expected a probability between 0 and 1 (e.g. 0.1)")
        if self.runs is not None and self.runs < 1:
            wrong.append(f"--runs is {self.runs}; expected at least 1")
        if self.horizon_us <= 0:
            wrong.append("--time-bound must be a positive duration (e.g. 1 s)")
        if self.batch < 1:
            wrong.append(f"--batch is {self.batch}; expected at least 1")
        if wrong:
            raise UsageError(wrong)

    @property
    def planned(self) -> int | None:
        """The runs of a Chernoff–Hoeffding estimate (None: Wald's test decides when to stop)."""
        if self.runs is not None:
            return self.runs
        return chernoff_runs(self.epsilon, self.delta) if self.threshold is None else None


# --------------------------------------------------------------------------- the simulator's configuration


def sim_config(model: Model, settings: SmcSettings, warn: Callable[[str], None] | None = None) -> SimConfig:
    """Goals, schedulers, durations, weights and response watches of ``model`` (InputError / DiagnosticError for
    a bad ``.proba`` file; UsageError for a model SMC does not take); ``warn`` hears the ``.proba`` file's
    warnings, rendered."""
    tick = tick_us(model.package)
    if tick is None:
        raise UsageError(["--smc needs --timed: a model with ticks"])
    if model.description is None:
        raise UsageError(["--smc takes description files (a .bip file has no platform to draw durations from)"])
    flat = model.flat
    schedulers = [fa.name for fa in flat.atoms if "BUSY" in fa.places
                  and any(a.name == "scheduler" for a in fa.type.annotations)
                  and {"x", "lo", "hi"} <= {d.name for d in fa.variables}]
    goals = [Goal(subject(a, tick), a.path) for a in observers(model, settings.kinds)]
    windows = [Window(fa.name, place, clock, lo, hi, end) for fa in flat.atoms
               for place, clock, lo, hi, end in WINDOWS
               if place in fa.places and lo in fa.constants and hi in fa.constants]
    durations = {}
    platform = model.platform
    if platform is not None:
        durations = {".".join(key): law for key, law in platform.distributions.items()}
    weights: dict[tuple[str, str, str], float] = {}
    if settings.proba:
        from genom2bip.proba import load_proba
        from runtime.diagnostics import Reporter

        if not Path(settings.proba).exists():
            raise InputError([f"{settings.proba}: no such .proba file"])
        if not Path(settings.proba).is_file():
            raise InputError([f"{settings.proba}: not a file (a .proba file was expected)"])
        reporter = Reporter()
        proba = load_proba(Path(settings.proba), model.description, reporter)
        reporter.raise_if_errors()
        assert proba is not None
        for d in reporter.diagnostics:
            if warn is not None:
                warn(d.render(reporter.sources))
        weights = {(f"{c}.{o}", s, n): w for (c, o, s, n), w in proba.weights.items()}
    watches = []
    if settings.responses:
        for c in model.description.components:
            for t in c.tasks:
                if t.period is not None:
                    watches.append(Watch(f"{c.name}.{t.name}", (f"{c.name}.{t.name}:period",),
                                         (f"{c.name}.{t.name}:sleep",)))
            for s in c.services:
                watches.append(Watch(f"{c.name}.{s.name}", (f"{c.name}.{s.name}:trigger",),
                                     tuple(f"{c.name}.{s.name}:{p}" for p in FINALS)))
    return SimConfig(tick_us=tick, horizon=settings.horizon_us // tick, goals=goals, watches=watches,
                     schedulers=schedulers, windows=windows, durations=durations, weights=weights,
                     keep_going=bool(watches))


def simulator(model: Model, config: SimConfig, externs: str | None = None,
              compiled: bool = True) -> tuple[Simulator, str]:
    """The simulator of ``model`` on the compiled step (on the Python step where it cannot be compiled, with a
    note saying why; always, with ``compiled`` false); the note also says why runs go tick by tick, if they do."""
    from runtime.explore import StateSpace
    from runtime.native.compiled import compile_space

    space = StateSpace(model.package, model.root, _externs(externs), None, True, set())
    step, why = compile_space(space, search=True) if compiled else (None, "")
    sim = Simulator(space, step, config)
    return sim, "; ".join(note for note in (why, sim.no_leaps) if note)


def _externs(module: str | None):
    if not module:
        return None
    from genom2bip.verify.search import extern_bindings

    return extern_bindings(module)


# --------------------------------------------------------------------------- batches


@dataclass
class BatchResult:
    """Runs ``first .. first + count - 1``: when each reached each goal (ticks, None: not by the horizon), the
    response times seen (per watch: ticks -> times seen), how the runs ended, their steps and ticks."""

    first: int
    count: int
    reached: list[tuple[int | None, ...]]
    responses: list[dict[int, int]]
    ends: dict[str, int]
    steps: int
    ticks: int
    seconds: float


def run_batch(sim: Simulator, seed: int, first: int, count: int) -> BatchResult:
    """Runs ``first .. first + count - 1`` of ``seed`` on ``sim``."""
    start = time.perf_counter()
    reached = []
    responses = [Counter() for _ in sim.config.watches]
    ends: Counter = Counter()
    steps = ticks = 0
    for index in range(first, first + count):
        run = sim.run(seed, index)
        reached.append(tuple(run.reached))
        for counter, seen in zip(responses, run.responses):
            counter.update(seen)
        ends[run.end] += 1
        steps += run.steps
        ticks += run.ticks
    return BatchResult(first, count, reached, [dict(c) for c in responses], dict(ends), steps, ticks,
                       time.perf_counter() - start)


class LocalRunner:
    """Batches computed here, one after another, on the simulator given."""

    name = "this process"
    workers = 1

    def __init__(self, sim: Simulator) -> None:
        self.sim = sim

    def run(self, seed: int, ranges: Iterable[tuple[int, int]]) -> Iterator[BatchResult]:
        for first, count in ranges:
            yield run_batch(self.sim, seed, first, count)


def estimate(model: Model, settings: SmcSettings, runner=None, config: SimConfig | None = None,
             sim: Simulator | None = None,
             progress: Callable[[int, int | None, float], None] | None = None) -> SmcReport:
    """Estimate every observer's ``Pr[<= T](<> phi)`` (and the response times) of ``model``.

    ``runner`` computes the batches (:class:`LocalRunner` on ``sim`` by default); the runs are read in index
    order, so the report depends on the settings alone, whatever the runner.  ``progress(runs, planned,
    seconds)`` hears each batch read.  Ctrl-C stops the estimate with the whole batches read so far (a second one
    at once): the report's ``stopped`` says so, and each interval is the one those runs give.
    """
    settings.check()
    config = config or sim_config(model, settings)
    notes: list[str] = []
    if runner is None:
        if sim is None:
            sim, why = simulator(model, config)
            if why:
                notes.append(why)
        runner = LocalRunner(sim)
    planned = settings.planned
    sprt = settings.threshold is not None and settings.runs is None
    epsilon = settings.epsilon if settings.runs is None or sprt else hoeffding_epsilon(settings.runs, settings.delta)
    cap = planned if planned is not None else SPRT_CAP * chernoff_runs(settings.epsilon, settings.delta)
    tests = [Sprt(settings.threshold, settings.epsilon, settings.delta) for _ in config.goals] if sprt else []
    hits = [0] * len(config.goals)
    first: list[tuple[int, int] | None] = [None] * len(config.goals)
    responses = [Counter() for _ in config.watches]
    ends: Counter = Counter()
    runs = steps = ticks = 0
    start = time.perf_counter()
    ranges = ((i, min(settings.batch, cap - i)) for i in range(0, cap, settings.batch))
    batches = runner.run(settings.seed, ranges)
    stopped = ""
    ctrl_c = CtrlC()
    with ctrl_c.watching():
        try:
            for batch in batches:
                for offset, reached in enumerate(batch.reached):
                    for g, tick in enumerate(reached):
                        if tick is not None:
                            hits[g] += 1
                            if first[g] is None:
                                first[g] = (batch.first + offset, tick)
                        if sprt:
                            tests[g].add(tick is not None)
                runs += batch.count
                for counter, seen in zip(responses, batch.responses):
                    counter.update(seen)
                ends.update(batch.ends)
                steps += batch.steps
                ticks += batch.ticks
                if progress is not None:
                    progress(runs, None if sprt else cap, time.perf_counter() - start)
                if sprt and all(t.decision is not None for t in tests):
                    break
                if ctrl_c.pressed:  # the first Ctrl-C: the whole batches read so far
                    stopped = "interrupted"
                    break
        except KeyboardInterrupt:
            stopped = "interrupted"
        finally:
            close = getattr(batches, "close", None)
            if close is not None:
                close()
    seconds = time.perf_counter() - start
    if stopped and not sprt and runs < cap:  # the interval of the runs read
        epsilon = hoeffding_epsilon(runs, settings.delta)
    tick = config.tick_us
    results = []
    for g, goal in enumerate(config.goals):
        test = tests[g] if sprt else None
        n, k = (test.runs, test.hits) if test is not None else (runs, hits[g])
        if test is not None:
            verdict = (Verdict.INCONCLUSIVE if test.decision is None else
                       Verdict.VIOLATED if test.decision else Verdict.HOLDS)
        else:
            verdict = Verdict.VIOLATED if k else Verdict.INCONCLUSIVE if stopped else Verdict.HOLDS
        where = first[g]
        results.append(SmcResult(
            goal.name, verdict, Figures(states=0, transitions=steps, seconds=seconds), method="smc",
            limit=stopped or ("max-runs" if test is not None and test.decision is None else ""), exhaustive=False,
            observer=goal.atom, runs=n, hits=k, epsilon=epsilon, delta=settings.delta,
            threshold=settings.threshold if sprt else None, decision=test.decision if test else None,
            seed=settings.seed, horizon_ms=config.horizon * tick / 1000,
            first_run=where[0] if where else None, first_ms=where[1] * tick / 1000 if where else None))
    kinds = {w.name: ("task" if w.opens[0].endswith(":period") else "service") for w in config.watches}
    dists = [ResponseDistribution(w.name, kinds[w.name], dict(c), tick) for w, c in zip(config.watches, responses)]
    return SmcReport(results, dists, runs, seconds, steps, ticks, dict(ends),
                     "Wald SPRT" if sprt else "Chernoff-Hoeffding", getattr(runner, "name", "?"),
                     getattr(runner, "workers", 1), settings.seed, config.horizon * tick / 1000, tick, notes,
                     stopped)
