"""Deadlock freedom three ways, side by side: the compositional analysis, our explorer, SPIN.

Models: dining philosophers N = 10, 20, 50, 100 (everyone takes the left
fork first: a deadlock) and with a fixed fork order (the last one takes
fork 0 first: deadlock-free), the NDD module, each DALA module, the whole
DALA functional level with its rules, and the Arm component
(descriptions/arm).  Each measurement runs in a child process so that its
peak memory (ru_maxrss, SPIN's verifier included) is its own.  The
explorer and SPIN get a time cap each (default 120 s; SPIN also
-DMEMLIM=4000, 4 GB); a run stopped by a cap prints "did not finish" and
what it reached.  Times exclude building the BIP model from descriptions
(common to all three); SPIN's time includes the translation and gcc.

    python bench/compositional_bench.py [--seconds 120] [--only NAME]
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from verify_bench import dala_model, dining  # noqa: E402

MODULES = ["LaserRF", "Aspect", "RFLEX", "NDD", "POM"]


def ordered(n: int) -> str:
    """Dining with a fixed fork order: the last philosopher takes fork 0 first."""
    text = dining(n)
    last = n - 1
    text = text.replace(f"connector Take left{last}(p{last}.takeL, f{last}.take)",
                        f"connector Take left{last}(p{last}.takeL, f0.take)")
    return text.replace(f"connector Take right{last}(p{last}.takeR, f0.take)",
                        f"connector Take right{last}(p{last}.takeR, f{last}.take)")


def model(name: str):
    """(package, root) of a model named as the table names it."""
    from runtime.bip2 import parse_text
    kind, _, arg = name.partition(" ")
    if kind == "dining":
        n = int(arg.split("=")[1])
        return parse_text(dining(n), f"Dining{n}.bip"), "Table()"
    if kind == "ordered":
        n = int(arg.split("=")[1])
        return parse_text(ordered(n), f"Ordered{n}.bip"), "Table()"
    if kind == "DALA":
        return dala_model(None)
    if kind == "Arm":
        from genom2bip.generate import model_of
        from genom2bip.parser import parse_paths
        package, root, _ = model_of(parse_paths([str(ROOT / "descriptions" / "arm" / "Arm.gen")]), "arm", None)
        return package, root
    return dala_model([kind])


class TimeUp(Exception):
    pass


def one(method: str, name: str, seconds: float) -> dict:
    """One measurement in this process: verdict, seconds, and what was reached."""
    package, root = model(name)
    start = time.perf_counter()
    if method == "compositional":
        from runtime.compositional import analyse, decide
        from runtime.engine import flatten
        analysis = analyse(flatten(package, root))
        decide(analysis, package, root)
        n = len(analysis.candidates)
        note = f"{len(analysis.potentials)} potential, {analysis.traps} traps, {n} checked"
        return {"verdict": analysis.verdict, "seconds": time.perf_counter() - start, "note": note}
    if method == "explore":
        from runtime.explore import StateSpace, explore

        def stop(*_):
            raise TimeUp

        space = StateSpace(package, root)
        signal.signal(signal.SIGALRM, stop)
        signal.setitimer(signal.ITIMER_REAL, seconds)
        try:
            result = explore(space)
        except TimeUp:
            return {"verdict": "did not finish", "seconds": time.perf_counter() - start,
                    "note": f"{len(space):,} states in {seconds:.0f} s"}
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
        verdict = "deadlock" if result.deadlocks else "deadlock-free"
        return {"verdict": verdict, "seconds": time.perf_counter() - start, "note": f"{result.states:,} states"}
    from runtime.explore import StateSpace
    from runtime.export.spin import SpinRun, parse_pan
    run = SpinRun(StateSpace(package, root))
    try:
        run.build(extra=("-DMEMLIM=4000",))
        proc = subprocess.Popen(["./pan", "-m1000000", "-w26", "-c1", "-n"], cwd=run.dir, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True)
        try:
            out, _ = proc.communicate(timeout=seconds)
            finished = True
        except subprocess.TimeoutExpired:
            proc.send_signal(signal.SIGINT)  # pan prints its statistics when interrupted
            out, _ = proc.communicate()
            finished = False
        report = parse_pan(out)
        elapsed = time.perf_counter() - start
        memory_out = "out of memory" in out.lower() or "memlim" in out.lower() and "error" in out.lower()
        if report.errors:
            verdict = "deadlock"
        elif finished and report.complete and not memory_out:
            verdict = "deadlock-free"
        else:
            verdict = "did not finish"
        why = "memory cap" if memory_out else f"{seconds:.0f} s cap" if not finished else "incomplete"
        note = f"{report.states:,.0f} states" + ("" if verdict != "did not finish" else f", {why}")
        return {"verdict": verdict, "seconds": elapsed, "note": note}
    finally:
        run.cleanup()


def measure(method: str, name: str, seconds: float) -> dict:
    """Run ``one`` in a child; add its peak memory (the child and its own children, e.g. pan)."""
    argv = [sys.executable, __file__, "--one", method, name, "--seconds", str(seconds)]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONPATH": str(ROOT)}, start_new_session=True)
    try:
        out, err = proc.communicate(timeout=seconds + 240)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)  # the child and what it started (gcc, pan)
        out, err = proc.communicate()
        stage = "translating or compiling (SPIN)" if method == "spin" else "running"
        return {"verdict": "did not finish", "seconds": seconds + 240,
                "note": f"still {stage} at {seconds + 240:.0f} s, stopped", "mb": 0.0}
    line = next((x for x in out.splitlines() if x.startswith("{")), None)
    if line is None:
        return {"verdict": "error", "seconds": 0.0, "note": err.strip().splitlines()[-1:] or [""], "mb": 0.0}
    got = json.loads(line)
    return got


def child_report(result: dict) -> None:
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    kids = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    result["mb"] = max(own, kids) / 1024
    print(json.dumps(result))


def cell(r: dict) -> str:
    verdict = r["verdict"]
    return f"{verdict} | {r['seconds']:.2f} s | {r['mb']:,.0f} MB | {r['note']}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=120.0, help="time cap of the explorer and of SPIN per model")
    ap.add_argument("--only", help="run only the models whose name contains this")
    ap.add_argument("--methods", default="compositional,explore,spin")
    ap.add_argument("--one", nargs=2, metavar=("METHOD", "MODEL"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        child_report(one(args.one[0], args.one[1], args.seconds))
        return 0
    names = [f"dining N={n}" for n in (10, 20, 50, 100)] + [f"ordered N={n}" for n in (10, 20, 50, 100)]
    names += [f"{m} module" for m in MODULES] + ["DALA (5 modules, rules)", "Arm component"]
    methods = args.methods.split(",")
    print(f"machine: {os.cpu_count()} cores, Python {sys.version.split()[0]}; caps: {args.seconds:.0f} s, "
          "SPIN -DMEMLIM=4000 -w26")
    head = "| model | " + " | ".join(f"{m} verdict | time | peak | reached" for m in methods) + " |"
    print(head)
    print("| --- |" + " --- | ---: | ---: | --- |" * len(methods))
    for name in names:
        if args.only and args.only not in name:
            continue
        cells = [cell(measure(m, name, args.seconds)) for m in methods]
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)
    if not args.only:
        solvers_table(names)
    return 0


SOLVERS = ["minisat22", "glucose4", "cadical153", "cadical195", "lingeling", "maplechrono"]


def solvers_table(names: list[str]) -> None:
    """Seconds of the analysis (invariants, formula, SAT; no candidate checks) per SAT solver."""
    from runtime.compositional import analyse
    from runtime.engine import flatten
    print()
    print("| model (analysis only) | " + " | ".join(SOLVERS) + " |")
    print("| --- |" + " ---: |" * len(SOLVERS))
    for name in names:
        flat = flatten(*model(name))
        row = []
        for solver in SOLVERS:
            best = float("inf")
            for _ in range(3):
                start = time.perf_counter()
                analyse(flat, solver)
                best = min(best, time.perf_counter() - start)
            row.append(f"{best:.3f}")
        print(f"| {name} | " + " | ".join(row) + " |", flush=True)


if __name__ == "__main__":
    sys.exit(main())
