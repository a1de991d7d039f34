"""RobNav's schedulability study run by genom2bip, beside the published UPPAAL results.

Run ``python bench/robnav_bench.py ARTEFACT_DIR [--cores 1-5] [--jobs N] [--exceptions] [--keep DIR] [--smc RUNS]``.

ARTEFACT_DIR is a clone of the public schedulability artefact of the RobNav
functional level (four components robloco, robmotion, robmap, roblaser, each
``NAME/NAME.gen``, and the UPPAAL model ``robnav-artefact-edf.xta``).  Its
``.gen`` files include ``robsim/robsim-struct.idl``, which is not public: put a
stub declaring ``robsim::map`` and ``robsim::cell_type`` there first.

The script reads from the ``.xta`` what its authors set by hand: each codel's
execution interval (the invariant ``x <= max`` of the state the codel runs in,
the guard ``x >= min`` or ``x == v`` leaving it), the offset of a task whose
timer starts when another task's initial codel ends, the client's requests in
order, and when the components take them (each control task waits for a
task's initial codel: robloco's for track's, which starts when odo's ends, so
20 ms at the latest).  It writes them as a genom2bip platform file (cooperative
EDF, ``nc`` cores, the releases of one instant seen one by one as the
artefact's timers fire: ``--releases together`` queues them all before a core
is granted) and a client mission (the first request sent once every
component takes requests, each next one once the previous one is queued;
``--requests-at-start`` sends them at 0 ms instead), then runs
``verify --timed --platform P --client C --response-times`` through the
verification API, one process per ``nc`` (for its peak memory), as many at
once as this process has cores (``--jobs N`` to choose), which is how a
second core pays (docs/verification/scale.md); rows run at once share the
default memory budget.
Printed per ``nc``: whether task ``track`` keeps its period, the largest
response time of each task beside the published one, states, seconds, MB.

``--suspension 0-50`` runs the artefact's suspension study instead: the task
whose manager has a ``delay`` state in ``robnav-artefact-edf-suspension.xta``
(plan) waits ``sd`` ms once granted its core, keeping it, before its codels
(``suspend: {for: SD ms, after: grant}``), one row per ``sd`` beside the
artefact's ``res.csv``.

The artefact's templates give codels no exception: they take their declared
yields only.  The default here is the same (``--no-exceptions``);
``--exceptions`` keeps genom2bip's default, where every codel of a service
that declares ``throw`` may also end in its exception.
"""
from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import re
import resource
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from genom2bip.verify.options import default_memory  # noqa: E402

COMPONENTS = ("robloco", "robmotion", "robmap", "roblaser")
#: The artefact's README and res.csv (row sd = 0): largest response time per task at nc = 4, in ms.
PUBLISHED = {"robloco.odo": 40, "robloco.track": 40, "robmap.fuse": 45, "roblaser.scan": 65, "robmotion.plan": 60}
#: The artefact's finding: task track keeps its period from 4 cores on, not with 3.
PUBLISHED_SCHEDULABLE_FROM = 4

PROCESS = re.compile(r"^process\s+(\w+)\s*\(.*?\)\s*\{(.*?)^\}", re.S | re.M)
INVARIANT = re.compile(r"(\w+)\s*\{\s*x\s*<=\s*(\d+)\s*\}")
LEAVING = re.compile(r"(\w+)\s*->\s*\w+\s*\{\s*guard\s+x\s*(>=|==)\s*(\d+)\s*;")
SPAWN = re.compile(r"idle\s*->\s*start\s*\{\s*sync\s+end_spawn_(\w+?)_(\w+)\?")
ACCEPTS = re.compile(r"unspawned\s*->\s*receive\s*\{\s*sync\s+end_spawn_(\w+?)_(\w+)\?")
REQUEST = re.compile(r"(\w+)\s*->\s*\w+\s*\{\s*sync\s+recv_(\w+)!\s*;\s*assign\s+req_\w+\s*:=\s*(\w+?)_\2\s*;")


def read_artefact(xta: str, description) -> tuple[dict[str, tuple[int, int]], dict[str, tuple[int, int]], list[str],
                                                  int]:
    """Execution intervals per ``Component.Owner.codel``, task offsets, the client's requests, and the latest time
    every component that receives one takes requests (its control task waits for a task's initial codel), from
    the .xta."""
    components = {c.name: c for c in description.components}
    execution: dict[str, tuple[int, int]] = {}
    offsets: dict[str, tuple[int, int]] = {}
    requests: list[tuple[int, str]] = []
    init_of: dict[str, tuple[int, int]] = {}
    accepts: dict[str, tuple[str, str]] = {}  # component -> the task whose initial codel its control waits for
    for name, body in PROCESS.findall(xta):
        high = {state.rstrip("_2").rstrip("_"): int(v) for state, v in INVARIANT.findall(body)}
        low = {state.rstrip("_2").rstrip("_"): int(v) for state, _, v in LEAVING.findall(body)}
        perm = re.fullmatch(r"Perm_(\w+?)_(\w+)", name)
        activity = re.fullmatch(r"(\w+?)_(\w+)_", name)
        owner = None
        if perm:  # a task's permanent activity: its initial codels
            owner, comp = perm.groups()
            codels = next(t for t in components[comp].tasks if t.name == owner).codels
        elif activity and activity.group(2) in components:
            owner, comp = activity.groups()
            codels = next(s for s in components[comp].services if s.name == owner).codels
        for codel in codels if owner else ():
            state = codel.triggers[0]
            if state in high:
                execution[f"{comp}.{owner}.{codel.name}"] = (low.get(state, high[state]), high[state])
                if perm:
                    init_of[f"{comp}.{owner}"] = execution[f"{comp}.{owner}.{codel.name}"]
        if name == "client":
            order = {"start": 0} | {f"s{k}": k for k in range(1, 100)}
            requests += [(order[src], f"{comp}.{service}") for src, comp, service in REQUEST.findall(body)]
        control = re.fullmatch(r"control_(\w+)", name)
        if control and ACCEPTS.search(body):
            accepts[control.group(1)] = ACCEPTS.search(body).groups()
        timer = re.fullmatch(r"Timer_(\w+?)_(\w+)", name)
        spawn = SPAWN.search(body)
        if timer and spawn:
            offsets[f"{timer.group(2)}.{timer.group(1)}"] = (spawn.group(1), spawn.group(2))
    offsets = {task: init_of[f"{comp}.{other}"] for task, (other, comp) in offsets.items()}
    requests = [r for _, r in sorted(requests)]
    ready = 0
    for comp in {r.split(".")[0] for r in requests}:
        task, _ = accepts[comp]
        ready = max(ready, init_of[f"{comp}.{task}"][1] + offsets.get(f"{comp}.{task}", (0, 0))[1])
    return execution, offsets, requests, ready


def suspending_task(xta: str) -> str | None:
    """``Component.task`` whose manager waits in a ``delay`` state (the artefact's suspension model), if any."""
    for name, body in PROCESS.findall(xta):
        manager = re.fullmatch(r"Manager_(\w+?)_(\w+)", name)
        if manager and re.search(r"\bdelay\s*\{", body):
            return f"{manager.group(2)}.{manager.group(1)}"
    return None


def published_by_sd(path: Path) -> dict[int, dict[str, int]]:
    """The artefact's res.csv: the largest response time per task (ms) at nc = 4, per suspension delay ``sd``."""
    names = {"odo": "robloco.odo", "track": "robloco.track", "fuse": "robmap.fuse", "scan": "roblaser.scan",
             "plan": "robmotion.plan"}
    rows = [line.strip().strip(";").split(";") for line in path.read_text().splitlines() if line.strip()]
    head = [h.replace("MRT ", "") for h in rows[0]]
    out = {}
    for row in rows[1:]:
        values = dict(zip(head, row))
        out[int(values["sd"])] = {names[k]: int(v) for k, v in values.items() if k in names}
    return out


def platform_text(cores: int, execution: dict, offsets: dict, releases: str = "one-by-one",
                  suspend: dict[str, int] | None = None) -> str:
    lines = [f"cores: {cores}", "policy: edf", f"releases: {releases}", "execution:"]
    lines += [f"  {key}: [{lo} ms, {hi} ms]" for key, (lo, hi) in execution.items()]
    tasks = {t: [f"    delay: [{lo} ms, {hi} ms]"] for t, (lo, hi) in offsets.items()}
    for task, ms in (suspend or {}).items():
        tasks.setdefault(task, []).append(f"    suspend: {{for: {ms} ms, after: grant}}")
    if tasks:
        lines.append("tasks:")
        for task, settings in tasks.items():
            lines += [f"  {task}:"] + settings
    return "\n".join(lines) + "\n"


def client_text(requests: list[str], after: int, inputs: dict[str, dict] | None = None) -> str:
    """The client mission; ``inputs``: each request's ``with:`` (none where absent)."""
    first = f"    after: {after} ms\n" if after else ""
    given = inputs or {}
    steps = "".join(f"  - send: {r}\n{first if k == 0 else ''}"
                    + (f"    with: {json.dumps(given[r])}\n" if given.get(r) else "") + "    until: queued\n"
                    for k, r in enumerate(requests))
    return f"mission: robnav-client\nsteps:\n{steps}"


def request_inputs(description, requests: list[str]) -> dict[str, dict]:
    """Zero values for each request's inputs that have no default: the artefact's client sends none (its model
    has no data), and the controller refuses a request whose inputs are missing."""
    from genom2bip.back.interface import interface_data, zero

    data = interface_data(description, "robnav", "")
    out = {}
    for r in requests:
        component, _, service = r.partition(".")
        spec = data["components"][component]["services"][service]
        out[r] = {p["name"]: zero(p["schema"], data.get("types", {})) for p in spec["parameters"]
                  if p["direction"] in ("in", "inout") and p["source"] != "ids" and "default" not in p}
    return out


def run(paths, include, platform, client, exceptions, limits, shown, queue) -> None:
    """One ``nc``: the timing checks and response times, in a process of its own (its peak memory is the run's)."""
    from genom2bip.loading import TimeSettings
    from genom2bip.verify.model import build_model
    from genom2bip.verify.options import Listener, SearchOptions
    from genom2bip.verify.zones import ResponseResult, check_timing
    from runtime.explore import Progress

    class Shown(Listener):
        def progress(self):
            return Progress(force=shown)  # states, rate, frontier and memory: on a terminal, or asked

    settings = TimeSettings(platform=platform, client=client, responses=True, exceptions=exceptions)
    model = build_model(paths, include_dirs=[include], no_rules=True, time=settings)
    start = time.perf_counter()
    results = check_timing(model, kinds=("overrun",), responses=True, options=SearchOptions(**limits),
                           listener=Shown())
    seconds = time.perf_counter() - start
    out = {"seconds": seconds, "mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, "verdicts": {},
           "responses": {}, "so_far": set()}
    for r in results:
        out["states"] = r.figures.states
        if isinstance(r, ResponseResult):
            if r.kind == "task":
                out["responses"][r.owner] = "inf" if r.unbounded else r.value_ms
                if r.verdict.value == "inconclusive":  # the search stopped first: the largest seen so far
                    out["so_far"].add(r.owner)
                    out["limit"] = r.limit
        else:
            out["verdicts"][r.observer.rsplit(".", 1)[0]] = r.verdict.value
    queue.put(out)


def main() -> None:
    """Every ``nc`` asked, one process each, and the table beside the published figures."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("artefact", type=Path)
    ap.add_argument("--cores", default="1-5", help="a range (1-5) or a list (3,4)")
    ap.add_argument("--exceptions", action="store_true", help="codels may also end in their service's exceptions")
    ap.add_argument("--max-states", type=int, default=5_000_000)
    ap.add_argument("--max-memory", type=int, metavar="MB",
                    help="stop a row's search past MB megabytes (default: half the machine's memory)")
    ap.add_argument("--jobs", type=int, default=None,
                    help="rows run at once, each in its own process (default: one per core this process may use)")
    ap.add_argument("--progress", action="store_true", help="progress lines on stderr even when it is not a terminal")
    ap.add_argument("--keep", type=Path, help="write the platform files and the client mission there")
    ap.add_argument("--requests-at-start", action="store_true",
                    help="send the requests at time 0, before the initial codels end (the artefact's control tasks "
                         "take requests only once their task's initial codel has ended)")
    ap.add_argument("--releases", choices=("one-by-one", "together"), default="one-by-one",
                    help="tasks released at one instant: one by one, the first taking a free core before the next is "
                         "queued, as in the artefact's model (default); or all queued before a core is granted")
    ap.add_argument("--suspension", metavar="SD",
                    help="suspension delays in ms of the task whose manager suspends in "
                         "robnav-artefact-edf-suspension.xta (a range 0-50 or a list 0,11,30): one row per value, "
                         "beside the artefact's res.csv")
    ap.add_argument("--smc", type=int, metavar="RUNS",
                    help="statistical model checking instead: RUNS random runs of 1 s per nc, the largest response "
                         "time each task reaches beside the exhaustive one (bench/smc_bench.py --robnav)")
    args = ap.parse_args()
    cores = _numbers(args.cores)
    if args.jobs is None:  # one row per core, never more processes than rows
        rows = len(cores) * (len(_numbers(args.suspension)) if args.suspension is not None else 1)
        args.jobs = max(1, min(len(os.sched_getaffinity(0)), rows))
    if args.smc is not None:
        import smc_bench

        for nc in cores:
            smc_bench.robnav(argparse.Namespace(robnav=args.artefact, cores=nc, runs=args.smc, seed=1,
                                                time_bound="1 s"))
        return
    if args.suspension is not None:
        return suspension_rows(args, cores, _numbers(args.suspension))
    paths, out, execution, offsets, requests, after = prepare(args)
    print(f"{len(execution)} codel intervals, offsets {offsets}, client {' -> '.join(requests)}, "
          f"the first request at {after} ms")
    print(f"exceptions: {'as genom2bip models them' if args.exceptions else 'none (as the artefact)'}; "
          f"releases at one instant: {args.releases}; files in {out}")
    rows = []
    platforms = []
    for nc in cores:
        platforms.append(out / f"edf{nc}.yaml")
        platforms[-1].write_text(platform_text(nc, execution, offsets, args.releases))
    start = time.perf_counter()
    for nc, got in zip(cores, runs(args, paths, platforms, out)):
        rows.append((nc, got))
        show(nc, got)
    print(f"\n{len(cores)} row(s) in {time.perf_counter() - start:.1f} s wall clock, {args.jobs} at a time")
    print()
    holds = [nc for nc, g in rows if _track_ok(g)]
    print(f"track keeps its period with {', '.join(map(str, holds)) or 'none'} of the cores tried "
          f"({', '.join(str(nc) for nc, _ in rows)}); published: from {PUBLISHED_SCHEDULABLE_FROM} on")


def prepare(args) -> tuple[list[str], Path, dict, dict, list[str], int]:
    """The artefact read (paths, codel intervals, offsets, requests, when the first is sent) and the client mission
    written into the output directory."""
    from genom2bip.parser import parse_paths

    paths = [str(args.artefact / c / f"{c}.gen") for c in COMPONENTS]
    description = parse_paths(paths, [str(args.artefact)])
    execution, offsets, requests, ready = read_artefact((args.artefact / "robnav-artefact-edf.xta").read_text(),
                                                        description)
    after = 0 if args.requests_at_start else ready
    out = args.keep or Path(tempfile.mkdtemp(prefix="robnav-"))
    out.mkdir(parents=True, exist_ok=True)
    (out / "client.yaml").write_text(client_text(requests, after, request_inputs(description, requests)))
    return paths, out, execution, offsets, requests, after


def one_run(ctx, args, paths: list[str], platform: Path, out: Path) -> dict:
    """The checks of one platform file, in a process of their own (:func:`run`)."""
    queue = ctx.Queue()
    proc = ctx.Process(target=run, args=(paths, str(args.artefact), str(platform), str(out / "client.yaml"),
                                         args.exceptions, _limits(args), args.progress, queue))
    proc.start()
    got = queue.get()
    proc.join()
    return got


class _Box:
    """What :func:`run` puts, for a row run by a process pool (which returns it rather than queueing it)."""

    def put(self, value) -> None:
        self.value = value


def _row(*arguments) -> dict:
    """:func:`run` in a pool's process: its figures returned."""
    box = _Box()
    run(*arguments, box)
    return box.value


def runs(args, paths: list[str], platforms: list[Path], out: Path):
    """Each platform file's checks, in order; with ``--jobs N``, N rows at once, each in a fresh process (its peak
    memory its own): the rows are independent searches, which is how two cores pay (docs/verification/scale.md)."""
    ctx = multiprocessing.get_context("spawn")
    if args.jobs <= 1:
        for platform in platforms:
            yield one_run(ctx, args, paths, platform, out)
        return
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(args.jobs, mp_context=ctx, max_tasks_per_child=1) as pool:
        futures = [pool.submit(_row, paths, str(args.artefact), str(platform), str(out / "client.yaml"),
                               args.exceptions, _limits(args), args.progress) for platform in platforms]
        for future in futures:
            yield future.result()


def _limits(args) -> dict:
    """The search's budgets (SearchOptions' fields) from the command line; without ``--max-memory``, rows run at
    once share the default budget (half the machine's memory) instead of each taking all of it."""
    memory, half = args.max_memory, default_memory()
    if memory is None and args.jobs > 1 and half:
        memory = max(1, half // args.jobs // 2**20)
    return {"max_states": args.max_states, "max_memory_mb": memory}


def _numbers(text: str) -> list[int]:
    """``1-5`` or ``3,4``."""
    if "-" in text:
        lo, hi = map(int, text.split("-"))
        return list(range(lo, hi + 1))
    return [int(c) for c in text.split(",")]


def suspension_rows(args, cores: list[int], delays: list[int]) -> None:
    """One run per suspension delay (and nc), the largest response times beside res.csv's row of that delay."""
    task = suspending_task((args.artefact / "robnav-artefact-edf-suspension.xta").read_text())
    if task is None:
        raise SystemExit("robnav-artefact-edf-suspension.xta: no manager with a 'delay' state")
    published = published_by_sd(args.artefact / "res.csv") if (args.artefact / "res.csv").exists() else {}
    paths, out, execution, offsets, _, _ = prepare(args)
    order = ["robloco.odo", "robloco.track", "robmap.fuse", "roblaser.scan", "robmotion.plan"]
    print(f"{task} waits sd ms once granted its core, keeping it (the artefact's 'delay' state); "
          f"nc = {', '.join(map(str, cores))}; files in {out}")
    print("response times in ms, genom2bip / published (res.csv, nc = 4)")
    print(f"{'nc':>3} {'sd':>3}  {'track ok':8} " + " ".join(f"{t.split('.')[1]:>9}" for t in order)
          + f" {'states':>9} {'time':>7}")
    grid = [(nc, sd) for nc in cores for sd in delays]
    platforms = []
    for nc, sd in grid:
        platforms.append(out / f"edf{nc}-sd{sd}.yaml")
        platforms[-1].write_text(platform_text(nc, execution, offsets, args.releases, {task: sd} if sd else None))
    start = time.perf_counter()
    for (nc, sd), got in zip(grid, runs(args, paths, platforms, out)):
        ref = published.get(sd, {}) if nc == 4 else {}
        cells = []
        for t in order:
            value = got["responses"].get(t)
            mine = "inf" if value == "inf" else ("?" if value is None else f"{value:g}")
            cells.append(f"{mine + '/' + str(ref[t]) if t in ref else mine:>9}")
        track = next((v for o, v in got["verdicts"].items() if o == "robloco.track"), "?")
        print(f"{nc:>3} {sd:>3}  {track:8} " + " ".join(cells)
              + f" {got.get('states', 0):>9,} {got['seconds']:>6.1f}s", flush=True)
    print(f"{len(grid)} row(s) in {time.perf_counter() - start:.1f} s wall clock, {args.jobs} at a time")


def _track_ok(got: dict) -> bool:
    return any(o == "robloco.track" and v == "holds" for o, v in got["verdicts"].items())


def show(nc: int, got: dict) -> None:
    track = next((v for o, v in got["verdicts"].items() if o == "robloco.track"), "?")
    from genom2bip.cli.verify_timed import STOPPED

    limit = got.get("limit") or "max-states"
    stopped = f" (stopped {STOPPED.get(limit, limit)}: response times so far)" if got.get("so_far") else ""
    print(f"\nnc = {nc}: track keeps its period: {track}; {got.get('states', 0):,} symbolic states{stopped}, "
          f"{got['seconds']:.1f} s, {got['mb']:.0f} MB")
    print(f"  {'task':16} {'genom2bip':>10} {'published (nc=4)':>17}")
    for task, value in sorted(got["responses"].items()):
        shown = "unbounded" if value == "inf" else ("> cap" if value is None else f"{value:g} ms")
        if task in got.get("so_far", ()) and value not in ("inf", None):
            shown = f">= {value:g} ms"  # a lower bound: the search stopped at its budget
        print(f"  {task:16} {shown:>10} {PUBLISHED.get(task, '-'):>14} ms")


if __name__ == "__main__":
    main()
