"""How long each DALA codel runs over the shipped missions, and the WCET a margin makes of it.

    python bench/codel_times.py [--runs 3] [--margin 2] [--realtime] [--markdown] [--json FILE] [MISSION...]

Runs each mission (default: every descriptions/dala/missions/*.yaml) RUNS times, each in a process of its
own (``genom2bip mission MISSION --codel-times FILE``, so every run pays its own imports and first calls),
merges the figures (calls added; longest and mean exact; p99 the highest of the runs' p99) and prints one
line per codel: its calls, its CPU time (the codel thread's, ``time.thread_time``: longest, p99, mean), its
longest wall time, the WCET declared in descriptions/dala/*.gen (as gen/dala/interface.py has it) and the
WCET the margin gives: MARGIN x the longest CPU time, rounded up to a whole millisecond (1 ms at least).
A line is marked where the two differ.  Needs gen/dala (``genom2bip descriptions/dala -o gen``).
"""
from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from runtime.controller.codel_times import merge  # noqa: E402


def proposed(cpu_max_ms: float, margin: float) -> int:
    """The WCET to declare (ms): ``margin`` times the longest CPU time, rounded up to a whole ms, 1 ms at least."""
    return max(1, math.ceil(round(cpu_max_ms * margin, 6)))


def run_all(missions: list[Path], runs: int, realtime: bool, folder: Path) -> list[dict]:
    """Every mission ``runs`` times, each in its own process; the figures of each run."""
    out = []
    for mission in missions:
        for k in range(1, runs + 1):
            target = folder / f"{mission.stem}-{k}.json"
            command = [sys.executable, "-m", "genom2bip", "mission", str(mission), "--quiet", "--out", str(folder),
                       "--codel-times", str(target)] + (["--realtime"] if realtime else [])
            start = time.perf_counter()
            done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
            wall = time.perf_counter() - start
            met = "every expectation met" if done.returncode == 0 else f"exit {done.returncode}"
            if not target.is_file():
                sys.exit(f"{mission.stem}: no codel times written:\n{done.stderr[-2000:]}")
            print(f"{mission.stem} run {k}/{runs}: {wall:.1f} s, {met}; {late(folder / f'{mission.stem}.jsonl')}",
                  flush=True)
            out.append(json.loads(target.read_text()))
    return out


def late(trace: Path) -> str:
    """What the run's trace says was late: periods overrun, codels past their bound (the watchdog's, real time)."""
    events = [json.loads(line) for line in trace.read_text().splitlines()]
    overruns = [e for e in events if e["event"] == "overrun"]
    stuck = sorted({e["codel"] for e in events if e["event"] == "codel_overrun"})
    return (f"{len(overruns)} period overrun(s)" + (f" ({', '.join(sorted({e['task'] for e in overruns}))})"
                                                    if overruns else "")
            + f", {len(stuck)} codel(s) past their bound" + (f" ({', '.join(stuck)})" if stuck else ""))


def rows(data: dict, margin: float) -> list[tuple[str, ...]]:
    """One row per codel that ran: name, task, calls, CPU max/p99/mean, wall max, declared, proposed, mark."""
    out = []
    for name, c in data["codels"].items():
        declared = c.get("wcet")
        want = proposed(c["cpu"]["max"], margin)
        mark = "" if declared is not None and math.isclose(declared, want) else "differs"
        out.append((name, c.get("task") or "control", f"{c['calls']:,}", f"{c['cpu']['max']:.3f}",
                    f"{c['cpu']['p99']:.3f}", f"{c['cpu']['mean']:.3f}", f"{c['wall']['max']:.3f}",
                    f"{declared:g}" if declared is not None else "-", f"{want}", mark))
    return out


HEAD = ("codel", "task", "calls", "cpu max ms", "cpu p99 ms", "cpu mean ms", "wall max ms", "declared ms",
        "proposed ms", "")


def text_table(table: list[tuple[str, ...]]) -> str:
    lines = [HEAD] + table
    widths = [max(len(r[i]) for r in lines) for i in range(len(HEAD))]
    return "\n".join("  ".join(cell.ljust(w) if i < 2 else cell.rjust(w) for i, (cell, w) in
                               enumerate(zip(r, widths))).rstrip() for r in lines)


def markdown_table(table: list[tuple[str, ...]]) -> str:
    lines = ["| " + " | ".join(HEAD[:-1]) + " |", "|" + " --- |" * 2 + " ---: |" * (len(HEAD) - 3)]
    lines += ["| " + " | ".join((f"`{r[0]}`",) + r[1:-1]) + " |" for r in table]
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("missions", nargs="*", type=Path, help="mission files (default: descriptions/dala/missions/)")
    ap.add_argument("--runs", type=int, default=3, help="runs of each mission (default 3)")
    ap.add_argument("--margin", type=float, default=2.0, help="WCET = MARGIN x the longest CPU time (default 2)")
    ap.add_argument("--realtime", action="store_true", help="run the missions in real time (default: virtual clock)")
    ap.add_argument("--markdown", action="store_true", help="print the table in Markdown")
    ap.add_argument("--json", type=Path, metavar="FILE", help="also write the merged figures to FILE")
    args = ap.parse_args()
    missions = [m.resolve() for m in args.missions] or sorted((ROOT / "descriptions/dala/missions").glob("*.yaml"))
    with tempfile.TemporaryDirectory(prefix="codel-times-") as folder:
        data = merge(run_all(missions, args.runs, args.realtime, Path(folder)))
    if args.json:
        args.json.write_text(json.dumps(data, indent=1) + "\n")
    table = rows(data, args.margin)
    print(f"\n{len(missions)} missions x {args.runs} runs ({data['clock']} clock); CPU time of the codel's thread, "
          f"proposed WCET = {args.margin:g} x the longest CPU time, rounded up to a whole ms")
    print(markdown_table(table) if args.markdown else text_table(table))
    if data["not_run"]:
        print("not run by any mission: " + ", ".join(data["not_run"]))


if __name__ == "__main__":
    main()
