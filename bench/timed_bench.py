"""What symbolic time costs: states and seconds of NDD untimed and timed, and the schedulability check per DALA module.

Run ``python bench/timed_bench.py [--default-wcet MS] [--max-states N] [--only MODULE]``.
Each DALA module is built alone (its own constraints, no rule file), as
``genom2bip verify descriptions/dala/M.gen --no-rules`` builds it; the timed
model is what ``--timed`` adds (docs/verification.md, *Time*).  The DALA
descriptions declare no WCET, so every codel takes ``--default-wcet``
(default 0: the periods alone make time; give e.g. 10 to charge each codel
10 ms).  Figures are one run each, end to end: full exploration of the
untimed and the timed model, then one check per period observer (on the
fly: it stops at the first overrun it finds).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from genom2bip.build.timed import TimeOptions  # noqa: E402
from genom2bip.generate import model_of  # noqa: E402
from genom2bip.parser import parse_paths  # noqa: E402
from genom2bip.rules import description_rules  # noqa: E402
from genom2bip.cli.verify_timed import observer_atoms, tick_us  # noqa: E402
from runtime.engine import flatten  # noqa: E402
from runtime.explore import StateSpace, explore  # noqa: E402
from runtime.props import check, read_property_text  # noqa: E402

MODULES = ("NDD", "RFLEX", "LaserRF", "POM", "Aspect")


def explored(package, root: str, max_states: int) -> tuple[str, float]:
    space = StateSpace(package, root, {}, None, True, set(), max_states=max_states)
    result = explore(space)
    what = f"{result.states:,} states, {result.transitions:,} transitions" + ("" if result.complete else " (limit)")
    return what, result.seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--default-wcet", type=float, default=0.0, metavar="MS")
    parser.add_argument("--max-states", type=int, default=2_000_000)
    parser.add_argument("--only", choices=MODULES)
    args = parser.parse_args()
    options = TimeOptions(default_wcet_us=round(args.default_wcet * 1000))
    print(f"default WCET {args.default_wcet:g} ms; limit {args.max_states:,} states")
    for name in (args.only,) if args.only else MODULES:
        description = parse_paths([ROOT / "descriptions/dala" / f"{name}.gen"])
        rules = description_rules(description)
        untimed, root, _ = model_of(description, name, rules)
        timed, _, _ = model_of(description, name, rules, options)
        if name == "NDD" or args.only:
            what, seconds = explored(untimed, root, args.max_states)
            print(f"{name:8s} untimed  explore: {what}; {seconds:.1f} s")
            what, seconds = explored(timed, root, args.max_states)
            print(f"{name:8s} timed    explore: {what}; {seconds:.1f} s (tick {tick_us(timed) / 1000:g} ms)")
        flat = flatten(timed, root)
        space = StateSpace(timed, root, {}, None, True, set(), keep_edges=True, max_states=args.max_states)
        for obs in observer_atoms(timed, root):
            start = time.perf_counter()
            verdict = check(space, read_property_text(f"invariant not ({obs.path} @ ERROR)", flat))
            answer = {True: "no overrun", False: f"overrun in {len(verdict.trace)} steps", None: "inconclusive"}
            print(f"{name:8s} schedulability {obs.path} ({obs.bound * tick_us(timed) / 1000:g} ms): "
                  f"{answer[verdict.holds]}; {verdict.states:,} states, {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
