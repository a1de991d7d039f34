"""Exploration throughput and memory: our explorer in Python, compiled to C, and SPIN side by side on the same models.

Run ``python bench/verify_bench.py [--seconds S] [--max-states N] [--only NAME]``.
Models: dining philosophers N = 10..12 (left fork, then right: one deadlock),
the NDD module, and the whole DALA functional level (rules included), whose
state space no exhaustive search finishes: the tools then run for a budget
(the Python explorer stops at ``--max-states``; the compiled explorer and
SPIN are stopped after ``--seconds``, SPIN's memory is capped at 4 GB with
``-DMEMLIM=4000``) and the rates are compared.  Both tools see the same model:
the Promela translation has our layout and dead-variable reduction, and the
exhaustive runs find the same number of states (checked here).

The compiled explorer runs on one thread and on two (``--workers 2``:
breadth-first levels shared by two threads over one lock-free visited
set); the speed-up of two threads over one is a column of the first table.

A second table gives the compiled explorer with its partial-order reduction
(``verify --por``) on the deadlock check, beside the full compiled search and
SPIN (which the SPIN hand-off builds with -DNOREDUCE: no reduction).

Rates are end to end over the search (ours: numbering, successors, packing;
SPIN: pan's process including its hash-table set-up), repeated until a run
has lasted a second so that small models are timed fairly; building the
engine, compiling the C step or compiling pan is not counted.  Bytes per
state: the Python explorer's is the visited set (dict of packed ints,
numbering, parents) divided by the states; the compiled explorer's is all it
allocates (packed states, parents, the interactions that reached them, the
hash table) divided by the states; SPIN's is pan's "equivalent memory usage
for states" (stored x (state vector + overhead)) divided by the states it
stored, without its hash table and search stack.

``--dala-long S`` adds the run on the whole DALA with its rules
(bench/dala_long.py): deadlock freedom and every property of
descriptions/dala/properties by our compiled explorer with POR, each bounded
by S seconds, and SPIN on the deadlock check for S seconds at the same time
(``--spin-memlim``, 8000 MB by default): states, depth, memory, states/s
and whether each finished, then the estimate of the full state space.
"""
from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from runtime.bip2 import parse_text  # noqa: E402
from runtime.explore import StateSpace, explore  # noqa: E402
from runtime.export.spin import DEPTH, SpinRun, parse_pan  # noqa: E402


def dining(n: int) -> str:
    """N philosophers who take the left fork, then the right one."""
    comps = "\n".join(f"    component Phil p{i}()\n    component Fork f{i}()" for i in range(n))
    conns = "\n".join(
        f'    @label(name="left{i}")\n    connector Take left{i}(p{i}.takeL, f{i}.take)\n'
        f'    @label(name="right{i}")\n    connector Take right{i}(p{i}.takeR, f{(i + 1) % n}.take)\n'
        f'    @label(name="release{i}")\n    connector Release release{i}(p{i}.release, f{i}.put, f{(i + 1) % n}.put)'
        for i in range(n))
    return f"""package Dining{n}
  port type Port()
  atom type Fork()
    export port Port take(), put()
    place FREE, BUSY
    initial to FREE
    on take from FREE to BUSY
    on put from BUSY to FREE
  end
  atom type Phil()
    export port Port takeL(), takeR(), release()
    place THINK, ONE, EAT
    initial to THINK
    on takeL from THINK to ONE
    on takeR from ONE to EAT
    on release from EAT to THINK
  end
  connector type Take(Port p, Port f)
    define p f
  end
  connector type Release(Port p, Port l, Port r)
    define p l r
  end
  compound type Table()
{comps}
{conns}
  end
end
"""


def dala_model(modules: list[str] | None = None):
    from genom2bip.generate import model_of
    from genom2bip.parser import parse_paths
    from genom2bip.rules import all_rules
    from runtime.diagnostics import Reporter

    base = ROOT / "descriptions" / "dala"
    files = [str(base / f"{m}.gen") for m in modules] if modules else sorted(str(p) for p in base.glob("*.gen"))
    description = parse_paths(files)
    rules = None
    if not modules:
        reporter = Reporter()
        rules = all_rules(description, base / "rules.yaml", reporter)
        reporter.raise_if_errors()
    package, root, _ = model_of(description, "dala" if not modules else modules[0], rules)
    return package, root


@dataclass
class Row:
    model: str
    ours_states: int
    ours_rate: float
    ours_bytes: float
    ours_complete: bool
    c_states: int
    c_rate: float
    c_bytes: float
    c_complete: bool
    spin_states: int
    spin_rate: float
    spin_bytes: float
    spin_complete: bool
    por_states: int = 0
    por_rate: float = 0.0
    por_bytes: float = 0.0
    por_complete: bool = False
    c2_rate: float = 0.0  # the compiled explorer on two threads


#: A measurement is repeated until its runs add up to this many seconds.
MIN_SECONDS = 1.0


def run_ours(package, root: str, max_states: int | None) -> tuple[int, float, float, bool]:
    runs, total = 0, 0.0
    while total < MIN_SECONDS:
        space = StateSpace(package, root, max_states=max_states)
        result = explore(space)
        runs += 1
        total += result.seconds
    return result.states, result.states * runs / total, result.bytes_per_state, result.complete


def run_compiled(package, root: str, seconds: float, por: bool = False,
                 workers: int = 1) -> tuple[int, float, float, bool]:
    """The compiled explorer (library built and cached before timing), capped at ``seconds`` and 4 GB.

    ``por``: with partial-order reduction (states are then the reduced graph's); ``workers``: threads.
    """
    from runtime.native.compiled import compile_space

    cs, note = compile_space(StateSpace(package, root), search=True)
    if cs is None:
        print(f"compiled explorer: {note}", file=sys.stderr)
        return 0, 0.0, 0.0, False
    if workers > 1:
        cs.build(parallel=True)  # compiled before timing
    runs, total = 0, 0.0
    while total < MIN_SECONDS:
        result = cs.explore(max_seconds=seconds, max_bytes=4 << 30, por=por, workers=workers)
        runs += 1
        total += result.seconds
    return result.states, result.states * runs / total, result.bytes_per_state, result.complete


def run_spin(package, root: str, seconds: float, states_hint: int, report_out: list | None = None
             ) -> tuple[int, float, float, bool]:
    """SPIN's pan on the Promela translation (-DMEMLIM=4000), stopped after ``seconds``; ``report_out`` gets
    the last PanReport."""
    run = SpinRun(StateSpace(package, root))
    bits = max(16, min(27, (2 * states_hint).bit_length()))
    try:
        run.build(extra=("-DMEMLIM=4000",))
        runs, total = 0, 0.0
        while total < MIN_SECONDS:
            start = time.perf_counter()
            proc = subprocess.Popen(["./pan", f"-m{DEPTH}", f"-w{bits}", "-E", "-n"], cwd=run.dir,
                                    stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            try:
                out, _ = proc.communicate(timeout=seconds)
                complete = True
            except subprocess.TimeoutExpired:
                proc.send_signal(signal.SIGINT)  # pan prints its statistics when interrupted
                out, _ = proc.communicate()
                complete = False
            total += time.perf_counter() - start
            runs += 1
            report = parse_pan(out)
        if report_out is not None:
            report_out.append(report)
        equivalent = _equivalent_mb(report.output)
        per_state = equivalent * 1024 * 1024 / report.states if report.states else 0.0
        return report.states, report.states * runs / total, per_state, complete and report.complete
    finally:
        run.cleanup()


def _equivalent_mb(output: str) -> float:
    import re
    m = re.search(r"([0-9.]+)\s+equivalent memory usage for states", output)
    return float(m.group(1)) if m else 0.0


def _reduction(r: Row) -> str:
    """Full states over reduced ones; a lower bound when the full search did not finish."""
    if not r.por_states or not r.por_complete:
        return "n/a"
    return f"{r.c_states / r.por_states:,.1f}x" if r.c_complete else f">= {r.c_states / r.por_states:,.0f}x"


def table(rows: list[Row]) -> str:
    head = ("| model | states (Python / compiled / SPIN) | Python states/s | compiled states/s | "
            "compiled 2 threads states/s | 2 threads / 1 | SPIN states/s | "
            "compiled/SPIN speed | B/state Python / compiled / SPIN | compiled/SPIN B/state |")
    lines = [head, "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- | ---: |"]
    for r in rows:
        mark = "" if r.ours_complete and r.c_complete and r.spin_complete and r.por_complete else " (budget)"
        speed = r.c_rate / r.spin_rate if r.spin_rate else float("nan")
        mem = r.c_bytes / r.spin_bytes if r.spin_bytes else float("nan")
        scale = r.c2_rate / r.c_rate if r.c_rate else float("nan")
        lines.append(f"| {r.model}{mark} | {r.ours_states:,} / {r.c_states:,} / {r.spin_states:,} | "
                     f"{r.ours_rate:,.0f} | {r.c_rate:,.0f} | {r.c2_rate:,.0f} | {scale:.2f}x | "
                     f"{r.spin_rate:,.0f} | {speed:,.2f}x | "
                     f"{r.ours_bytes:,.0f} / {r.c_bytes:,.0f} / {r.spin_bytes:,.0f} | {mem:.2f}x |")
    lines += ["", ("| model | states compiled / compiled+POR / SPIN (-DNOREDUCE) | compiled+POR states/s | "
                   "reduction | B/state compiled+POR |"), "| --- | --- | ---: | ---: | ---: |"]
    for r in rows:
        mark = "" if r.c_complete and r.por_complete else " (budget)"
        lines.append(f"| {r.model}{mark} | {r.c_states:,} / {r.por_states:,} / {r.spin_states:,} | {r.por_rate:,.0f} | "
                     f"{_reduction(r)} | {r.por_bytes:,.0f} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=20.0, help="SPIN's time budget on models too large to finish")
    ap.add_argument("--max-states", type=int, default=150_000, help="our state budget on models too large to finish")
    ap.add_argument("--only", help="run only the models whose name contains this")
    ap.add_argument("--dala-long", type=float, metavar="S",
                    help="also the whole DALA: deadlock and properties with POR, and SPIN, S seconds each "
                         "(bench/dala_long.py), with the estimate of the full state space")
    ap.add_argument("--dala-checks", help="--dala-long: only these checks (comma-separated property names)")
    ap.add_argument("--dala-store", default="compact", help="--dala-long: our visited set (default compact)")
    ap.add_argument("--dala-workers", type=int, default=1, help="--dala-long: our threads (default 1)")
    ap.add_argument("--spin-memlim", type=int, default=8000, help="--dala-long: SPIN's -DMEMLIM in MB (default 8000)")
    ap.add_argument("--skip-table", action="store_true", help="only the --dala-long run")
    args = ap.parse_args(argv)
    models = [(f"dining N={n}", lambda n=n: (parse_text(dining(n), f"Dining{n}.bip"), "Table()"), None)
              for n in range(10, 13)]
    models.append(("NDD module", lambda: dala_model(["NDD"]), None))
    models.append(("DALA (5 modules, rules)", dala_model, args.max_states))
    rows = []
    for name, build, budget in models:
        if args.skip_table or (args.only and args.only not in name):
            continue
        package, root = build()
        ours = run_ours(package, root, budget)
        compiled = run_compiled(package, root, args.seconds)
        theirs = run_spin(package, root, args.seconds, max(ours[0], compiled[0]))
        for who, got in (("compiled", compiled), ("SPIN", theirs)):
            if ours[3] and got[3] and ours[0] != got[0]:
                print(f"warning: {name}: Python {ours[0]} states, {who} {got[0]}", file=sys.stderr)
        reduced = run_compiled(package, root, args.seconds, por=True)
        two = run_compiled(package, root, args.seconds, workers=2)
        rows.append(Row(name, *ours, *compiled, *theirs, *reduced, c2_rate=two[1]))
        print(f"{name}: done", file=sys.stderr)
    from runtime.native.build import FLAGS, PARALLEL_FLAGS, compiler

    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the end, "
          f"Python {sys.version.split()[0]}; compiled explorer 1 and 2 threads, "
          f"{compiler()} {' '.join(FLAGS)} (2 threads: {' '.join(PARALLEL_FLAGS)}); SPIN single core, gcc -O2 "
          "-DMEMLIM=4000")
    if rows:
        print(table(rows))
    if args.dala_long:
        from dala_long import dala_long

        checks = args.dala_checks.split(",") if args.dala_checks else None
        print()
        print(dala_long(args.dala_long, checks, args.dala_store, args.dala_workers, args.spin_memlim))
        print(f"load average at the end: {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
