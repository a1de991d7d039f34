"""Statistical model checking: runs per second, here and on Dask, and SMC beside exhaustive search.

``python bench/smc_bench.py [--runs N] [--time-bound 1s] [--workers 1,2]``
    DALA's sensing level (RFLEX, LaserRF, POM... on one core, ``missions/sensing.yaml`` as client): runs per
    second in this process and on a local Dask cluster of each number of workers, with the estimates (which
    must be the same everywhere for the same seed and run count).

``python bench/smc_bench.py --robnav ARTEFACT_DIR [--runs N] [--cores 4]``
    Foughali's RobNav (prepared as bench/robnav_bench.py prepares it: its stub ``robsim/robsim-struct.idl``
    included): the largest response time of each task by clock zones beside the largest SMC sees, which is never
    above it, and the run after which SMC came within 5 ms of it.

``python bench/smc_bench.py --quadcopter ARTEFACT_DIR [-I DIR] [--platform P] [--runs N] [--queries]``
    Foughali's quadcopter (Mo-F/uppaal-smc-exp: ``all.gen``, ``all.proba``, ``quadcopter.q``): runs per second
    on 1 and 2 Dask workers; with ``--queries``, each query of ``quadcopter.q`` that is a period overrun, at
    epsilon 0.01 and delta 0.05 over 10 s (1,000,000 units of 10 us).  Its components include openrobots interfaces
    (``or/pose/pose_estimator.gen``...) that the artefact does not ship: give their directory with ``-I``.
"""
from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

DALA = ROOT / "descriptions" / "dala"
#: SMC is "within reach" of the exhaustive maximum when it sees a value this close to it.
WITHIN_MS = 5


def _settings(args, **kw):
    from genom2bip.durations import parse_duration
    from genom2bip.verify.smc import SmcSettings

    return SmcSettings(horizon_us=int(parse_duration(args.time_bound)), seed=args.seed, **kw)


def _dask(model, params, settings, workers: int):
    from genom2bip.campaign.cluster import ClusterSpec
    from genom2bip.campaign.smc import DaskRunner
    from genom2bip.verify.smc import estimate, sim_config

    config = sim_config(model, settings)
    runner = DaskRunner(ClusterSpec(workers=workers), params, config)
    try:
        return estimate(model, settings, runner, config)
    finally:
        runner.close()


def _line(where: str, report) -> None:
    estimates = ", ".join(f"{r.hits}/{r.runs}" for r in report.results)
    print(f"  {where:<22} {report.runs:>6,} runs  {report.seconds:7.2f} s  {report.runs_per_second:8.1f} runs/s  "
          f"({report.steps / max(report.runs, 1):,.0f} steps a run; reached: {estimates})", flush=True)


def speed(args) -> None:
    from genom2bip.campaign.params import ModelParams
    from genom2bip.verify import TimeSettings, build_model
    from genom2bip.verify.smc import estimate

    platform, client = str(DALA / "platforms" / "one-core.yaml"), str(DALA / "missions" / "sensing.yaml")
    model = build_model([DALA], time=TimeSettings(platform=platform, client=client))
    settings = _settings(args, runs=args.runs, batch=max(1, args.runs // 8))
    print(f"DALA sensing, one core, runs of {settings.horizon_us / 1000:g} ms, seed {args.seed}")
    estimate(model, _settings(args, runs=1))  # the compiled step built (and widened) once, outside the figures
    here = estimate(model, settings)
    _line("this process", here)
    params = ModelParams(paths=(str(DALA),), timed=True, platform=platform, client=client)
    for n in args.workers:
        report = _dask(model, params, settings, n)
        _line(f"Dask, {n} worker{'s' if n > 1 else ''}", report)
        same = [r.hits for r in report.results] == [r.hits for r in here.results]
        print(f"  {'':<22} same estimates as this process: {'yes' if same else 'NO'}")


def robnav(args) -> None:
    """Exhaustive largest response times (zones) beside what SMC sees, run after run."""
    sys.path.insert(0, str(ROOT / "bench"))
    import robnav_bench

    from genom2bip.verify import SearchOptions, TimeSettings, build_model
    from genom2bip.verify.smc import sim_config, simulator
    from genom2bip.verify.zones import check_response_times

    ns = argparse.Namespace(artefact=args.robnav, keep=None, requests_at_start=False)
    paths, out, execution, offsets, _, _ = robnav_bench.prepare(ns)
    platform = out / f"edf{args.cores}.yaml"
    platform.write_text(robnav_bench.platform_text(args.cores, execution, offsets, "one-by-one"))
    time_settings = TimeSettings(platform=str(platform), client=str(out / "client.yaml"), exceptions=False,
                                 responses=True)
    model = build_model(paths, include_dirs=[str(args.robnav)], time=time_settings)
    start = time.perf_counter()
    exhaustive = {r.owner: r.value_ms for r in check_response_times(model, SearchOptions()).responses
                  if r.kind == "task"}
    zones_s = time.perf_counter() - start
    settings = _settings(args)
    config = sim_config(model, settings)
    sim, _ = simulator(model, config)
    tasks = [k for k, w in enumerate(config.watches) if w.name in exhaustive]
    largest = {k: 0 for k in tasks}
    reached: dict[int, int] = {}
    start = time.perf_counter()
    for index in range(args.runs):
        run = sim.run(args.seed, index)
        for k in tasks:
            if run.responses[k]:
                largest[k] = max(largest[k], max(run.responses[k]))
            limit = exhaustive[config.watches[k].name]
            if k not in reached and limit is not None and largest[k] * config.tick_us / 1000 >= limit - WITHIN_MS:
                reached[k] = index + 1
    smc_s = time.perf_counter() - start
    print(f"RobNav, {args.cores} cores (EDF, releases one by one), the artefact's client; zones {zones_s:.1f} s, "
          f"{args.runs} runs of {settings.horizon_us / 1000:g} ms in {smc_s:.1f} s ({args.runs / smc_s:.1f} runs/s)")
    print(f"  {'task':<16} {'exhaustive':>10} {'SMC max':>8}  runs to come within {WITHIN_MS} ms")
    for k in tasks:
        name = config.watches[k].name
        seen = largest[k] * config.tick_us / 1000
        limit = exhaustive[name]
        flag = "" if limit is None or seen <= limit else "  ABOVE THE EXHAUSTIVE MAXIMUM"
        print(f"  {name:<16} {limit if limit is not None else '?':>8} ms {seen:>5g} ms  "
              f"{reached.get(k, f'not within {args.runs} runs')}{flag}")


#: ``Pr[<=T] (<> Man_TASK_COMPONENT.manage and tick_TASK_COMPONENT)``: the period overrun of TASK.
OVERRUN_QUERY = re.compile(r"Pr\[<=(\d+)\]\s*\(\s*<>\s*Man_(\w+?)_(\w+)\.manage\s+and\s+tick_\w+\)")
#: One time unit of the quadcopter model, in µs.
UNIT_US = 10


def quadcopter(args) -> int:
    from genom2bip.campaign.params import ModelParams
    from genom2bip.loading import InputError
    from genom2bip.verify import TimeSettings, build_model
    from genom2bip.verify.smc import estimate
    from runtime.diagnostics import DiagnosticError

    art = args.quadcopter
    includes = [str(art), *args.include]
    time_settings = TimeSettings(exceptions=False, platform=str(args.platform) if args.platform else None)
    try:
        model = build_model([art / "all.gen"], include_dirs=includes, time=time_settings)
    except (DiagnosticError, InputError) as exc:
        text = exc.render() if isinstance(exc, DiagnosticError) else "\n".join(exc.messages)
        missing = sorted(set(re.findall(r"cannot find include file '([^']+)'", text)))
        print(f"the quadcopter does not load: {len(text.splitlines())} lines of errors; "
              f"include files not found: {', '.join(missing) or 'none'}")
        print("give the directory of the openrobots interfaces with -I DIR (they are not in the artefact)")
        return 1
    params = ModelParams(paths=(str(art / "all.gen"),), include_dirs=tuple(includes), timed=True,
                         platform=str(args.platform) if args.platform else None, no_exceptions=True)
    print(f"quadcopter: runs of {args.time_bound}, {args.runs} runs, the artefact's all.proba")
    for n in args.workers:
        settings = _settings(args, runs=args.runs, proba=str(art / "all.proba"), batch=max(1, args.runs // 8))
        _line(f"Dask, {n} worker{'s' if n > 1 else ''}", _dask(model, params, settings, n))
    if not args.queries:
        return 0
    queries = OVERRUN_QUERY.findall((art / "quadcopter.q").read_text())
    print(f"{len(queries)} period-overrun queries of quadcopter.q (the others are not translated), "
          f"epsilon 0.01, delta 0.05")
    for bound, task, component in queries:
        settings = _settings(args, epsilon=0.01, delta=0.05, proba=str(art / "all.proba"))
        settings.horizon_us = int(bound) * UNIT_US
        report = estimate(model, settings)
        want = f"period of {component}.{task} "
        for r in report.results:
            if r.subject.startswith(want):
                e = r.estimate
                print(f"  {r.subject}: Pr[<= {settings.horizon_us / 1e6:g} s] = {e.value:.4f} "
                      f"[{e.low:.4f}, {e.high:.4f}] ({report.runs:,} runs, {report.runs_per_second:.1f} runs/s)")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=200)
    ap.add_argument("--time-bound", default="1 s")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", default="1,2", help="Dask cluster sizes to time (a list: 1,2)")
    ap.add_argument("--robnav", type=Path, metavar="DIR")
    ap.add_argument("--cores", type=int, default=4)
    ap.add_argument("--quadcopter", type=Path, metavar="DIR")
    ap.add_argument("-I", dest="include", action="append", default=[], metavar="DIR")
    ap.add_argument("--platform", type=Path, help="quadcopter: a platform file (default: a core per task)")
    ap.add_argument("--queries", action="store_true",
                    help="quadcopter: answer quadcopter.q's overrun queries at epsilon 0.01, delta 0.05 (18,445 runs "
                         "of 10 s each)")
    args = ap.parse_args()
    args.workers = [int(n) for n in args.workers.split(",") if n]
    if args.robnav:
        robnav(args)
        return 0
    if args.quadcopter:
        return quadcopter(args)
    speed(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
