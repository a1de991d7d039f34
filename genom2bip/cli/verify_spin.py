"""The SPIN side of ``genom2bip verify --engine spin``: deadlocks and safety observers, trails in our labels.

Every trail SPIN reports is replayed on our engine before it is printed
(runtime.export.spin), so a trail shown is a path of the BIP model.
"""
from __future__ import annotations

import argparse

from genom2bip.cli.printers import print_state, print_trace, progress, step_sources
from genom2bip.cli.verbs import EXIT_ERRORS, EXIT_INCONCLUSIVE, EXIT_OK, EXIT_VIOLATED, error


def _spin_summary(report, title: str) -> None:
    rate = f", {report.rate:,.0f} states/s" if report.rate else ""
    exact = "" if report.complete else " (not exhaustive)"
    print(f"{title}: {report.states:,} states, {report.transitions:,} transitions, state vector {report.vector} bytes, "
          f"{report.memory_mb:.1f} MB, {report.seconds:.2f} s{rate}{exact}")


def run_spin(space, args: argparse.Namespace, deadlock: bool, properties) -> int:
    from runtime.export import spin
    from runtime.export.interactions import all_interactions
    from runtime.export.monitors import build_monitor, spin_shape
    from runtime.props import describe

    worst = EXIT_OK
    unsupported = [p.name for p in properties if not spin_shape(p)]
    if unsupported:
        error(f"--engine spin checks deadlock freedom and safety properties [R] false / [R] {{P}} (never, precedes, "
              f"invariant); use --engine explore for: {', '.join(unsupported)}")
        return EXIT_ERRORS
    try:
        if deadlock or any(spin_shape(p) == "deadlock" for p in properties):
            if args.spin_swarm:
                result = spin.swarm(space, args.spin_swarm, None, min(args.spin_hash_bits, 30))
            else:
                result = spin.verify_deadlocks(space, args.spin_cores, args.spin_bitstate, args.spin_hash_bits,
                                               workdir=args.spin_dir, progress=progress(args))
            _spin_summary(result.report, "SPIN")
            errors = result.report.errors
            if errors == 0:
                print("deadlocks: none reachable" + ("" if result.report.complete and not args.spin_bitstate
                                                     and not args.spin_swarm else " (in the part SPIN covered)"))
            else:
                worst = EXIT_VIOLATED
                print(f"deadlocks: {errors} invalid end state(s) found by SPIN; trails replayed on the engine:")
                for k, trail in enumerate(result.trails, 1):
                    print(f"deadlock {k} ({trail.message}, {len(trail.steps)} steps):")
                    print_trace(trail.steps, sources=step_sources(space.engine.flat))
                    print("  state:")
                    print_state(space.engine, space.concrete(trail.steps))
            if not result.report.complete and worst == EXIT_OK:
                worst = EXIT_INCONCLUSIVE
        statics = None
        for k, item in enumerate(properties):
            shape = spin_shape(item)
            print(f"property {describe(item)}")
            if shape == "deadlock":
                print("  " + ("violated (see the deadlocks above)" if worst == EXIT_VIOLATED else "holds (SPIN)"))
                continue
            statics = statics or all_interactions(space.engine)
            monitor, _ = build_monitor(item, statics, f"p{k}")
            if args.spin_swarm:
                result = spin.swarm(space, args.spin_swarm, [monitor], min(args.spin_hash_bits, 30))
            else:
                result = spin.verify_safety(space, [monitor], args.spin_cores, args.spin_bitstate,
                                            args.spin_hash_bits, workdir=args.spin_dir, progress=progress(args))
            _spin_summary(result.report, "  SPIN")
            if result.report.errors:
                worst = max(worst, EXIT_VIOLATED)
                print("  violated: counterexample (SPIN's trail, replayed on the engine):")
                if result.trails:
                    print_trace(result.trails[0].steps, sources=step_sources(space.engine.flat))
            else:
                approximate = args.spin_bitstate or args.spin_swarm or not result.report.complete
                print("  holds" + (" in the part SPIN covered (bitstate: not exhaustive)" if approximate else ""))
                if approximate and worst == EXIT_OK:
                    worst = EXIT_INCONCLUSIVE
    except spin.SpinError as exc:
        error(str(exc))
        return EXIT_ERRORS
    return worst
