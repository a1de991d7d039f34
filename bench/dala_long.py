"""Whole DALA with its rules for minutes, ours and SPIN side by side, and an estimate of the full state space.

Used by ``python bench/verify_bench.py --dala-long S``.  Our compiled explorer
checks deadlock freedom and every property of descriptions/dala/properties
(partial-order reduction, the chosen store and threads), each bounded by S
seconds; SPIN's pan searches the deadlock check at the same time in its own
process (the full state space: the Promela hand-off has no reduction), is
interrupted after S seconds and prints its statistics.  Our progress goes to
the terminal; SPIN's, one line a report, to ``out/dala-long-spin.log``.

The estimate of the full state space (docs/verification/benchmark.md, "How large is
whole DALA") is the product of the five modules' own reachable state counts,
each found exactly by the compiled explorer in well under a second.
"""
from __future__ import annotations

import math
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODULES = ("Aspect", "LaserRF", "NDD", "POM", "RFLEX")


@dataclass
class LongRow:
    check: str
    tool: str
    verdict: str
    finished: bool
    states: int
    depth: int
    memory_mb: float
    seconds: float

    @property
    def rate(self) -> float:
        return self.states / self.seconds if self.seconds else 0.0


def spin_deadlock(package, root: str, seconds: float, memlim: int, log: Path, out: list) -> None:
    """pan on the deadlock check for ``seconds`` (then SIGINT: it prints its statistics), progress into ``log``."""
    from runtime.explore import Progress, StateSpace
    from runtime.export.spin import DEPTH, SpinRun, parse_pan
    from runtime.export.spin import _PAN_PROGRESS as LINE

    run = SpinRun(StateSpace(package, root))
    try:
        run.build(extra=(f"-DMEMLIM={memlim}",))
        log.parent.mkdir(parents=True, exist_ok=True)
        with log.open("w", encoding="utf-8") as stream:
            progress = Progress(stream, force=True, delay=0)
            start = time.perf_counter()
            proc = subprocess.Popen(["./pan", f"-m{DEPTH}", "-w26", "-E", "-n"], cwd=run.dir, stdout=subprocess.PIPE,
                                    stderr=subprocess.STDOUT, text=True)
            timer = threading.Timer(seconds, proc.send_signal, (signal.SIGINT,))
            timer.start()
            lines = []
            for line in proc.stdout:
                lines.append(line)
                m = LINE.match(line)
                if m:
                    depth, states, transitions, memory = (float(m.group(k)) for k in range(1, 5))
                    progress.tick(int(states), int(transitions), 0, lambda: memory * 2**20, depth=int(depth))
            proc.wait()
            timer.cancel()
            elapsed = time.perf_counter() - start
        report = parse_pan("".join(lines))
        finished = elapsed < seconds and report.complete
        verdict = ("deadlock found" if report.errors else "no deadlock") if finished else "open (time)"
        out.append(LongRow("deadlock", f"SPIN -DMEMLIM={memlim}", verdict, finished, report.states,
                           report.depth if report.depth < DEPTH else 0, report.memory_mb, elapsed))
    finally:
        run.cleanup()


def ours(package, root: str, seconds: float, checks: list[str] | None, store: str, workers: int) -> list[LongRow]:
    """Deadlock freedom and each property by the compiled search with POR, ``seconds`` at most each."""
    from runtime.engine import flatten
    from runtime.explore import Progress, StateSpace
    from runtime.native.properties import compiled_check
    from runtime.props import read_property_file

    items, _ = read_property_file(ROOT / "descriptions" / "dala" / "properties" / "NDD.mcl", flatten(package, root))
    observed = set().union(*(i.observed for i in items))
    tool = f"compiled+POR, {store} store, {workers} thread{'s' if workers > 1 else ''}"
    rows = []
    for item in items:
        if checks and item.name not in checks:
            continue
        space = StateSpace(package, root, observed=observed)
        print(f"DALA {item.name}:", file=sys.stderr)
        start = time.perf_counter()
        v = compiled_check(space, item, progress=Progress(force=True), max_bytes=6 << 30, por=True, store=store,
                           workers=workers, max_seconds=seconds)
        if v is None:
            rows.append(LongRow(item.name, tool, "not compiled (the Python checker's)", False, 0, 0, 0.0, 0.0))
            continue
        r = v.result
        word = {True: "holds", False: f"violated ({len(v.trace)} steps)", None: f"open ({r.stopped_by})"}[v.holds]
        rows.append(LongRow(item.name, tool, word, v.holds is not None, r.states, r.depth, r.memory / 2**20,
                            time.perf_counter() - start))
        print(f"  {word}, {r.states:,} states", file=sys.stderr)
    return rows


def module_counts() -> dict[str, int]:
    """Each DALA module's own reachable states, by the compiled explorer (exact store, complete)."""
    from verify_bench import dala_model
    from runtime.explore import StateSpace
    from runtime.native.compiled import compile_space

    out = {}
    for m in MODULES:
        package, root = dala_model([m])
        cs, why = compile_space(StateSpace(package, root), search=True)
        if cs is None:
            raise RuntimeError(why)
        r = cs.explore(max_seconds=120)
        if not r.complete:
            raise RuntimeError(f"{m} alone did not finish in 120 s")
        out[m] = r.states
    return out


def pair_check() -> str:
    """Two modules with no connector between them: their state space is exactly the product of theirs."""
    from verify_bench import dala_model
    from runtime.explore import StateSpace
    from runtime.native.compiled import compile_space

    package, root = dala_model(["POM", "Aspect"])
    cs, _ = compile_space(StateSpace(package, root), search=True)
    return f"{cs.explore(max_seconds=60).states:,}"


def full_search(package, root, seconds: float) -> LongRow:
    """Our compiled search without reduction on the deadlock check, for its rate and bytes per state."""
    from runtime.explore import StateSpace
    from runtime.native.compiled import compile_space

    cs, _ = compile_space(StateSpace(package, root), search=True)
    r = cs.explore(max_seconds=seconds, store="compact", max_bytes=6 << 30)
    return LongRow("deadlock", "compiled, no POR, compact store", "open (time)", r.complete, r.states, r.depth,
                   r.memory / 2**20, r.seconds)


def estimate_lines(counts: dict[str, int], rows: list[LongRow], pair: str) -> list[str]:
    product = math.prod(counts.values())
    lines = ["Full size of whole DALA with its rules (docs/verification/benchmark.md, \"How large is whole DALA\"):",
             "  modules alone: " + ", ".join(f"{m} {n:,}" for m, n in counts.items()),
             f"  POM and Aspect side by side, no connector: {pair} states "
             f"(product {counts['POM'] * counts['Aspect']:,})",
             f"  product of the five: {product:.3g} states (the rules only guard interactions: an estimate from "
             "above)"]
    for r in rows:
        if r.states and r.seconds and not r.finished and "+POR" not in r.tool:
            years = product / r.rate / (3600 * 24 * 365) if r.rate else float("inf")
            per = r.memory_mb * 2**20 / r.states
            lines.append(f"  at {r.tool}'s {r.rate:,.0f} states/s and {per:,.0f} B/state ({r.check}): "
                         f"{years:.3g} years, {product * per / 2**40:.3g} TB")
    return lines


def dala_long(seconds: float, checks: list[str] | None = None, store: str = "compact", workers: int = 1,
              memlim: int = 8000) -> str:
    """The side-by-side table and the estimate, as text."""
    from verify_bench import dala_model

    package, root = dala_model()
    log = ROOT / "out" / "dala-long-spin.log"
    got: list[LongRow] = []
    spin = threading.Thread(target=spin_deadlock, args=(package, root, seconds, memlim, log, got))
    spin.start()
    rows = ours(package, root, seconds, checks, store, workers)
    spin.join()
    rows += got
    full = full_search(package, root, 20)
    lines = [f"Whole DALA with its rules, {seconds:.0f} s per check at most (SPIN at the same time; its progress "
             f"in {log.relative_to(ROOT)}):", "",
             "| check | tool | verdict | finished | states | depth | memory MB | seconds | states/s | B/state |",
             "| --- | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for x in rows:
        per = x.memory_mb * 2**20 / x.states if x.states else 0.0
        lines.append(f"| {x.check} | {x.tool} | {x.verdict} | {'yes' if x.finished else 'no'} | {x.states:,} | "
                     f"{x.depth:,} | {x.memory_mb:,.0f} | {x.seconds:,.0f} | {x.rate:,.0f} | {per:,.0f} |")
    lines += ["", f"Our full search (no POR) for 20 s: {full.states:,} states, depth {full.depth}, {full.rate:,.0f} "
                  f"states/s, {full.memory_mb * 2**20 / full.states:,.0f} B/state"]
    return "\n".join(lines + [""] + estimate_lines(module_counts(), rows + [full], pair_check()))
