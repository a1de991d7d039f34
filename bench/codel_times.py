"""How long each DALA codel runs over the shipped missions, and the WCET a margin makes of it.

    python bench/codel_times.py [--runs 3] [--margin 2] [--realtime] [--markdown] [--json FILE]
                                [--from FILE]... [--write [--lower]] [MISSION...]

Runs each mission (default: every descriptions/dala/missions/*.yaml) RUNS times, each in a process of its
own (``genom2bip mission MISSION --codel-times FILE``, so every run pays its own imports and first calls),
merges the figures (calls added; longest and mean exact; p99 the highest of the runs' p99) and prints one
line per codel: its calls, its CPU time (the codel thread's, ``time.thread_time``: longest, p99, mean), its
longest wall time, the WCET declared in descriptions/dala/*.gen and the WCET the margin gives: MARGIN x
the longest CPU time, rounded up to a whole millisecond (1 ms at least).  A line is marked where the two
differ.  Needs gen/dala (``genom2bip descriptions/dala -o gen``).

``--write`` declares the proposed WCETs in descriptions/dala/*.gen (genom2bip.declare_wcets: only the
``wcet`` of each codel that ran changes, and the margin in the files' ``WCETs:`` comment), then regenerates
gen/ with ``genom2bip descriptions/dala -o gen``: after the codels change, one command measures them again
and declares what it measured.  A declared WCET higher than the proposed one stays (a quieter run does not
undo a longer call seen before) unless ``--lower`` is given.  ``--from FILE`` (repeatable: merged) takes the
figures of earlier ``--json FILE`` runs instead of running the missions.
"""
from __future__ import annotations

import argparse
import json
import math
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from genom2bip.declare_wcets import codels, set_wcets  # noqa: E402
from genom2bip.loading import read_description  # noqa: E402
from genom2bip.output import write_file  # noqa: E402
from runtime.controller.codel_times import merge  # noqa: E402

DESCRIPTIONS = ROOT / "descriptions" / "dala"
#: The comment of each .gen file that states the margin its WCETs were declared with.
NOTE = re.compile(r"(WCETs: )[0-9.]+( x the longest CPU time)")


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


def declared_now() -> dict[str, float | None]:
    """The WCET (ms) each codel declares in descriptions/dala/*.gen today, None where it declares none."""
    places = codels(read_description([DESCRIPTIONS]))
    return {name: p.seconds * 1e3 if p.seconds is not None else None for name, p in places.items()}


def to_declare(data: dict, margin: float, declared: dict[str, float | None], lower: bool) -> dict[str, float]:
    """The WCET (ms) to declare for each codel that ran: the proposed one, unless it is lower and not ``lower``.

    A WCET bounds every call ever seen: a quieter measurement does not undo a longer call seen before, so a
    declared WCET comes down only when asked (after the codel itself changed, say).
    """
    out = {}
    for name, c in data["codels"].items():
        want, have = proposed(c["cpu"]["max"], margin), declared.get(name)
        out[name] = float(want) if have is None or want > have or lower else have
    return out


def rows(data: dict, margin: float, declared: dict[str, float | None], lower: bool) -> list[tuple[str, ...]]:
    """One row per codel that ran: name, task, calls, CPU max/p99/mean, wall max, declared, proposed, mark."""
    out = []
    for name, c in data["codels"].items():
        have, want = declared.get(name), proposed(c["cpu"]["max"], margin)
        mark = ("new" if have is None else "" if math.isclose(have, want) else "raise" if want > have
                else "lower" if lower else "lower? (kept: --lower)")
        out.append((name, c.get("task") or "control", f"{c['calls']:,}", f"{c['cpu']['max']:.3f}",
                    f"{c['cpu']['p99']:.3f}", f"{c['cpu']['mean']:.3f}", f"{c['wall']['max']:.3f}",
                    f"{have:g}" if have is not None else "-", f"{want}", mark))
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


def positive(kind):
    """An argparse type: a number of ``kind`` above 0 (the message names the value given)."""
    def read(text: str):
        try:
            value = kind(text)
        except ValueError:
            value = None
        if value is None or not 0 < value < math.inf:
            raise argparse.ArgumentTypeError(f"expected a{'n integer' if kind is int else ' number'} above 0, "
                                             f"got {text!r}")
        return value
    return read


def arguments() -> argparse.Namespace:
    """The command line, every file named checked before a mission runs."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("missions", nargs="*", type=Path, help="mission files (default: descriptions/dala/missions/)")
    ap.add_argument("--runs", type=positive(int), default=3, help="runs of each mission (default 3)")
    ap.add_argument("--margin", type=positive(float), default=2.0,
                    help="WCET = MARGIN x the longest CPU time, rounded up to a whole ms (default 2)")
    ap.add_argument("--realtime", action="store_true", help="run the missions in real time (default: virtual clock)")
    ap.add_argument("--markdown", action="store_true", help="print the table in Markdown")
    ap.add_argument("--json", type=Path, metavar="FILE", help="also write the merged figures to FILE")
    ap.add_argument("--from", dest="sources", type=Path, metavar="FILE", action="append", default=[],
                    help="the figures of an earlier --json FILE instead of running the missions (repeat it: "
                         "the figures are merged)")
    ap.add_argument("--write", action="store_true",
                    help="declare the proposed WCETs in descriptions/dala/*.gen (a higher one declared stays) "
                         "and regenerate gen/")
    ap.add_argument("--lower", action="store_true", help="with --write: declare a proposed WCET lower than "
                                                         "the one declared too (after the codel changed)")
    args = ap.parse_args()
    for mission in args.missions:
        if not mission.is_file():
            ap.error(f"{mission}: no such mission file")
    for source in args.sources:
        if not source.is_file():
            ap.error(f"--from {source}: no such file")
    if args.sources and args.missions:
        ap.error("--from: the figures are read, not measured: name no mission")
    if args.lower and not args.write:
        ap.error("--lower goes with --write")
    if not args.sources and not (ROOT / "gen/dala/__init__.py").is_file():
        ap.error("gen/dala is missing: run `genom2bip descriptions/dala -o gen` first")
    return args


def declare(data: dict, margin: float, wanted: dict[str, float]) -> None:
    """Write ``wanted`` into descriptions/dala/*.gen, state the margin there, regenerate gen/."""
    changed = set(set_wcets([DESCRIPTIONS], wanted))
    for gen in sorted(DESCRIPTIONS.glob("*.gen")):
        text = gen.read_text(encoding="utf-8")
        noted = NOTE.sub(lambda m: f"{m.group(1)}{margin:g}{m.group(2)}", text)
        if noted != text:
            write_file(gen, lambda f, noted=noted: f.write(noted))
            changed.add(gen)
    names = ", ".join(str(p.relative_to(ROOT)) for p in sorted(changed)) or "none (they declared these already)"
    print(f"\ndeclared the WCETs of {len(wanted)} codels; files changed: {names}")
    if data["not_run"]:
        print("left as declared (no mission ran them): " + ", ".join(data["not_run"]))
    done = subprocess.run([sys.executable, "-m", "genom2bip", "descriptions/dala", "-o", "gen"], cwd=ROOT,
                          capture_output=True, text=True)
    print(f"genom2bip descriptions/dala -o gen: {(done.stdout + done.stderr).strip().splitlines()[-1:]}")
    if done.returncode != 0:
        sys.exit(f"regenerating gen/ failed (exit {done.returncode}):\n{done.stderr}")


def main() -> None:
    args = arguments()
    missions = [m.resolve() for m in args.missions] or sorted((DESCRIPTIONS / "missions").glob("*.yaml"))
    if args.sources:
        data = merge([json.loads(source.read_text()) for source in args.sources])
        heading = f"figures of {', '.join(map(str, args.sources))} ({data['runs']} runs, {data['clock']} clock)"
    else:
        with tempfile.TemporaryDirectory(prefix="codel-times-") as folder:
            data = merge(run_all(missions, args.runs, args.realtime, Path(folder)))
        heading = f"{len(missions)} missions x {args.runs} runs ({data['clock']} clock)"
    if args.json:
        args.json.write_text(json.dumps(data, indent=1) + "\n")
    declared = declared_now()
    table = rows(data, args.margin, declared, args.lower)
    print(f"\n{heading}; CPU time of the codel's thread, proposed WCET = {args.margin:g} x the longest CPU time, "
          "rounded up to a whole ms")
    print(markdown_table(table) if args.markdown else text_table(table))
    if data["not_run"]:
        print("not run by any mission: " + ", ".join(data["not_run"]))
    if args.write:
        declare(data, args.margin, to_declare(data, args.margin, declared, args.lower))
    elif any(r[-1] for r in table):
        print("to declare the proposed WCETs: the same command with --write (and --lower to lower one)")


if __name__ == "__main__":
    main()
