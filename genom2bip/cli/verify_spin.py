"""The SPIN side of ``genom2bip verify --engine spin``, printed: deadlocks and safety observers, trails in our labels.

The verification API runs SPIN (genom2bip/verify/spin.py); every trail it
returns was replayed on our engine, so a trail shown is a path of the BIP model.
"""
from __future__ import annotations

import argparse

from genom2bip.cli.printers import print_lines, print_trace, step_sources
from genom2bip.cli.verbs import EXIT_ERRORS, EXIT_INCONCLUSIVE, EXIT_OK, EXIT_VIOLATED, error
from genom2bip.cli.verify_report import active


def run_spin(space, args: argparse.Namespace, options, listener, deadlock: bool, properties) -> int:
    """Deadlock freedom, then each property, by SPIN; the worst exit status."""
    from genom2bip.verify import Verdict, refuse_for_spin, spin_deadlock, spin_property
    from runtime.export import spin
    from runtime.export.monitors import spin_shape
    from runtime.props import describe

    refuse_for_spin(properties)
    worst = EXIT_OK
    sources = step_sources(space.engine.flat)
    try:
        if deadlock or any(spin_shape(p) == "deadlock" for p in properties):
            found = spin_deadlock(space, options, listener)
            print(f"SPIN: {found.summary}")
            active().check("deadlock", "deadlock freedom", found.verdict.value, found, how=f"SPIN, {found.summary}")
            if found.verdict is not Verdict.VIOLATED:
                print("deadlocks: none reachable" + ("" if found.complete and found.exhaustive
                                                     else " (in the part SPIN covered)"))
            else:
                worst = EXIT_VIOLATED
                print(f"deadlocks: {found.reported} invalid end state(s) found by SPIN; trails replayed on the engine:")
                for k, d in enumerate(found.deadlocks, 1):
                    with active().trace("deadlock freedom", f"deadlock-{k}", d.trace, "deadlock", d.text):
                        print(f"deadlock {k} ({d.message}, {len(d.trace)} steps):")
                        print_trace(d.trace.steps, sources=sources)
                        print("  state:")
                        print_lines(d.text)
            if not found.complete and worst == EXIT_OK:
                worst = EXIT_INCONCLUSIVE
        for k, item in enumerate(properties):
            print(f"property {describe(item)}")
            subject = f"property {item.name}"
            if spin_shape(item) == "deadlock":
                print("  " + ("violated (see the deadlocks above)" if worst == EXIT_VIOLATED else "holds (SPIN)"))
                active().check("property", subject, "violated" if worst == EXIT_VIOLATED else "holds",
                               how="SPIN, the deadlock search above")
                continue
            found = spin_property(space, item, options, listener, f"p{k}")
            print(f"  SPIN: {found.summary}")
            active().check("property", subject, found.verdict.value, found, how=f"SPIN, {found.summary}")
            if found.verdict is Verdict.VIOLATED:
                worst = max(worst, EXIT_VIOLATED)
                with active().trace(subject, f"{subject} counterexample", found.trace, "counterexample"):
                    print("  violated: counterexample (SPIN's trail, replayed on the engine):")
                    if found.trace is not None:
                        print_trace(found.trace.steps, sources=sources)
            else:
                approximate = found.verdict is Verdict.INCONCLUSIVE
                print("  holds" + (" in the part SPIN covered (bitstate: not exhaustive)" if approximate else ""))
                if approximate and worst == EXIT_OK:
                    worst = EXIT_INCONCLUSIVE
    except spin.SpinError as exc:
        error(str(exc))
        return EXIT_ERRORS
    return worst
