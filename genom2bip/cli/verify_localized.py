"""``genom2bip verify --method compositional --property FILE`` (or ``--timed``): properties and timing observers
of a model too large to explore, printed.

Deadlock freedom is the compositional analysis's (invariants and SAT); safety
properties, possibilities and the observers of a timed model are decided by
localization with counterexample-guided refinement (genom2bip/verify/localized.py).
Every property is classified before anything runs: one the method cannot take is
refused with its file:line:column.
"""
from __future__ import annotations

import argparse
import sys

from genom2bip.cli.verbs import EXIT_ERRORS, EXIT_INCONCLUSIVE, EXIT_OK, EXIT_VIOLATED, Failure, error


def print_warnings(diagnostics, _sources=None) -> None:
    """A property file's warnings, each as it renders."""
    for w in diagnostics:
        print(w.render(), file=sys.stderr)


def read_localizable(args: argparse.Namespace, model) -> list:
    """The properties of the --property files, every one of a shape this method takes; else fail with where."""
    from genom2bip.verify import read_properties, refuse_unlocalizable
    from runtime.diagnostics import DiagnosticError

    try:
        items, _ = read_properties(model, args.property, print_warnings)
    except DiagnosticError as exc:
        print(exc.render(), file=sys.stderr)
        raise Failure(EXIT_ERRORS) from None
    refuse_unlocalizable(items)
    return items


def run(items, model, args: argparse.Namespace, options, listener, deadlock_verdict: int) -> int:
    """Check each property by localization (deadlock freedom: the analysis above); the worst exit status."""
    from genom2bip.cli.printers import print_trace, step_sources
    from genom2bip.verify import Verdict, check_property_localized
    from runtime.localize.refine import NotLocalizable
    from runtime.props import describe

    from genom2bip.cli.verify_report import active

    print("properties by localization (the atoms a property involves kept exact, the others a free environment; "
          "counterexample-guided refinement; deadlock freedom is not preserved by it and stays with the invariants)")
    worst = EXIT_OK
    for item in items:
        print(f"property {describe(item)}")
        if hasattr(listener, "aside") and item.property.pattern != "deadlock free":
            listener.aside(f"property {item.name}: localization ...")
        if item.property.pattern == "deadlock free":
            word = {EXIT_OK: "holds", EXIT_VIOLATED: "violated"}.get(deadlock_verdict, "inconclusive")
            print(f"  {word} (compositional invariants, above)")
            active().check("property", f"property {item.name}", word, how="compositional invariants, above")
            worst = max(worst, deadlock_verdict)
            continue
        try:
            found = check_property_localized(model, item, options, listener)
        except NotLocalizable as exc:  # classified above; an abstraction's own labels may still count
            error(f"{item.property.span}: property {item.name}: {exc}")
            worst = max(worst, EXIT_ERRORS)
            continue
        how = f"{found.method}, {found.figures.states:,} states, {found.figures.seconds:.2f} s"
        print(f"  {found.word} ({how})" + (f": {found.message}" if found.message else ""))
        subject = f"property {item.name}"
        active().check("property", subject, found.verdict.value, found, how=how)
        if found.trace is not None and len(found.trace):
            what = "counterexample" if found.verdict is Verdict.VIOLATED else "witness"
            n = len(found.trace)
            with active().trace(subject, f"{subject} {what}", found.trace, what):
                print(f"  {what} on the model ({n} step{'s' if n != 1 else ''}):")
                print_trace(found.trace.steps, sources=step_sources(model.flat))
        if found.verdict in (Verdict.VIOLATED, Verdict.ERROR):
            worst = max(worst, EXIT_VIOLATED)
        elif found.verdict is Verdict.INCONCLUSIVE:
            worst = max(worst, EXIT_INCONCLUSIVE)
    return worst


def observers(model, kinds, options, listener) -> int:
    """``--timed --method compositional``: each observer's ERROR unreachable, by localization; the worst status."""
    from genom2bip.cli.verify_timed import check_observers

    print("observers by localization (the observer, what forces its close event in time and what the rounds add "
          "kept exact, the others a free environment)")
    return check_observers(model, kinds, None, options, listener, localized=True)
