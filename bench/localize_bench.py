"""Localization on the whole DALA level: per property and per timing observer, rounds, atoms kept, states, seconds.

Untimed: the properties of descriptions/dala/properties/NDD.mcl and
rules.mcl on DALA with its rules (65 atoms).  Timed: the period observer of
each task and the latency observer of descriptions/dala/observers.yaml
(71 atoms).  Seconds include compiling each abstraction's C step unless the
cache already holds it (run twice to see both).  With --exhaustive S, the
exhaustive compiled search of the latency observer on LaserRF and RFLEX
alone runs beside it, stopped after S seconds.

    python bench/localize_bench.py [--default-wcet MS] [--max-states N] [--exhaustive S] [--only untimed|timed]
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

DALA = ROOT / "descriptions" / "dala"


def dala(timed: bool, wcet_us: int):
    """(package, root) of whole DALA with its rules, timed with its latency observer when asked."""
    from genom2bip.build.timed import TimeOptions
    from genom2bip.generate import model_of
    from genom2bip.observers import load_observers
    from genom2bip.parser import parse_paths
    from genom2bip.rules import all_rules
    from runtime.diagnostics import Reporter

    description = parse_paths(sorted(str(p) for p in DALA.glob("*.gen")))
    reporter = Reporter()
    rules = all_rules(description, DALA / "rules.yaml", reporter)
    options = None
    if timed:
        options = TimeOptions(None, wcet_us, load_observers(DALA / "observers.yaml", description, reporter),
                              ticks=True)
    assert not reporter.has_errors, reporter.diagnostics
    package, root, _ = model_of(description, "dala", rules, options)
    return package, root


def row(name: str, package, root: str, item, max_states: int) -> None:
    from runtime.localize.refine import check_localized

    started = time.perf_counter()
    result = check_localized(package, root, item, max_states=max_states)
    v, rounds = result.verdict, result.rounds
    print(f"{name:34} {v.word:12} {len(rounds):6} {rounds[-1].kept:4}/{rounds[-1].atoms:<3} {v.states:12,} "
          f"{time.perf_counter() - started:8.2f}", flush=True)


def untimed(max_states: int) -> None:
    from runtime.engine import flatten
    from runtime.props import read_property_file

    package, root = dala(False, 0)
    flat = flatten(package, root)
    print("whole DALA with its rules (untimed)")
    print(f"{'property':34} {'verdict':12} {'rounds':>6} {'K':>8} {'states':>12} {'s':>8}")
    for path in (DALA / "properties" / "NDD.mcl", DALA / "properties" / "rules.mcl"):
        items, _ = read_property_file(path, flat)
        for item in items:
            if item.property.pattern != "deadlock free":
                row(item.name, package, root, item, max_states)


def timed(wcet_ms: float, max_states: int) -> None:
    from genom2bip.verify.timing import observer_atoms
    from runtime.engine import flatten
    from runtime.props import read_property_text

    package, root = dala(True, int(wcet_ms * 1000))
    flat = flatten(package, root)
    print(f"\nwhole timed DALA, default WCET {wcet_ms:g} ms")
    print(f"{'observer':34} {'verdict':12} {'rounds':>6} {'K':>8} {'states':>12} {'s':>8}")
    for obs in observer_atoms(package, root):
        row(obs.path, package, root, read_property_text(f"invariant not ({obs.path} @ ERROR)", flat), max_states)


def exhaustive(seconds: float, wcet_ms: float) -> None:
    """The latency observer by the exhaustive compiled search on LaserRF and RFLEX alone, for comparison."""
    argv = [sys.executable, "-m", "genom2bip", "verify", str(DALA / "LaserRF.gen"), str(DALA / "RFLEX.gen"),
            "--timed", "--observers", str(DALA / "observers.yaml"), "--default-wcet", f"{wcet_ms:g}ms", "--quiet"]
    started = time.perf_counter()
    try:
        out = subprocess.run(argv, capture_output=True, text=True, timeout=seconds, cwd=ROOT).stdout
        line = next((x for x in out.splitlines() if x.startswith("latency")), out.strip().splitlines()[-1])
    except subprocess.TimeoutExpired:
        line = f"did not finish in {seconds:g} s"
    print(f"\nexhaustive, LaserRF + RFLEX alone: {line} [{time.perf_counter() - started:.1f} s wall clock]")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--default-wcet", type=float, default=0.0, metavar="MS")
    parser.add_argument("--max-states", type=int, default=5_000_000, metavar="N", help="per round")
    parser.add_argument("--exhaustive", type=float, default=0.0, metavar="S")
    parser.add_argument("--only", choices=("untimed", "timed"))
    args = parser.parse_args()
    if args.only != "timed":
        untimed(args.max_states)
    if args.only != "untimed":
        timed(args.default_wcet, args.max_states)
    if args.exhaustive:
        exhaustive(args.exhaustive, args.default_wcet)


if __name__ == "__main__":
    main()
