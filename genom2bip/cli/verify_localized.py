"""``genom2bip verify --method compositional --property FILE``: the properties of a model too large to explore.

Deadlock freedom is the compositional analysis's (invariants and SAT); safety
properties and possibilities are decided by localization with
counterexample-guided refinement (runtime.localize).  Every property is
classified before anything runs: one the method cannot take is refused with
its file:line:column.
"""
from __future__ import annotations

import argparse
import sys

from genom2bip.cli.verbs import EXIT_ERRORS, EXIT_INCONCLUSIVE, EXIT_OK, EXIT_VIOLATED, Failure, error


def read_localizable(args: argparse.Namespace, flat) -> list:
    """The properties of the --property files, every one of a shape this method takes; else fail with where."""
    from runtime.diagnostics import DiagnosticError
    from runtime.localize.refine import localizable
    from runtime.props import read_property_file

    items, refused = [], []
    for path in args.property:
        try:
            props, warnings = read_property_file(path, flat)
        except DiagnosticError as exc:
            print(exc.render(), file=sys.stderr)
            raise Failure(EXIT_ERRORS) from None
        for w in warnings:
            print(w.render(), file=sys.stderr)
        for item in props:
            why = "" if item.property.pattern == "deadlock free" else localizable(item)
            if why:
                refused.append(f"{item.property.span}: property {item.name}: not checked by --method compositional: "
                               f"{why}")
            items.append(item)
    if refused:
        for line in refused:
            error(line)
        error("check these with --method explore on a model the search can finish (e.g. one module)")
        raise Failure(EXIT_ERRORS)
    return items


def run(items, package, root: str, args: argparse.Namespace, externs, deadlock_verdict: int) -> int:
    """Check each property by localization (deadlock freedom: the analysis above); the worst exit status."""
    from genom2bip.cli.printers import print_trace, step_sources
    from genom2bip.cli.verify_native import default_memory
    from runtime.localize.refine import NotLocalizable, check_localized
    from runtime.props import describe

    print("properties by localization (the atoms a property involves kept exact, the others a free environment; "
          "counterexample-guided refinement; deadlock freedom is not preserved by it and stays with the invariants)")
    max_bytes = args.max_memory * 1024 * 1024 if args.max_memory is not None else default_memory()
    worst = EXIT_OK
    sources = None
    for item in items:
        print(f"property {describe(item)}")
        if item.property.pattern == "deadlock free":
            word = {EXIT_OK: "holds", EXIT_VIOLATED: "violated"}.get(deadlock_verdict, "inconclusive")
            print(f"  {word} (compositional invariants, above)")
            worst = max(worst, deadlock_verdict)
            continue

        def say(r) -> None:
            what = "every atom kept (the exact search)" if r.kept == r.atoms else \
                f"{r.kept} of {r.atoms} atoms kept, {r.chaos} free"
            replayed = "replayed on the model" if r.outcome in ("violated", "run found") else "not replayed"
            tail = f", {replayed} ({r.concrete_states:,} states searched)" if r.concrete_states else ""
            print(f"  round {len(rounds) + 1}: {what}: {r.states:,} states, {r.seconds:.2f} s: {r.outcome}{tail}",
                  flush=True)
            rounds.append(r)

        rounds: list = []
        try:
            result = check_localized(package, root, item, externs, max_states=args.max_states, max_bytes=max_bytes,
                                     on_round=say)
        except NotLocalizable as exc:  # classified above; an abstraction's own labels may still count
            error(f"{item.property.span}: property {item.name}: {exc}")
            worst = max(worst, EXIT_ERRORS)
            continue
        v = result.verdict
        print(f"  {v.word} ({v.method}, {v.states:,} states, {v.seconds:.2f} s)" + (f": {v.note}" if v.note else ""))
        if v.trace:
            what = "counterexample" if v.holds is False else "witness"
            print(f"  {what} on the model ({len(v.trace)} step{'s' if len(v.trace) != 1 else ''}):")
            if sources is None:
                from runtime.engine import flatten
                sources = step_sources(flatten(package, root))
            print_trace(v.trace, sources=sources)
        if v.holds is False or v.error:
            worst = max(worst, EXIT_VIOLATED)
        elif v.holds is None:
            worst = max(worst, EXIT_INCONCLUSIVE)
    return worst
