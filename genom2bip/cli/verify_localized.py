"""``genom2bip verify --method compositional --property FILE`` (or ``--timed``): properties and timing observers
of a model too large to explore.

Deadlock freedom is the compositional analysis's (invariants and SAT); safety
properties, possibilities and the observers of a timed model are decided by
localization with counterexample-guided refinement (runtime.localize).  Every
property is classified before anything runs: one the method cannot take is
refused with its file:line:column.
"""
from __future__ import annotations

import argparse
import sys

from genom2bip.cli.verbs import EXIT_ERRORS, EXIT_INCONCLUSIVE, EXIT_OK, EXIT_VIOLATED, Failure, error

#: States one round's search may visit unless --max-states says otherwise: the rounds that prove DALA's properties
#: and observers take at most a few hundred thousand; past this, refinement has kept too much to stay cheap.
ROUND_STATES = 5_000_000


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
    from runtime.localize.refine import NotLocalizable, check_localized
    from runtime.props import describe

    print("properties by localization (the atoms a property involves kept exact, the others a free environment; "
          "counterexample-guided refinement; deadlock freedom is not preserved by it and stays with the invariants)")
    max_bytes = _max_bytes(args)
    worst = EXIT_OK
    sources = None
    for item in items:
        print(f"property {describe(item)}")
        if item.property.pattern == "deadlock free":
            word = {EXIT_OK: "holds", EXIT_VIOLATED: "violated"}.get(deadlock_verdict, "inconclusive")
            print(f"  {word} (compositional invariants, above)")
            worst = max(worst, deadlock_verdict)
            continue
        try:
            result = check_localized(package, root, item, externs, max_states=_round_states(args),
                                     max_bytes=max_bytes, on_round=round_printer())
        except NotLocalizable as exc:  # classified above; an abstraction's own labels may still count
            error(f"{item.property.span}: property {item.name}: {exc}")
            worst = max(worst, EXIT_ERRORS)
            continue
        v = _capped(result.verdict, args)
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


def observers(package, root: str, flat, kinds: set[str], args: argparse.Namespace, externs) -> int:
    """``--timed --method compositional``: each observer's ERROR unreachable, by localization; the worst status."""
    from genom2bip.cli.verify_timed import check_observers
    from runtime.localize.refine import check_localized

    print("observers by localization (the observer, what forces its close event in time and what the rounds add "
          "kept exact, the others a free environment)")

    def decide(item):
        return _capped(check_localized(package, root, item, externs, max_states=_round_states(args),
                                       max_bytes=_max_bytes(args), on_round=round_printer()).verdict, args)

    return check_observers(None, flat, package, root, kinds, None, decide=decide)


def round_printer():
    """``on_round`` for check_localized: one line per round (kept atoms, states, time, outcome, replay)."""
    rounds: list = []

    def say(r) -> None:
        what = "every atom kept (the exact search)" if r.kept == r.atoms else \
            f"{r.kept} of {r.atoms} atoms kept, {r.chaos} free"
        replayed = "replayed on the model" if r.outcome in ("violated", "run found") else "not replayed"
        tail = f", {replayed} ({r.concrete_states:,} states searched)" if r.concrete_states else ""
        print(f"  round {len(rounds) + 1}: {what}: {r.states:,} states, {r.seconds:.2f} s: {r.outcome}{tail}",
              flush=True)
        rounds.append(r)

    return say


def _round_states(args: argparse.Namespace) -> int:
    return args.max_states if args.max_states is not None else ROUND_STATES


def _capped(verdict, args: argparse.Namespace):
    """An inconclusive verdict says that the rounds' default limit stopped it, and how to lift it."""
    if verdict.holds is None and args.max_states is None and "max-states" in (verdict.note or ""):
        verdict.note = (f"a round stopped at {ROUND_STATES:,} states (the default limit of a localization round; "
                        "--max-states N sets another)")
    return verdict


def _max_bytes(args: argparse.Namespace) -> int:
    from genom2bip.cli.verify_native import default_memory

    return args.max_memory * 1024 * 1024 if args.max_memory is not None else default_memory()
