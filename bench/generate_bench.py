"""Generation time: DALA (with its rules), and a synthetic component with 40 services (parse, check, build, write).

Prints the median of several runs for each phase; not a test.
    python bench/generate_bench.py
"""
from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

from genom2bip.checks import check_description
from genom2bip.generate import generate, model_of
from genom2bip.parser import parse_paths, parse_text
from genom2bip.rules import all_rules
from runtime.diagnostics import Reporter

ROOT = Path(__file__).resolve().parents[1]


def synthetic(services: int) -> str:
    """A component with ``services`` activities over two tasks, each with a 3-state FSM, constraints and posters."""
    lines = ["component big {", '  lang "c";', "  exception e_fail;",
             "  ids { double x; long n; };", "  port out double Out;",
             "  task fast { period 10 ms; };", "  task slow { period 100 ms; };"]
    for i in range(services):
        task = "fast" if i % 2 else "slow"
        after = f"    after S{i - 1};\n" if i % 5 == 4 else ""
        interrupts = f"    interrupts S{i - 1};\n" if i % 7 == 6 else ""
        lines.append(
            f"  activity S{i}(in double p = 0) {{\n    task {task};\n{after}{interrupts}"
            f"    codel <start> s{i}_start(ids in x) yield main, ether;\n"
            f"    codel <main> s{i}_main(port out Out) yield pause::main, end;\n"
            f"    codel <end> s{i}_end() yield ether;\n"
            f"    codel <stop> s{i}_stop() yield ether;\n    throw e_fail;\n  }};")
    lines.append("};")
    return "\n".join(lines) + "\n"


def timed(fn, runs: int = 5) -> tuple[float, object]:
    times, result = [], None
    for _ in range(runs):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times) * 1000, result


def phases(label: str, parse, rules_file: Path | None = None) -> None:
    t_parse, description = timed(parse)
    t_check, _ = timed(lambda: check_description(description, Reporter()))
    rules = all_rules(description, rules_file, Reporter())
    t_build, (package, _, _) = timed(lambda: model_of(description, label, rules))
    with tempfile.TemporaryDirectory() as out:
        t_all, _ = timed(lambda: generate(parse(), label, Path(out), label, "bench", rules))
    atoms = len(package.atom_types)
    print(f"{label:<12} parse {t_parse:7.1f} ms   check {t_check:6.1f} ms   build {t_build:7.1f} ms   "
          f"end to end (parse..write) {t_all:7.1f} ms   ({atoms} atom types, "
          f"{sum(len(c.connectors) for c in package.compound_types)} connectors)")


if __name__ == "__main__":
    phases("dala", lambda: parse_paths([ROOT / "descriptions" / "dala"]), ROOT / "descriptions" / "dala" / "rules.yaml")
    text = synthetic(40)
    phases("big-40", lambda: parse_text(text, "big.gen"))
