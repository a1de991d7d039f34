"""TChecker side by side: each model with ``tck-reach`` (``-a reach`` and ``-a covreach``) and with our zone engine.

    python bench/tchecker_bench.py TCK_REACH MODELS_DIR [--time-limit 300] [--grid 2] [--only fischer]

TCK_REACH is a built ``tck-reach`` (bench/build_tchecker.sh); MODELS_DIR holds TChecker files
(bench/tchecker_models.sh generates them with TChecker's own scripts, outside the repository).  Each model
is asked for the labels of its ``#labels=`` line (all at once, as TChecker's tests do) and, when it has
some, for its first label alone (a reachable query).  Our runs are ``python -m runtime reach`` in a process
of their own (time, peak memory); verdicts must agree, and where both searches finish the reachable
configurations without clocks (locations and integers, ``tck-reach -a reach -C graph``) are compared too.
States: tck-reach's STORED_STATES (the nodes of its final graph, covered ones removed), ours not covered at the
end (every one stored in brackets); times: the searches' own (tck-reach's RUNNING_TIME_SECONDS; ours without
Python's start, reading the file, building the zone model and setting the C search up), and our whole process
beside it; a run stopped at
the time limit is "unknown (time limit ...)" with how far it got; memory: each process's peak resident size
(ours includes Python and numpy, about 43 MiB).
Prints a table (markdown) and exits 1 when a verdict or a configuration set differs.
"""
from __future__ import annotations

import argparse
import os
import re
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Runs a command in a child of ``sh``: Linux keeps the largest resident size across exec, so a tool started
#: straight from this (larger) process would report ours as its own peak memory.
SMALL_PARENT = ["sh", "-c", '"$0" "$@"; exit $?']


@dataclass
class Run:
    verdict: str  # "reachable", "unreachable", "unknown", "error"
    states: int | None  # tck-reach: STORED_STATES, the nodes of its final graph; ours: not covered at the end
    transitions: int | None
    seconds: float | None
    rss_mib: float | None
    note: str = ""
    stored: int | None = None  # ours: every symbolic state stored, later covered ones included
    wall: float | None = None  # ours: the whole process (Python's start, reading the file, the search)


def limited(cmd: list[str], timeout: float | None = None, **kw) -> subprocess.CompletedProcess:
    """``cmd`` under :data:`SMALL_PARENT` in a session of its own: at ``timeout`` the whole group is killed (the
    tool is a grandchild, which killing ``sh`` alone would leave running)."""
    p = subprocess.Popen(SMALL_PARENT + cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         start_new_session=True, **kw)
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.communicate()
        raise
    return subprocess.CompletedProcess(cmd, p.returncode, out, err)


def tchecker(binary: str, algorithm: str, model: Path, labels: str, timeout: float) -> Run:
    cmd = [binary, "-a", algorithm] + (["-l", labels] if labels else []) + [str(model)]
    try:
        p = limited(cmd, timeout)
    except subprocess.TimeoutExpired:
        return Run("unknown", None, None, timeout, None, "time limit")
    got = dict(line.split(" ", 1) for line in p.stdout.splitlines() if " " in line)
    if p.returncode != 0 or "REACHABLE" not in got:
        return Run("error", None, None, None, None, (p.stderr or p.stdout).strip()[:200])
    return Run("reachable" if got["REACHABLE"].strip() == "true" else "unreachable",
               int(got.get("STORED_STATES", got.get("VISITED_STATES", "0"))), int(got["VISITED_TRANSITIONS"]),
               float(got["RUNNING_TIME_SECONDS"]), int(got["MEMORY_MAX_RSS"]) / 1024)


#: ``python -m runtime reach``'s exit statuses with an answer (runtime/exits.py): 0 unreachable, 4 reachable,
#: 5 stopped at a limit (its verdict line says which); any other is an error.
ANSWERED = (0, 4, 5)
ANSWERS = ("reachable", "unreachable")


def ours(model: Path, labels: str, grid: int, time_limit: int) -> Run:
    cmd = [sys.executable, "-m", "runtime", "reach", str(model), "--grid", str(grid), "--time-limit",
           str(time_limit), "--no-trace"] + (["--labels", labels] if labels else [])
    start = time.perf_counter()
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    p = limited(cmd, time_limit + 600, cwd=ROOT, env=env)  # it stops itself at time_limit; this is a safety net
    return read_ours(p.returncode, p.stdout, p.stderr, time.perf_counter() - start)


def read_ours(code: int, out: str, err: str, wall: float) -> Run:
    """Our run from its exit status and output: the verdict, and for one stopped at a limit, which limit and how
    far it got (states stored, transitions, time: lower bounds of what the whole search needs)."""
    verdict = re.search(r"^verdict: (\w+)(?: \(stopped at the (time|state) limit\))?", out, re.M)
    if code not in ANSWERED or verdict is None:
        lines = (err or out).strip().splitlines()
        return Run("error", None, None, wall, None, f"exit status {code}: {lines[0][:200] if lines else ''}")

    def number(pattern: str) -> float:
        return float(re.search(pattern, out, re.M).group(1).replace(",", ""))

    name = verdict.group(1)
    run = Run(name, int(number(r"^stored states: [\d,]+ \(([\d,]+) not covered")),
              int(number(r"^visited transitions: ([\d,]+)")), number(r"^time: ([\d.]+) s"),
              number(r"^memory: ([\d.]+) MiB"), f"{verdict.group(2) or 'a'} limit" if name == "unknown" else "")
    run.stored = int(number(r"^stored states: ([\d,]+)"))
    run.wall = wall
    return run


def best(run, repeat: int, under: float = 1.0) -> Run:
    """``run()``, and when it answered in under ``under`` seconds, the fastest of ``repeat`` runs (the same
    answer and states each time: the searches are deterministic)."""
    first = run()
    if repeat <= 1 or first.seconds is None or first.seconds >= under or first.verdict not in ANSWERS:
        return first
    runs = [first] + [run() for _ in range(repeat - 1)]
    return min((r for r in runs if r.verdict == first.verdict), key=lambda r: r.seconds)


def time_bound(mine: Run, theirs: Run) -> str:
    """'>' before the time ratio when our run stopped at the limit, '<' when theirs did (the ratio is a bound)."""
    if mine.verdict == "unknown":
        return ">"
    return "<" if theirs.verdict == "unknown" else ""


def verdict_cell(reach: Run, cov: Run, mine: Run) -> str:
    """The table's verdict: the one all answers agree on; ours stopped at a limit is "unknown (time limit ...)" with
    how far it got, and tck-reach's answer beside it; DISAGREE when two answers differ."""
    answers = {r.verdict for r in (reach, cov, mine) if r.verdict in ("reachable", "unreachable")}
    if len(answers) > 1:
        return "DISAGREE: " + "/".join(r.verdict for r in (reach, cov, mine))
    theirs = cov.verdict if cov.verdict in answers else reach.verdict
    if mine.verdict == "unknown":
        return (f"unknown ({mine.note}: {mine.stored:,} states stored, {mine.transitions:,} transitions in "
                f"{mine.seconds:.0f} s; tck-reach: {theirs})")
    if mine.verdict == "error":
        return f"error (ours: {mine.note}); tck-reach: {theirs}"
    return mine.verdict


def configurations_agree(binary: str, model: Path, grid: int, timeout: float) -> str:
    """'yes', 'NO: ...' or '' (not compared): the configurations without clocks both tools reach."""
    sys.path.insert(0, str(ROOT))
    from runtime.tchecker.reach import configurations
    from runtime.tchecker.syntax import read
    from runtime.tchecker.system import check

    try:
        p = limited([binary, "-a", "reach", "-C", "graph", str(model)], timeout)
    except subprocess.TimeoutExpired:
        return ""
    system = check(*read(model))
    theirs = set()
    for m in re.finditer(r'intval="([^"]*)".*?vloc="<([^>]*)>"', p.stdout):
        ints = tuple((k, int(v)) for k, v in (x.split("=") for x in m.group(1).split(",") if x))
        theirs.add((tuple(m.group(2).split(",")), tuple(sorted(ints))))
    mine = {(locs, tuple(sorted(ints))) for locs, ints in configurations(model, grid if system.strict else None)}
    if mine == theirs:
        return f"yes ({len(mine):,})"
    return f"NO: {len(theirs - mine)} only in tck-reach, {len(mine - theirs)} only here"


def ratio(a: float | None, b: float | None) -> str:
    if a is None or b is None or b == 0:
        return "—"
    return f"{a / b:,.1f}×"


def cell(v, fmt: str) -> str:
    return "—" if v is None else format(v, fmt)


def seconds_cell(v: float | None) -> str:
    """A time in seconds: to the millisecond, to the microsecond below one (as tck-reach prints it, five digits)."""
    return cell(v, ".3f" if v is None or v >= 0.001 else ".6f")


def seconds(r: Run) -> str:
    """tck-reach's time, or the limit it ran past."""
    return f">{r.seconds:.0f} (limit)" if r.verdict == "unknown" else seconds_cell(r.seconds)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("tck_reach", help="a built tck-reach (bench/build_tchecker.sh prints its path)")
    ap.add_argument("models", help="a directory of TChecker files (bench/tchecker_models.sh)")
    ap.add_argument("--time-limit", type=int, default=300, help="seconds per run of each tool (default 300)")
    ap.add_argument("--grid", type=int, default=2, help="our time grid for strict constraints (default 2)")
    ap.add_argument("--only", default="", help="only the models whose file name contains this")
    ap.add_argument("--repeat", type=int, default=1,
                    help="the fastest of this many runs of each tool where the first took under a second (on a "
                         "loaded machine, a small model's time is mostly noise); default 1")
    ap.add_argument("--compare-up-to", type=int, default=20_000,
                    help="compare configuration sets when tck-reach -a reach stored at most this many states")
    args = ap.parse_args(argv)
    files = sorted(Path(args.models).glob("*.tck"), key=lambda f: (re.sub(r"_\d+$", "", f.stem),
                                                                     int(re.sub(r"\D", "", f.stem) or 0)))
    files = [f for f in files if args.only in f.name]
    if not files:
        print(f"no .tck file in {args.models}", file=sys.stderr)
        return 2
    print("| model | labels | verdict | tck reach states | tck covreach states | ours states (all stored) "
          "| states ratio "
          "| tck reach s | tck covreach s | ours s | time ratio | ours process s "
          "| tck covreach MiB | ours MiB | configurations |")
    print("|" + "---|" * 15)
    bad = 0
    for f in files:
        line = f.read_text(encoding="utf-8").splitlines()
        found = [x[len("#labels="):] for x in line if x.startswith("#labels=")]
        every = found[0].replace(":", ",") if found else ""
        queries = [every] + ([every.split(",")[0]] if "," in every else [])
        for labels in queries:
            reach = best(lambda: tchecker(args.tck_reach, "reach", f, labels, args.time_limit), args.repeat)
            cov = best(lambda: tchecker(args.tck_reach, "covreach", f, labels, args.time_limit), args.repeat)
            mine = best(lambda: ours(f, labels, args.grid, args.time_limit), args.repeat)
            verdict = verdict_cell(reach, cov, mine)
            bad += verdict.startswith("DISAGREE")
            agree = ""
            if labels == every and mine.verdict != "unknown" and reach.states and reach.states <= args.compare_up_to:
                agree = configurations_agree(args.tck_reach, f, args.grid, args.time_limit)
                bad += agree.startswith("NO")
            more = "+" if mine.verdict == "unknown" else ""  # stopped: our figures are lower bounds
            print(f"| {f.stem} | {labels or '(none)'} | {verdict} | {cell(reach.states, ',')} "
                  f"| {cell(cov.states, ',')} | {cell(mine.states, ',')}{more} ({cell(mine.stored, ',')}) "
                  f"| {'>' if more else ''}{ratio(mine.states, cov.states)} | {seconds(reach)} "
                  f"| {seconds(cov)} "
                  f"| {seconds_cell(mine.seconds)}{more} | {time_bound(mine, cov)}{ratio(mine.seconds, cov.seconds)} "
                  f"| {cell(mine.wall, '.2f')} | {cell(cov.rss_mib, '.1f')} "
                  f"| {cell(mine.rss_mib, '.1f')} | {agree or '—'} |", flush=True)
            if mine.verdict == "error":
                print(f"  ours: {mine.note}", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
