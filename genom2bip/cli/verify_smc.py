"""``verify --timed --smc``: statistical model checking of the timed platform model, printed (docs/smc.md).

Per timing observer: the runs, the estimate of ``Pr[<= T](<> phi)`` and its
interval (or Wald's decision against ``--threshold``), and the first run that
reached phi as a timed trace; per task and service: the response times seen
(mean, 99th percentile, largest, how many), with a picture on request.
Exit status: 4 when a run reached an observer's ERROR (the trace printed is
a run of the model), 5 when Wald's test stayed undecided, else 0.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from genom2bip.cli.verbs import EXIT_ERRORS, EXIT_USAGE, Failure, error

EXIT_OK, EXIT_VIOLATED, EXIT_INCONCLUSIVE = 0, 4, 5
#: Seconds to reach a running Dask scheduler (--scheduler).
CONNECT_TIMEOUT = 30.0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("statistical model checking (--timed --smc; docs/smc.md)")
    group.add_argument("--smc", action="store_true",
                       help="estimate Pr[<= T](<> overrun) of each timing observer and the response-time "
                            "distributions from random runs (durations drawn in their intervals)")
    group.add_argument("--time-bound", metavar="DURATION", default="1 s",
                       help="T: how long each run lasts, in model time (default 1 s)")
    group.add_argument("--epsilon", type=float, default=0.01,
                       help="half-width of the interval (Chernoff-Hoeffding), or Wald's indifference region "
                            "(default 0.01)")
    group.add_argument("--delta", type=float, default=0.05,
                       help="probability that the interval misses (or that Wald's test errs) (default 0.05)")
    group.add_argument("--threshold", type=float, metavar="P",
                       help="Wald's sequential test of Pr >= P instead of an estimate")
    group.add_argument("--runs", type=int, metavar="N",
                       help="exactly N runs (the interval is the one N runs give at --delta)")
    group.add_argument("--seed", type=int, default=1, help="seed of the runs (default 1): same seed, same estimate")
    group.add_argument("--proba", metavar="FILE",
                       help="GenoM3 .proba file: weights of the codels' next states (task::state::next N)")
    group.add_argument("--smc-workers", type=int, metavar="N",
                       help="run the batches on a local Dask cluster of N worker processes (default: this process)")
    group.add_argument("--scheduler", metavar="ADDRESS",
                       help="run the batches on a running Dask cluster (tcp://HOST:PORT)")
    group.add_argument("--batch", type=int, default=None, metavar="N",
                       help="runs per batch sent to a worker (default 250)")
    group.add_argument("--smc-trace", metavar="FILE",
                       help="write the first run that reaches each observer's ERROR as JSON traces (one file; "
                            "replayable step by step)")
    group.add_argument("--histogram", metavar="FILE",
                       help="draw the response-time distributions (.png or .svg)")


def wanted(args: argparse.Namespace) -> bool:
    """Whether the command asks for SMC; usage errors for SMC options given without it."""
    if getattr(args, "smc", False):
        if not args.timed:
            error("--smc needs --timed")
            raise Failure(EXIT_USAGE)
        other = [o for o, on in (("--deadlock", args.deadlock), ("--property", args.property), ("--aut", args.aut),
                                 ("--dot", args.dot), ("--promela", args.promela), ("--por", args.por),
                                 ("--trace-picture", args.trace_picture), ("--time-search", args.time_search),
                                 ("--method", args.method != "explore")) if on]
        if other:
            error(f"{other[0]} belongs to exhaustive verification; --smc estimates the timing observers "
                  "and the response times from runs")
            raise Failure(EXIT_USAGE)
        return True
    given = [o for o in ("threshold", "runs", "proba", "smc_workers", "scheduler", "batch", "smc_trace", "histogram")
             if getattr(args, o, None) is not None]
    if given:
        error(f"--{given[0].replace('_', '-')} needs --smc")
        raise Failure(EXIT_USAGE)
    return False


def settings(args: argparse.Namespace):
    """The :class:`~genom2bip.verify.smc.SmcSettings` of the command line (usage errors said and raised)."""
    from genom2bip.durations import parse_duration
    from genom2bip.loading import UsageError
    from genom2bip.verify.smc import BATCH, SmcSettings

    horizon = parse_duration(args.time_bound)
    if horizon is None:
        error(f"--time-bound: '{args.time_bound}' is not a duration (e.g. 1 s, 500 ms)")
        raise Failure(EXIT_USAGE)
    if args.smc_workers is not None and args.smc_workers < 1:
        error("--smc-workers must be >= 1")
        raise Failure(EXIT_USAGE)
    if args.smc_workers is not None and args.scheduler:
        error("--smc-workers starts a local cluster, --scheduler uses a running one: give one of them")
        raise Failure(EXIT_USAGE)
    out = SmcSettings(horizon_us=int(horizon), epsilon=args.epsilon, delta=args.delta, threshold=args.threshold,
                      runs=args.runs, seed=args.seed, batch=args.batch if args.batch is not None else BATCH,
                      responses=True, proba=args.proba)
    try:
        out.check()
    except UsageError as exc:
        for line in exc.messages:
            error(line)
        raise Failure(EXIT_USAGE) from None
    for path in (args.smc_trace, args.histogram):
        inputs = (*args.paths, args.proba, args.platform, args.client, args.observers, args.rules)
        if path and Path(path).resolve() in {Path(p).resolve() for p in inputs if p}:
            error(f"{path} is an input of this command: it would be overwritten")
            raise Failure(EXIT_ERRORS)
    if args.histogram and Path(args.histogram).suffix.lower() not in (".png", ".svg"):
        error(f"--histogram: '{args.histogram}' must end in .png or .svg")
        raise Failure(EXIT_USAGE)
    return out


def run(model, args: argparse.Namespace, smc) -> int:
    """Estimate, print, write the traces and the picture; the exit status."""
    from genom2bip.cli.verify_timed import platform_line, timed_trace
    from genom2bip.loading import InputError, UsageError
    from genom2bip.verify.smc import estimate, sim_config, simulator, witness
    from runtime.diagnostics import DiagnosticError

    try:
        config = sim_config(model, smc, lambda text: print(text, file=sys.stderr))
    except DiagnosticError as exc:
        print(exc.render(), file=sys.stderr)
        return EXIT_ERRORS
    except (InputError, UsageError) as exc:
        for line in exc.messages:
            error(line)
        return EXIT_USAGE if isinstance(exc, UsageError) else EXIT_ERRORS
    print(f"model {model.title}")
    platform_line(model)
    sim, why = simulator(model, config, args.externs, compiled=args.engine != "python")
    if why:
        print(f"genom2bip: note: {why}", file=sys.stderr)
    runner, closing = _runner(model, args, config, sim)
    try:
        report = estimate(model, smc, runner, config, sim, _progress(args))
    finally:
        closing()
    print(f"time: one tick is {config.tick_us / 1000:g} ms; runs of {report.horizon_ms:g} ms, seed {smc.seed}")
    how = (f"Chernoff-Hoeffding, epsilon {report.results[0].epsilon:.4g}, delta {smc.delta:g}"
           if report.method == "Chernoff-Hoeffding" and report.results else report.method)
    print(f"smc: {report.runs:,} runs ({how}) on {report.runner}, {report.seconds:.2f} s, "
          f"{report.runs_per_second:,.0f} runs/s")
    if report.stopped:
        print(f"smc: interrupted by Ctrl-C after {report.runs:,} runs: each interval is the one they give")
    for end, count in sorted(report.ends.items()):
        if end in ("deadlock", "zeno"):
            what = "a deadlock" if end == "deadlock" else "time blocked (no tick for too many steps)"
            print(f"warning: {count} run(s) stopped before the time bound: {what}")
    if not report.results:
        print("observers: none in the model")
    violated = undecided = False
    for r in report.results:
        e = r.estimate
        bound = f"Pr[<= {r.horizon_ms:g} ms](<> {'overrun' if 'period of' in r.subject else 'violation'})"
        if r.threshold is not None:
            answer = {True: f">= {r.threshold:g} accepted", False: f"< {r.threshold:g} accepted",
                      None: "undecided (" + ("interrupted" if report.stopped else "run cap reached") + ")"}[r.decision]
            print(f"{r.subject}: {bound} {answer} (Wald SPRT, {r.runs:,} runs, {r.hits:,} reached it, "
                  f"estimate {e.value:.4f})")
            undecided = undecided or r.decision is None
        else:
            print(f"{r.subject}: {bound} = {e.value:.4f}  [{e.low:.4f}, {e.high:.4f}]  "
                  f"({r.hits:,} of {r.runs:,} runs reached it)")
        violated = violated or r.hits > 0
    undecided = undecided or bool(report.stopped)
    worst = EXIT_VIOLATED if violated else EXIT_INCONCLUSIVE if undecided else EXIT_OK  # a run reaching ERROR answers
    traces = {}
    for r in report.results:
        trace = witness(sim, smc.seed, r)
        if trace is None:
            continue
        traces[r.observer] = {"subject": r.subject, "observer": r.observer, "seed": smc.seed, "run": r.first_run,
                              "trace": trace.to_json()}
        print(f"{r.subject}: first reached by run {r.first_run} at {r.first_ms:g} ms ({len(trace)} steps):")
        timed_trace(trace)
    _responses(report, model)
    if args.smc_trace:
        _write(args.smc_trace, json.dumps({"model": model.title, "traces": list(traces.values())}, indent=1))
        print(f"wrote {args.smc_trace} ({len(traces)} trace{'s' if len(traces) != 1 else ''})")
    if args.histogram:
        from genom2bip.verify.smc_picture import draw

        try:
            draw(report, Path(args.histogram))
        except OSError as exc:
            error(f"cannot write {args.histogram}: {exc.strerror or exc}")
            return EXIT_ERRORS
        print(f"wrote {args.histogram}")
    return worst


#: Seconds between two progress lines.
PROGRESS_PERIOD = 1.0


def _progress(args):
    """A progress line on stderr per batch read (at most one a second), where progress is shown."""
    if args.quiet or not (args.progress or sys.stderr.isatty()):
        return None
    last = [-PROGRESS_PERIOD]

    def show(runs: int, planned: int | None, seconds: float) -> None:
        if seconds - last[0] < PROGRESS_PERIOD and runs != planned:
            return
        last[0] = seconds
        of = f" of {planned:,}" if planned is not None else ""
        print(f"smc: {runs:,}{of} runs, {seconds:.1f} s, {runs / seconds if seconds else 0:,.1f} runs/s",
              file=sys.stderr, flush=True)

    return show


def _responses(report, model) -> None:
    from genom2bip.verify.zones import IDLE, idle_owners

    seen = [d for d in report.responses if d.samples]
    if not report.responses:
        return
    print(f"response times seen ({report.runs:,} runs; mean, 99th percentile, largest, how many):")
    width = max(len(d.owner) for d in report.responses)
    idle = idle_owners(model)
    for d in report.responses:
        if d.owner in idle:  # its releases are not in the model: the build's argument answers
            print(f"  {d.owner:<{width}}  0 ms: {IDLE}")
            continue
        if not d.samples:
            print(f"  {d.owner:<{width}}  none ended within the runs")
            continue
        print(f"  {d.owner:<{width}}  mean {d.mean_ms:.3g} ms, p99 {d.percentile_ms():g} ms, "
              f"max {d.max_ms:g} ms  ({d.samples:,})")
    if not seen:
        print("  (no response ended within the time bound)")


def _write(path: str, text: str) -> None:
    """Write ``text`` whole or not at all (aside, then renamed)."""
    import os

    target = Path(path)
    partial = target.with_name(f".{target.name}.{os.getpid()}.partial")
    try:
        partial.write_text(text + "\n")
        os.replace(partial, target)
    except OSError as exc:
        partial.unlink(missing_ok=True)
        error(f"cannot write {path}: {exc.strerror or exc}")
        raise Failure(EXIT_ERRORS) from None


def _runner(model, args, config, sim):
    """The runner of the batches and how to close it: this process, or a Dask cluster."""
    if args.smc_workers is None and not args.scheduler:
        return None, lambda: None
    from genom2bip.campaign.cluster import ClusterSpec
    from genom2bip.campaign.smc import DaskRunner

    params = model_params(args)
    spec = ClusterSpec(scheduler=args.scheduler, workers=args.smc_workers, connect_timeout=CONNECT_TIMEOUT)
    try:
        runner = DaskRunner(spec, params, config)
    except (OSError, TimeoutError) as exc:
        error(f"cannot reach the Dask scheduler {args.scheduler}: {exc}")
        raise Failure(EXIT_ERRORS) from None
    return runner, runner.close


def model_params(args: argparse.Namespace):
    """The command line's model as parameters a worker rebuilds it from."""
    from genom2bip.campaign.params import ModelParams
    from genom2bip.cli.verbs import parse_defines
    from genom2bip.cli.verify_timed import time_settings

    time = time_settings(args)
    return ModelParams(paths=tuple(str(p) for p in args.paths), rules=args.rules, no_rules=args.no_rules,
                       defines=tuple(sorted(parse_defines(args.defines).items())),
                       include_dirs=tuple(args.include_dirs), root=args.root, timed=True, tick_us=time.tick_us,
                       default_wcet_us=time.default_wcet_us, observers=time.observers, platform=time.platform,
                       client=time.client, responses=time.responses, no_exceptions=not time.exceptions)
