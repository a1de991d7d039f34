"""What symbolic time costs: states and seconds of NDD untimed and timed, and the schedulability check per DALA module.

Run ``python bench/timed_bench.py [--default-wcet MS] [--max-states N] [--only MODULE]``.
Each DALA module is built alone (its own constraints, no rule file), as
``genom2bip verify descriptions/dala/M.gen --no-rules`` builds it; the timed
model is what ``--timed`` adds (docs/verification/time.md).  The DALA
descriptions declare no WCET, so every codel takes ``--default-wcet``
(default 0: the periods alone make time; give e.g. 10 to charge each codel
10 ms).  Figures are one run each, end to end: full exploration of the
untimed and the timed model, then one check per period observer (on the
fly: it stops at the first overrun it finds).  Each figure is given for the
compiled explorer (runtime/native, what ``verify`` runs by default) and the
Python one side by side; ``--python-limit`` caps the Python runs that would
take too long (their figures then say ``limit``).
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
from genom2bip.verify.model import tick_us  # noqa: E402
from genom2bip.verify.timing import observer_atoms  # noqa: E402
from runtime.engine import flatten  # noqa: E402
from runtime.explore import StateSpace, explore  # noqa: E402
from runtime.native.compiled import compile_space  # noqa: E402
from runtime.native.properties import compiled_check  # noqa: E402
from runtime.props import check, read_property_text  # noqa: E402

MODULES = ("NDD", "RFLEX", "LaserRF", "POM", "Aspect")


def explored(package, root: str, max_states: int) -> tuple[str, float]:
    space = StateSpace(package, root, {}, None, True, set(), max_states=max_states)
    return _figures(explore(space))


def explored_compiled(package, root: str, max_states: int) -> tuple[str, float]:
    cs, why = compile_space(StateSpace(package, root, {}, None, True, set()), search=True)
    if cs is None:
        return why, 0.0
    return _figures(cs.explore(max_states))


def _figures(result) -> tuple[str, float]:
    what = f"{result.states:,} states, {result.transitions:,} transitions" + ("" if result.complete else " (limit)")
    return what, result.seconds


ANSWER = {True: "no overrun", False: "overrun", None: "inconclusive"}


def schedulability(package, root: str, obs, max_states: int, compiled: bool) -> str:
    """One period observer's verdict, states and seconds, by the compiled or the Python checker."""
    flat = flatten(package, root)
    space = StateSpace(package, root, {}, None, True, set(), keep_edges=not compiled, max_states=max_states)
    item = read_property_text(f"invariant not ({obs.path} @ ERROR)", flat)
    start = time.perf_counter()
    verdict = compiled_check(space, item, max_states=max_states) if compiled else check(space, item)
    if verdict is None:
        return "not compiled"
    answer = ANSWER[verdict.holds] + (f" in {len(verdict.trace)} steps" if verdict.holds is False else "")
    return f"{answer}; {verdict.states:,} states, {time.perf_counter() - start:.2f} s"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--default-wcet", type=float, default=0.0, metavar="MS")
    parser.add_argument("--max-states", type=int, default=2_000_000)
    parser.add_argument("--python-limit", type=int, default=2_000_000, metavar="N",
                        help="state limit of the Python runs (default: --max-states)")
    parser.add_argument("--only", choices=MODULES)
    args = parser.parse_args()
    options = TimeOptions(default_wcet_us=round(args.default_wcet * 1000))
    plimit = min(args.python_limit, args.max_states)
    print(f"default WCET {args.default_wcet:g} ms; limit {args.max_states:,} states (Python: {plimit:,})")
    for name in (args.only,) if args.only else MODULES:
        description = parse_paths([ROOT / "descriptions/dala" / f"{name}.gen"])
        rules = description_rules(description)
        untimed, root, _ = model_of(description, name, rules)
        timed, _, _ = model_of(description, name, rules, options)
        if name == "NDD" or args.only:
            for label, package in (("untimed", untimed), ("timed", timed)):
                for engine, run, limit in (("compiled", explored_compiled, args.max_states),
                                           ("python", explored, plimit)):
                    what, seconds = run(package, root, limit)
                    tick = f" (tick {tick_us(timed) / 1000:g} ms)" if label == "timed" else ""
                    print(f"{name:8s} {label:8s} explore  {engine:8s}: {what}; {seconds:.2f} s{tick}")
        for obs in observer_atoms(timed, root):
            period = f"{obs.bound * tick_us(timed) / 1000:g} ms"
            for engine, limit in (("compiled", args.max_states), ("python", plimit)):
                answer = schedulability(timed, root, obs, limit, engine == "compiled")
                print(f"{name:8s} schedulability {obs.path} ({period}) {engine:8s}: {answer}")


if __name__ == "__main__":
    main()
