"""``genom2bip verify --deadlock --method compositional|both``: the D-Finder style analysis and its report.

The analysis lives in runtime/compositional and the verification API
(genom2bip/verify/compositional.py) runs it; this module only adds the
options, prints the phases as they end, each potential deadlock with its
verdict and the method that decided it, and writes the dependency graph.
"""
from __future__ import annotations

import argparse

from genom2bip.cli.verbs import EXIT_ERRORS, EXIT_INCONCLUSIVE, EXIT_OK, EXIT_USAGE, EXIT_VIOLATED, Failure, error

METHODS = ("explore", "compositional", "both")
#: Potential deadlocks refuted by invariants printed in full; the rest are counted.
SHOWN_REFUTED = 5


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from runtime.compositional.solver import DEFAULT_SOLVER
    group = parser.add_argument_group("compositional deadlock analysis (--method compositional or both)")
    group.add_argument("--method", choices=METHODS, default="explore",
                       help="deadlock-freedom by exploration (default), by invariants and SAT (compositional: "
                            "--property and the observers of --timed then by localization), or both side by side")
    group.add_argument("--solver", default=DEFAULT_SOLVER, metavar="NAME",
                       help=f"python-sat solver for the formulas (default {DEFAULT_SOLVER}; e.g. minisat22, "
                            "glucose4, cadical195)")
    group.add_argument("--graph", metavar="FILE",
                       help="write the atoms' dependency graph as Graphviz DOT, the candidates' wait-for cycles in red")
    group.add_argument("--check-states", type=int, default=None, metavar="N",
                       help="states the explorer may visit to decide each candidate (default 2,000,000 breadth-first "
                            "compiled, 20,000 in Python, then 50,000 guided)")


def check_arguments(args: argparse.Namespace) -> None:
    """Usage errors specific to the compositional method."""
    if args.method == "explore":
        if args.graph:
            error("--graph belongs to --method compositional or both")
            raise Failure(EXIT_USAGE)
        return
    if (args.property and args.method == "both") or args.aut or args.dot:
        error(f"--method {args.method} checks deadlock freedom (and, with compositional, --property by "
              "localization); --aut and --dot need --method explore, --property with both needs one method")
        raise Failure(EXIT_USAGE)
    if args.property and getattr(args, "timed", False):
        error("--method compositional checks --property by localization on untimed models; drop --timed")
        raise Failure(EXIT_USAGE)
    if args.engine == "spin":
        error(f"--method {args.method} decides candidates with our explorer; it does not combine with --engine "
              f"{args.engine}")
        raise Failure(EXIT_USAGE)
    if args.requests is not None:
        error("--method compositional analyses the open environment (any number of requests); drop --requests")
        raise Failure(EXIT_USAGE)
    if args.check_states is not None and args.check_states < 0:
        error("--check-states must be >= 0")
        raise Failure(EXIT_USAGE)
    from pysat.solvers import SolverNames
    if not hasattr(SolverNames, args.solver):
        names = sorted(k for k in vars(SolverNames) if not k.startswith("_"))
        error(f"--solver {args.solver}: not a python-sat solver (one of {', '.join(names)})")
        raise Failure(EXIT_USAGE)


def run(model, args: argparse.Namespace, options, listener) -> int:
    """Analyse, decide the candidates, print the report; the exit status of the verdict."""
    from genom2bip.cli.printers import print_trace, step_sources
    from genom2bip.verify import Verdict, check_deadlock_compositional

    print(f"compositional analysis (component invariants, interaction invariants, DIS; SAT: {args.solver})")
    if getattr(args, "timed", False):
        print("  time: the tick is one more interaction (all timed atoms at once); deadlock-free means no time-lock")
    found = check_deadlock_compositional(model, options, listener)
    if args.graph and _write_graph(found.analysis, args.graph) != EXIT_OK:
        return EXIT_ERRORS
    from genom2bip.cli.verify_report import active

    sources = step_sources(model.flat)
    total = found.figures.seconds
    how = f"compositional: invariants and SAT, {found.potentials} potential, {len(found.candidates)} candidate(s), " \
          f"{total:.2f} s"
    active().check("deadlock", "deadlock freedom", found.verdict.value, found, how=how)
    _report(found, lambda trace: print_trace(trace, sources=sources))
    if found.verdict is Verdict.HOLDS:
        print(f"deadlock-free (compositional, {total:.2f} s)")
        return EXIT_OK
    if found.verdict is Verdict.VIOLATED:
        print(f"deadlock reachable (compositional, {total:.2f} s)")
        return EXIT_VIOLATED
    print(f"unknown: deadlock freedom neither proved nor refuted (compositional, {total:.2f} s)")
    return EXIT_INCONCLUSIVE


def _report(found, print_trace) -> None:
    """The potential deadlocks, the first refuted ones, and each candidate with its verdict, state and trace."""
    refuted = found.refuted
    counts: dict[str, int] = {}
    for p in refuted:
        counts[p.method] = counts.get(p.method, 0) + 1
    how = ", ".join(f"{n} by {m}" for m, n in counts.items())
    print(f"potential deadlocks: {found.potentials} models of CI ∧ DIS; {len(refuted)} refuted"
          + (f" ({how})" if how else "") + f"; {len(found.candidates)} candidate(s) checked"
          + (f"; {found.reused_traps} traps reused" if found.reused_traps else ""))
    for n, p in enumerate(refuted[:SHOWN_REFUTED], 1):
        print(f"  refuted {n}: {p.method}: {p.reason}")
    if len(refuted) > SHOWN_REFUTED:
        print(f"  ... and {len(refuted) - SHOWN_REFUTED} more refuted")
    for n, p in enumerate(found.candidates, 1):
        how = f" by {p.method}" if p.method else ""
        print(f"candidate {n}: {p.verdict}{how}" + (f": {p.reason}" if p.reason else ""))
        print("  state:")
        for line in p.state:
            print(f"    {line}")
        for cycle in p.waits[:5]:
            print(f"  waits: {' -> '.join(cycle + cycle[:1])}")
        if p.trace is not None:
            from genom2bip.cli.verify_report import active
            with active().trace("deadlock freedom", f"candidate-{n}", p.trace, "trace", "\n".join(p.state)):
                print(f"  trace ({len(p.trace)} steps):")
                print_trace(p.trace.steps)
    if not found.listing_complete:
        print(f"the listing stopped after {len(found.candidates)} candidates; "
              + ("the exhaustive exploration decided the others too" if found.explored else "more may exist"))


def _write_graph(analysis, path: str) -> int:
    from runtime.compositional import dependency_graph
    g = dependency_graph(analysis)
    red = set()
    for p in analysis.candidates:
        for cycle in p.waits:
            red |= {(a, b) for a, b in zip(cycle, cycle[1:] + cycle[:1])}
    lines = [f"// dependency graph of {analysis.flat.root}: an edge A -> B when an interaction needs ports of both",
             "// wait-for cycles of the candidates (red):"]
    for n, p in enumerate(analysis.candidates, 1):
        for cycle in p.waits:
            lines.append(f"//   candidate {n}: {' -> '.join(cycle + cycle[:1])}")
    lines.append("digraph dependencies {")
    lines.append("  node [shape=box, fontname=Helvetica];")
    for node in g.nodes:
        lines.append(f'  "{node}";')
    for a, b, data in g.edges(data=True):
        labels = "\\n".join(data["interactions"][:4]) + ("\\n..." if len(data["interactions"]) > 4 else "")
        style = ', color=red, penwidth=2' if (a, b) in red else ""
        lines.append(f'  "{a}" -> "{b}" [tooltip="{labels}"{style}];')
    lines.append("}")
    try:
        with open(path, "w", encoding="utf-8") as f:
            f.write("\n".join(lines) + "\n")
    except OSError as exc:
        error(f"cannot write {path}: {exc.strerror or exc}")
        return EXIT_ERRORS
    what = (f"dependency graph: {g.number_of_nodes()} atoms, {g.number_of_edges()} edges, "
            f"{sum(len(p.waits) for p in analysis.candidates)} wait-for cycles")
    print(f"wrote {path} ({what})")
    from genom2bip.cli.verify_report import active
    active().wrote(path, what)
    return EXIT_OK

