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
    Foughali's quadcopter (Mo-F/uppaal-smc-exp: ``all.gen``, ``all.proba``, ``quadcopter.q``), with the artefact's
    client written as a mission (``--default-environment``: without it): runs per second on 1 and 2 Dask workers;
    with ``--queries``, every query of ``quadcopter.q`` (period overruns, and its until formulas translated) at
    epsilon 0.01 and delta 0.05 over 10 s (1,000,000 units of 10 us), all from the same runs (``--query-runs``,
    ``--budget`` for fewer).  Its components include openrobots interfaces (``or/pose/pose_estimator.gen``...) that
    the artefact does not ship: give their directory with ``-I``.
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


def _dask(model, params, settings, workers: int, config=None, budget: float = 0, warm: bool = False):
    """The estimate on a local Dask cluster of ``workers``; after ``budget`` seconds (0: none), the runs read so
    far (the estimate stops as on Ctrl-C).  ``warm``: each worker builds the model and its compiled step first, in
    a run of its own (seed 0) outside the figures."""
    from dataclasses import replace

    from genom2bip.campaign.cluster import ClusterSpec
    from genom2bip.campaign.smc import DaskRunner
    from genom2bip.verify.smc import estimate, sim_config

    config = config or sim_config(model, settings)
    runner = DaskRunner(ClusterSpec(workers=workers), params, config)
    if warm:
        estimate(model, replace(settings, runs=runner.workers, batch=1, seed=0), runner, config)

    def progress(runs, planned, seconds) -> None:
        print(f"  ... {runs:,} of {planned:,} runs, {seconds:.0f} s", file=sys.stderr, flush=True)
        if budget and seconds > budget:
            raise KeyboardInterrupt

    try:
        return estimate(model, settings, runner, config, progress=progress)
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
#: ``Pr[<=T]((cl.A or cl.B ...) U SERVICE_INSTANCE_COMPONENT.LOCATION)``: an activity reaches LOCATION while the
#: artefact's client is still in one of the locations listed.
UNTIL_QUERY = re.compile(r"Pr\[<=(\d+)\]\s*\(\s*\(((?:cl\.\w+)(?:\s+or\s+cl\.\w+)*)\)\s+U\s+"
                         r"(\w+?)_(\d+)_([a-z]+)\.(\w+)\)")
#: One time unit of the quadcopter model, in µs.
UNIT_US = 10
#: The artefact's client (``quadcopter.xta``, process ``client``) as a mission: 10 ms in ``ini``, then
#: mikrokopter.start, mikrokopter.servo and nhfc.servo sent one after the other (``start``, ``start2``,
#: ``start3``), 5.5 ms in ``hold``, then maneuver's set_current_state, take_off, five waypoints, wait and take_off.
#: Inputs are not part of the timed model; those given are plausible values the services accept.
CLIENT = """mission: quadcopter-client
steps:
  - wait: 0.01
  - send: mikrokopter.start
    until: queued
  - send: mikrokopter.servo
    until: queued
  - send: nhfc.servo
    until: queued
  - wait: 0.0055
  - send: maneuver.set_current_state
    until: queued
  - send: maneuver.take_off
    with: {height: 1.0, duration: 0.0}
    until: queued
""" + "".join("""  - send: maneuver.waypoint
    with: {x: 0.0, y: 0.0, z: 1.0, yaw: 0.0, vx: 0.0, vy: 0.0, vz: 0.0, wz: 0.0, ax: 0.0, ay: 0.0, az: 0.0,
           duration: 0.0}
    until: queued
""" for _ in range(5)) + """  - send: maneuver.wait
    until: queued
  - send: maneuver.take_off
    with: {height: 0.0, duration: 0.0}
    until: queued
"""
#: The client's locations up to ``hold``; it leaves them when it sends maneuver.set_current_state.
BEFORE_HOLD_ENDS = ("ini", "start", "start2", "start3", "hold")
LEAVES_HOLD = "maneuver.set_current_state:trigger"


def until_goal(service: str, component: str, location: str, locations: list[str]):
    """The Goal of ``(cl.L1 or ...) U SERVICE_1_COMPONENT.LOCATION``, or a string saying why it has none.

    In the artefact's activity templates ``S_`` is the activity in state S waiting for its task and ``S_2`` the
    codel of S running: ``start_`` is ``C.S:start`` here (the activity starts) and ``S_2`` is ``C.S:exec_S``."""
    from runtime.smc import Goal

    if any(loc not in BEFORE_HOLD_ENDS for loc in locations):
        return f"client locations {', '.join(locations)}: only those up to hold are translated"
    if location == "start_":
        label = f"{component}.{service}:start"
    elif location.endswith("_2"):
        label = f"{component}.{service}:exec_{location[:-2]}"
    else:
        return f"location {location} of {service}: not translated"
    name = f"({' or '.join('cl.' + loc for loc in locations)}) U {service}_1_{component}.{location}"
    return Goal(name, f"until:{label}", label=label, before=(LEAVES_HOLD,))


def quadcopter(args) -> int:
    import tempfile

    from genom2bip.campaign.params import ModelParams
    from genom2bip.loading import InputError
    from genom2bip.verify import TimeSettings, build_model
    from genom2bip.verify.smc import sim_config
    from runtime.diagnostics import DiagnosticError

    art = args.quadcopter
    includes = [str(art), *args.include]
    client = None
    if not args.default_environment:
        client = Path(tempfile.mkdtemp(prefix="quadcopter-")) / "client.yaml"
        client.write_text(CLIENT)
    platform = str(args.platform) if args.platform else None
    time_settings = TimeSettings(exceptions=False, platform=platform, client=str(client) if client else None)
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
                         platform=platform, client=str(client) if client else None, no_exceptions=True)
    where = "the artefact's client as a mission" if client else "the default environment"
    print(f"quadcopter ({where}): runs of {args.time_bound}, {args.runs} runs, the artefact's all.proba")
    for n in args.workers:
        settings = _settings(args, runs=args.runs, proba=str(art / "all.proba"), batch=max(1, args.runs // (4 * n)),
                             responses=False)
        _line(f"Dask, {n} worker{'s' if n > 1 else ''}", _dask(model, params, settings, n, warm=True))
    if not args.queries:
        return 0
    text = (art / "quadcopter.q").read_text()
    overruns = OVERRUN_QUERY.findall(text)
    untils = UNTIL_QUERY.findall(text)
    bounds = {int(b) for b, *_ in overruns + untils}
    if len(bounds) != 1:
        print(f"quadcopter.q's queries have time bounds {sorted(bounds)}: one estimate per bound is not done here")
        return 1
    settings = _settings(args, epsilon=0.01, delta=0.05, proba=str(art / "all.proba"), responses=False,
                         batch=args.batch, runs=args.query_runs)
    settings.horizon_us = bounds.pop() * UNIT_US
    config = sim_config(model, settings)
    config.keep_going = False
    subjects = {}
    for _, task, component in overruns:
        want = f"period of {component}.{task} "
        goal = next((g for g in config.goals if g.name.startswith(want)), None)
        subjects[f"<> Man_{task}_{component}.manage and tick_{task}_{component}"] = goal.atom if goal else None
    for _, locations, service, _, component, location in untils:
        locs = [loc.strip()[3:] for loc in locations.split(" or ")]
        goal = until_goal(service, component, location, locs)
        name = f"({locations}) U {service}_1_{component}.{location}"
        if isinstance(goal, str):
            print(f"  not translated: {name}: {goal}")
            continue
        config.goals.append(goal)
        subjects[name] = goal.atom
        print(f"  {name}: translated as '{goal.label}' before '{LEAVES_HOLD}'")
    print(f"{len(subjects)} queries of quadcopter.q from the same runs, Pr[<= {settings.horizon_us / 1e6:g} s], "
          f"epsilon 0.01, delta 0.05 ({settings.planned:,} runs) on {args.query_workers} Dask worker(s)"
          + (f", stopped after {args.budget:g} s" if args.budget else ""))
    report = _dask(model, params, settings, args.query_workers, config, args.budget, warm=True)
    by_atom = {r.observer: r for r in report.results}
    for query, atom in subjects.items():
        r = by_atom.get(atom)
        if r is None:
            print(f"  Pr[{query}]: no observer of this task in the model")
            continue
        e = r.estimate
        print(f"  Pr[<= {settings.horizon_us / 1e6:g} s]({query}) = {e.value:.4f}  [{e.low:.4f}, {e.high:.4f}]  "
              f"({e.hits:,} of {e.runs:,} runs)")
    print(f"  {report.runs:,} runs in {report.seconds:.0f} s ({report.runs_per_second:.2f} runs/s, "
          f"{report.steps / max(report.runs, 1):,.0f} steps a run){' - ' + report.stopped if report.stopped else ''}")
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
                    help="quadcopter: answer quadcopter.q's queries at epsilon 0.01, delta 0.05 (18,445 runs "
                         "of 10 s each, the same runs for every query)")
    ap.add_argument("--query-runs", type=int, help="quadcopter: this many runs for the queries instead")
    ap.add_argument("--query-workers", type=int, default=2, help="quadcopter: Dask workers for the queries")
    ap.add_argument("--budget", type=float, default=0,
                    help="quadcopter: stop the queries' runs after this many seconds (the intervals of the runs read)")
    ap.add_argument("--batch", type=int, default=20, help="quadcopter: runs per batch for the queries")
    ap.add_argument("--default-environment", action="store_true",
                    help="quadcopter: the default environment instead of the artefact's client")
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
