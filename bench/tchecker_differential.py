"""Random TChecker models, read by our reader and by tck-reach: the reachable configurations must be the same.

    python bench/tchecker_differential.py TCK_REACH [--models 200] [--seed 0] [--grid 4] [--keep DIR]

Each model has one to three processes with a clock each, two to four locations (initial, committed, urgent,
invariants, labels), random edges over three events with clock and integer guards, clock resets and integer
assignments, and often a sync vector of two or three processes, some of its constraints weak.  For each, the
configurations without clocks (locations and integers) of ``tck-reach -a reach -C graph`` are compared with
ours (runtime.tchecker.reach.configurations).  Models on which tck-reach stops with an error (an assignment
out of a variable's domain: tck-reach 0.8 aborts where the format says the edge is not executable) are
counted apart.  The files are written to a temporary directory (``--keep DIR`` keeps them there instead; it
must lie outside the repository).  Exits 1 at the first difference, printing the model.
"""
from __future__ import annotations

import argparse
import random
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def model(rng: random.Random) -> str:
    out = ["system:r", "event:a", "event:b", "event:c", "int:1:0:2:0:n", "int:1:-1:1:0:m"]
    procs = []
    for p in range(rng.randint(1, 3)):
        name = f"P{p}"
        out += [f"process:{name}", f"clock:1:x{p}"]
        count = rng.randint(2, 4)
        for loc in range(count):
            attrs = ["initial:"] if loc == 0 else []
            r = rng.random()
            if r < 0.15 and loc:
                attrs.append("committed:")
            elif r < 0.3 and loc:
                attrs.append("urgent:")
            elif r < 0.6:
                attrs.append(f"invariant: x{p} <= {rng.randint(0, 3)}")
            attrs.append(f"labels: L{p}_{loc}")
            out.append(f"location:{name}:l{loc}{{{' : '.join(attrs)}}}")
        for _ in range(rng.randint(1, 5)):
            guard, stmts = [], []
            if rng.random() < 0.5:
                guard.append(f"x{p} {rng.choice(['<=', '>=', '==', '<', '>'])} {rng.randint(0, 3)}")
            if rng.random() < 0.4:
                guard.append(f"{rng.choice('nm')} {rng.choice(['==', '!=', '<', '>='])} {rng.randint(-1, 2)}")
            if rng.random() < 0.5:
                stmts.append(f"x{p} = {rng.randint(0, 1)}")
            if rng.random() < 0.4:
                v = rng.choice("nm")
                stmts.append(f"{v} = {rng.choice([v + ' + 1', v + ' - 1', str(rng.randint(-1, 2)), 'n + m'])}")
            attrs = ([f"provided: {' && '.join(guard)}"] if guard else []) + \
                ([f"do: {'; '.join(stmts)}"] if stmts else [])
            edge = f"edge:{name}:l{rng.randrange(count)}:l{rng.randrange(count)}:{rng.choice('abc')}"
            out.append(edge + (f"{{{' : '.join(attrs)}}}" if attrs else ""))
        procs.append(name)
    if len(procs) >= 2 and rng.random() < 0.7:
        parts = rng.sample(procs, rng.randint(2, len(procs)))
        weak = [rng.random() < 0.3 for _ in parts]
        out.append("sync:" + ":".join(f"{q}@{rng.choice('abc')}{'?' if w else ''}" for q, w in zip(parts, weak)))
    text = "\n".join(out) + "\n"
    for line in out:  # tck-reach refuses guards on weakly synchronised edges: draw again
        if line.startswith("sync:") and "?" in line:
            weak = {tuple(c.rstrip("?").split("@")) for c in line[5:].split(":") if c.endswith("?")}
            if any(e.startswith("edge:") and "provided" in e and (e.split(":")[1], e.split(":")[4].split("{")[0])
                   in weak for e in out):
                return model(rng)
    return text


def theirs(binary: str, path: Path) -> set | None:
    p = subprocess.run([binary, "-a", "reach", "-C", "graph", str(path)], capture_output=True, text=True, timeout=120)
    if p.returncode or "ERROR" in p.stderr:
        return None
    got = set()
    for m in re.finditer(r'intval="([^"]*)".*?vloc="<([^>]*)>"', p.stdout):
        ints = tuple(sorted((k, int(v)) for k, v in (x.split("=") for x in m.group(1).split(",") if x)))
        got.add((tuple(m.group(2).split(",")), ints))
    return got


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("tck_reach")
    ap.add_argument("--models", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--grid", type=int, default=4, help="our time grid for strict constraints (default 4)")
    ap.add_argument("--keep", help="write the models there (outside the repository) and keep them")
    args = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    from runtime.tchecker.reach import configurations

    if args.keep and Path(args.keep).resolve().is_relative_to(ROOT):
        print(f"--keep {args.keep}: inside the repository; keep the models elsewhere", file=sys.stderr)
        return 2
    folder = Path(args.keep or tempfile.mkdtemp(prefix="tck-diff-"))
    folder.mkdir(parents=True, exist_ok=True)
    rng = random.Random(args.seed)
    same = aborted = 0
    for k in range(args.models):
        path = folder / f"random_{args.seed}_{k}.tck"
        path.write_text(model(rng), encoding="utf-8")
        expected = theirs(args.tck_reach, path)
        if expected is None:
            aborted += 1
            continue
        mine = {(locs, tuple(sorted(ints))) for locs, ints in configurations(path, args.grid)}
        if mine != expected:
            print(f"{path}: different configurations: {len(expected - mine)} only in tck-reach "
                  f"{sorted(expected - mine)[:3]}, {len(mine - expected)} only here {sorted(mine - expected)[:3]}")
            print(path.read_text(encoding="utf-8"))
            return 1
        same += 1
    print(f"{same} models: the same configurations; {aborted} stopped by tck-reach with an error (not compared)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
