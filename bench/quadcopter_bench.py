"""The quadcopter's timing by clock zones: each task's period verdict and response time, or how far the search got.

Run ``python bench/quadcopter_bench.py ARTEFACT_DIR -I STUBS [--platform P] [--time-limit 10min] [--waypoints N]``.

ARTEFACT_DIR is a clone of Foughali's quadcopter artefact (Mo-F/uppaal-smc-exp: ``all.gen`` including five
components, ``quadcopter.xta``).  Its components include openrobots interfaces (``or/pose/pose_estimator.gen``...)
that the artefact does not ship: give a directory of stubs with ``-I`` (as for bench/smc_bench.py --quadcopter).

The environment is the artefact's own client, read from the ``client`` process of ``quadcopter.xta`` and written
as a genom2bip client mission (docs/missions.md): each request in the order of its automaton, each waiting on
its clock guard (``x == 1000`` after the start: 10 ms, the model's unit being 10 us), each next one sent once the
previous one is queued.  The automaton chooses how many ``waypoint`` requests to send (a self-loop while
``count < max``, 0 to 5); a mission has no choice, so ``--waypoints N`` fixes it (default: the largest), and the
union of the runs for 0..max is the artefact's client.  ``--client default`` uses genom2bip's default
environment instead (any service at most once per period of its task).

One zone search (``verify --timed --platform P --client C --response-times`` through the verification API) with a
budget (``--time-limit``, ``--max-states``, ``--max-memory-mb``: past it the search is stopped as Ctrl-C stops it).
Printed: per task whether it keeps its period and its largest response time; when the search stopped at its
budget, how far it got (symbolic states, discrete states, depth of the breadth-first search, frontier, memory) and
the largest response times reached so far as lower bounds.

``--exact-first DURATION`` searches first the platform with every codel taking exactly its WCET: a subset of the
platform's runs, so its overruns (``--traces`` prints them) are the platform's and its response times lower bounds
of the platform's; a last table gives each task's answer from both.  ``--por`` turns on the zone search's
partial-order reduction.  docs/verification/scale.md has the figures.
"""
from __future__ import annotations

import argparse
import os
import re
import signal
import resource
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

#: One time unit of the artefact's UPPAAL model, in µs (its README: 100 units are 1 ms).
UNIT_US = 10

TRANSITION = re.compile(r"(\w+)\s*->\s*(\w+)\s*\{([^}]*)\}")
CONSTANT = re.compile(r"const\s+int\s+(\w+)\s*:=\s*(-?\d+)\s*;")
INIT = re.compile(r"\binit\s+(\w+)\s*;")
SEND = re.compile(r"sync\s+recv(?:_urg)?_(\w+)!\s*;\s*assign\s+req_\1\s*:=\s*(\w+)")
WAIT = re.compile(r"guard\s+x\s*==\s*(\w+)\s*;")
LOOP = re.compile(r"(\w+)\s*<\s*(\w+)")
RESET = re.compile(r"[\s,;]x\s*:=\s*0\b")


@dataclass
class Step:
    """One request of the client: ``Component.service``, sent ``after_us`` after the previous one was queued."""

    request: str
    after_us: int = 0


@dataclass
class Client:
    """The artefact's client: requests in order; ``repeat`` the request its automaton may send 0..``most`` times."""

    steps: list[Step] = field(default_factory=list)
    repeat: Step | None = None
    at: int = 0  # the index in ``steps`` where the repeated request goes
    most: int = 0

    def mission(self, times: int) -> list[Step]:
        """The requests with the repeated one sent ``times`` times."""
        return self.steps[:self.at] + [Step(self.repeat.request)] * times + self.steps[self.at:] if self.repeat \
            else list(self.steps)


class ClientError(Exception):
    """The client process is not a chain of requests and clock waits this script reads."""


def read_client(xta: str) -> Client:
    """The ``client`` process of the artefact's .xta as a chain of requests (see the module's docstring)."""
    from robnav_bench import PROCESS

    body = next((b for name, b in PROCESS.findall(xta) if name == "client"), None)
    if body is None:
        raise ClientError("no process 'client' in the .xta")
    constants = {k: int(v) for k, v in CONSTANT.findall(body)}
    init = INIT.search(body)
    if init is None:
        raise ClientError("the client process has no 'init'")
    edges: dict[str, list[tuple[str, str]]] = {}
    for src, dst, label in TRANSITION.findall(body):
        edges.setdefault(src, []).append((dst, label))
    client, state, wait, seen = Client(), init.group(1), 0, set()
    known = 0  # units since x was last reset, while that is known (x starts at 0; a request goes when it can)
    while state in edges and state not in seen:
        seen.add(state)
        out = edges[state]
        loops = [label for dst, label in out if dst == state]
        onward = [(dst, label) for dst, label in out if dst != state]
        if len(onward) != 1 or len(loops) > 1:
            raise ClientError(f"state {state}: {len(onward)} ways on and {len(loops)} loops (one and at most one "
                              f"expected)")
        if loops:
            send, bound = SEND.search(loops[0]), LOOP.search(loops[0].split("sync")[0])
            if send is None or bound is None:
                raise ClientError(f"state {state}: a loop that is not a bounded request")
            client.repeat, client.at = Step(_request(*send.groups())), len(client.steps)
            client.most = constants.get(bound.group(2), int(bound.group(2)) if bound.group(2).isdigit() else 0)
        dst, label = onward[0]
        guard = WAIT.search(label)
        if guard:
            name = guard.group(1)
            at = constants[name] if name in constants else int(name)
            if known is None or at < known:
                raise ClientError(f"state {state}: waits for x == {name}, but the time since x was reset is not "
                                  f"known there (a request was sent since, without resetting x)")
            wait, known = wait + at - known, at
        send = SEND.search(label)
        if send:
            client.steps.append(Step(_request(*send.groups()), wait * UNIT_US))
            wait, known = 0, None
        if RESET.search(label):
            known = 0
        state = dst
    if not client.steps:
        raise ClientError("the client sends no request")
    return client


def _request(component: str, value: str) -> str:
    """``Component.service`` from the .xta's ``req_C := service_C``."""
    return f"{component}.{value.removesuffix('_' + component)}"


def mission_text(steps: list[Step], inputs: dict[str, dict]) -> str:
    """A client mission: each request once the previous one is queued, after its wait."""
    import json

    lines = ["mission: quadcopter-client", "steps:"]
    for s in steps:
        lines.append(f"  - send: {s.request}")
        if s.after_us:
            lines.append(f"    after: {s.after_us / 1000:g} ms")
        if inputs.get(s.request):
            lines.append(f"    with: {json.dumps(inputs[s.request])}")
        lines.append("    until: queued")
    return "\n".join(lines) + "\n"


def bfs_depth(nodes) -> int:
    """The depth of the breadth-first search: the longest chain of parents among the stored nodes (a parent is
    stored before its children).  The C search's nodes are read as a column (1: the parent), not as objects."""
    search = getattr(nodes, "search", None)
    parents = search.back.column(1).tolist() if search is not None else [n.parent for n in nodes]
    depth = [0] * len(parents)
    for k, parent in enumerate(parents):
        if parent >= 0:
            depth[k] = depth[parent] + 1
    return max(depth, default=0)


def run(args, client_file: Path | None, platform: Path | None, time_limit: float) -> dict:
    """Build the model, search it within the budget, print the verdicts or how far it got; the period results and
    task response times by task."""
    import genom2bip.verify.zones as zones
    from genom2bip.verify.model import build_model
    from genom2bip.verify.options import Listener, SearchOptions
    from genom2bip.verify.results import Verdict
    from genom2bip.verify.zones import ResponseResult, check_timing
    from runtime.explore import Progress

    class Recorded(Progress):
        """The progress line, and the last frontier it was given (for the summary)."""

        frontier = 0
        over_memory = False

        def tick(self, states, transitions, frontier, memory, depth=None):
            Recorded.frontier = frontier
            if not Recorded.over_memory and memory() > args.max_memory_mb * 1024 * 1024:
                Recorded.over_memory = True  # stopped as by Ctrl-C: the search reports what it found so far
                os.kill(os.getpid(), signal.SIGINT)
            super().tick(states, transitions, frontier, memory, depth)

    class Shown(Listener):
        def progress(self):
            return Recorded(force=args.progress)

        def found(self, result):
            print(f"  found at {result.figures.seconds:.0f} s: {result.subject} violated", flush=True)

        def so_far(self, text):
            print(f"  so far: {text}", flush=True)

    made = []
    original = zones.explorer

    def keep(model, options=None):  # the explorer check_timing makes, kept for the depth of its search
        made.append(original(model, options))
        made[-1].reduce = args.por  # the zone search's partial-order reduction (runtime/zones/reduction.py)
        return made[-1]

    from genom2bip.loading import TimeSettings

    settings = TimeSettings(platform=str(platform) if platform else None,
                            client=str(client_file) if client_file else None, responses=True, exceptions=False)
    start = time.perf_counter()
    model = build_model([args.artefact / "all.gen"], include_dirs=[str(args.artefact), *args.include],
                        no_rules=True, time=settings)
    print(f"model built in {time.perf_counter() - start:.1f} s", flush=True)
    options = SearchOptions(max_states=args.max_states, time_limit=time_limit)
    zones.explorer = keep
    start = time.perf_counter()
    try:
        results = check_timing(model, kinds=("overrun",), responses=True, options=options, listener=Shown())
    finally:
        zones.explorer = original
    seconds = time.perf_counter() - start
    mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    periods = [r for r in results if not isinstance(r, ResponseResult)]
    tasks = {r.owner: r for r in results if isinstance(r, ResponseResult) and r.kind == "task"}
    services = [r for r in results if isinstance(r, ResponseResult) and r.kind == "service"]
    figures = results[0].figures if results else None
    stopped = next((r.limit for r in results if r.verdict is Verdict.INCONCLUSIVE and r.limit), "")
    if stopped and Recorded.over_memory:
        stopped = f"memory: the search held more than {args.max_memory_mb:,} MB"
    z = made[-1] if made else None
    print()
    if stopped:
        depth = bfs_depth(z.nodes) if z is not None else 0
        discrete = re.search(r"([\d,]+) discrete", figures_method(results))
        discrete = discrete.group(1) if discrete else "?"
        print(f"stopped ({stopped}; budget: {_budget(args, time_limit)}) after {seconds:.0f} s: "
              f"{figures.states:,} symbolic states ({discrete} discrete), {figures.transitions:,} transitions, "
              f"depth {depth:,}, frontier {Recorded.frontier:,}, {mb:,.0f} MB")
    else:
        print(f"complete: {figures.states:,} symbolic states, {figures.transitions:,} transitions, "
              f"{seconds:.1f} s, {mb:,.0f} MB")
    print(f"  {'task':24} {'period':>9} {'keeps its period':>17} {'largest response time':>22}")
    for r in periods:
        owner = r.observer.rsplit(".", 1)[0]
        response = tasks.get(owner)
        period = f"{response.ms(response.period_ticks):g} ms" if response and response.period_ticks else "-"
        print(f"  {owner:24} {period:>9} {r.verdict.value:>17} {_value(response):>22}")
    for owner, response in sorted(tasks.items()):
        if not any(r.observer.rsplit(".", 1)[0] == owner for r in periods):
            print(f"  {owner:24} {'-':>9} {'-':>17} {_value(response):>22}")
    if services:
        print("  services: " + ", ".join(f"{r.owner} {_value(r)}" for r in services))
    for r in periods:
        if args.traces and r.trace is not None:
            from genom2bip.cli.verify_timed import timed_trace

            print(f"\n{r.subject}: violated; its trace, replayed on the tick model:")
            timed_trace(r.trace)
    return {r.observer.rsplit(".", 1)[0]: (r, tasks.get(r.observer.rsplit(".", 1)[0])) for r in periods}


def exact_platform(platform: Path, out: Path) -> Path:
    """The platform with every codel taking exactly its worst case (``best: wcet``, each listed interval at its
    upper end): its runs are runs of the platform, so its overruns are the platform's and its response times
    lower bounds of the platform's, and it branches only where tasks race, not on each codel's duration."""
    import yaml

    data = yaml.safe_load(platform.read_text()) or {}
    data["best"] = "wcet"
    for key, value in (data.get("execution") or {}).items():
        if isinstance(value, list) and len(value) == 2:
            data["execution"][key] = [value[1], value[1]]
    path = out / f"{platform.stem}-exact.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def both(exact: dict, full: dict) -> None:
    """Each task's answer on the platform from the two searches: an overrun of the exact search is one of the
    platform's; a response time of either is a lower bound of the platform's, exact where the full search ended."""
    from genom2bip.verify.results import Verdict
    from genom2bip.verify.zones import ABOVE_CAP

    print("\non the platform, from both searches (an overrun with exact WCETs is an overrun of the platform):")
    print(f"  {'task':24} {'keeps its period':>17} {'largest response time':>22}")
    for owner, (r, response) in full.items():
        first, first_response = exact.get(owner, (None, None))
        verdict = r.verdict.value
        if r.verdict is not Verdict.VIOLATED and first is not None and first.verdict is Verdict.VIOLATED:
            verdict = "violated (exact)"
        bounds = []  # (ms, above): a value reached, or past the observer's cap
        for x in (response, first_response):
            if x is not None and x.value_ticks is not None:
                bounds.append((x.value_ms, False))
            elif x is not None and x.message == ABOVE_CAP:
                bounds.append((x.ms(x.cap_ticks), True))
        if response is not None and response.verdict is not Verdict.INCONCLUSIVE:
            shown = _value(response)
        elif bounds:
            ms, above = max(bounds)
            shown = f"{'>' if above else '>='} {ms:g} ms"
        else:
            shown = _value(response)
        print(f"  {owner:24} {verdict:>17} {shown:>22}")


def figures_method(results) -> str:
    """How the results were found (``zones, N discrete states``)."""
    return results[0].method if results else ""


def _budget(args, time_limit: float | None = None) -> str:
    parts = []
    if time_limit or args.time_limit:
        parts.append(f"time limit {time_limit or args.time_limit:g} s")
    if args.max_states:
        parts.append(f"{args.max_states:,} states")
    parts.append(f"{args.max_memory_mb:,} MB")
    return ", ".join(parts)


def _value(r) -> str:
    """A response time: its maximum, a lower bound when the search stopped, or why there is no number."""
    from genom2bip.verify.results import Verdict
    from genom2bip.verify.zones import ABOVE_CAP, response_value

    if r is None:
        return "-"
    if r.verdict is Verdict.INCONCLUSIVE:
        if r.value_ticks is not None:
            return f">= {r.value_ms:g} ms"
        if r.message == ABOVE_CAP:
            return f"> {r.ms(r.cap_ticks):g} ms"
        return "not requested yet" if r.message == "never requested" else "not reached yet"
    value = response_value(r)
    return f"{value:g} ms" if isinstance(value, float) else str(value)


def budget_seconds(text: str) -> float | None:
    """``10 min``, ``30 s``, or ``10m`` as timeout(1) writes ten minutes: seconds; None when it is no duration."""
    from genom2bip.durations import parse_duration

    us = parse_duration(re.sub(r"(\d)\s*m\Z", r"\1 min", text))
    return us / 1e6 if us else None


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("artefact", type=Path)
    ap.add_argument("-I", dest="include", action="append", default=[], metavar="DIR",
                    help="a directory of the openrobots interfaces the artefact includes (stubs will do)")
    ap.add_argument("--platform", type=Path, help="a platform file (default: a core per task)")
    ap.add_argument("--time-limit", default="10 min", help="the search's budget in time: 30 s, 10 min, 10m "
                                                            "(default 10 min)")
    ap.add_argument("--max-states", type=int, help="the search's budget in symbolic states")
    ap.add_argument("--max-memory-mb", type=int, default=6000,
                    help="stop when the search holds more than this (default 6000 MB), as Ctrl-C stops it")
    ap.add_argument("--client", choices=("artefact", "default"), default="artefact",
                    help="the artefact's client as a mission (default), or genom2bip's default environment")
    ap.add_argument("--waypoints", type=int, help="how many waypoint requests the client sends (default: the most "
                                                  "its automaton sends)")
    ap.add_argument("--por", action="store_true",
                    help="the zone search's partial-order reduction where time cannot pass "
                         "(runtime/zones/reduction.py)")
    ap.add_argument("--exact-first", metavar="DURATION",
                    help="search first, for DURATION, the platform with every codel taking exactly its WCET: a subset "
                         "of its runs, which reaches overruns deeper in time (their traces are the platform's)")
    ap.add_argument("--traces", action="store_true", help="print the trace of each period overrun found")
    ap.add_argument("--keep", type=Path, help="write the client mission there")
    ap.add_argument("--progress", action="store_true", help="progress lines on stderr even when not a terminal")
    args = ap.parse_args()
    limit = budget_seconds(args.time_limit)
    if limit is None:
        ap.error(f"--time-limit: not a duration: {args.time_limit!r}")
    args.time_limit = limit
    if args.exact_first is not None:
        args.exact_first = budget_seconds(args.exact_first)
        if args.exact_first is None:
            ap.error("--exact-first: not a duration")
    client_file = None
    if args.client == "artefact":
        from robnav_bench import request_inputs

        from genom2bip.parser import parse_paths

        try:
            client = read_client((args.artefact / "quadcopter.xta").read_text())
        except (ClientError, OSError) as exc:
            print(f"quadcopter.xta: {exc}", file=sys.stderr)
            return 1
        times = client.most if args.waypoints is None else args.waypoints
        steps = client.mission(times)
        description = parse_paths([str(args.artefact / "all.gen")], [str(args.artefact), *args.include])
        out = args.keep or Path(tempfile.mkdtemp(prefix="quadcopter-"))
        out.mkdir(parents=True, exist_ok=True)
        client_file = out / "client.yaml"
        client_file.write_text(mission_text(steps, request_inputs(description, [s.request for s in steps])))
        repeat = f"; {client.repeat.request} {times} of 0..{client.most} times" if client.repeat else ""
        print("client (the artefact's): " + " -> ".join(
            (f"[{s.after_us / 1000:g} ms] " if s.after_us else "") + s.request for s in steps) + repeat)
        print(f"mission in {client_file}")
    else:
        print("client: genom2bip's default environment (any service at most once per period of its task)")
    print(f"platform: {args.platform or 'a core per task'}; budget {_budget(args)}; partial-order reduction "
          f"{'on' if args.por else 'off'}", flush=True)
    exact = {}
    if args.exact_first and args.platform:
        path = exact_platform(args.platform, client_file.parent if client_file else Path(tempfile.mkdtemp()))
        print(f"\nfirst, every codel taking exactly its WCET ({path}), for {args.exact_first:g} s:", flush=True)
        exact = run(args, client_file, path, args.exact_first)
        print(f"\nthen the platform as given ({args.platform}):", flush=True)
    full = run(args, client_file, args.platform, args.time_limit)
    if exact:
        both(exact, full)
    return 0


if __name__ == "__main__":
    sys.exit(main())
