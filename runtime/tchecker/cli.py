"""``python -m runtime reach FILE.tck --labels L1,L2``: reachability of location labels in a TChecker file.

Prints the verdict, the symbolic states stored, the transitions visited, the
time, the memory and, when the labels are reachable, a trace (delays and
global edges).  Exit status from the shared table (runtime/exits.py): 0
unreachable (the search is complete), 4 reachable (found), 5 unknown (stopped
at --max-states or --time-limit), 1 bad input (a located error, nothing
explored).
"""
from __future__ import annotations

import argparse

from runtime.exits import EXIT_ERRORS, EXIT_INCONCLUSIVE, EXIT_OK, EXIT_VIOLATED


def add_parser(sub) -> None:
    reach = sub.add_parser("reach", help="TChecker files: is a set of location labels reachable (clock zones)?",
                           description="Reachability of location labels in a TChecker file, explored with clock "
                                       "zones by the engine's zone search (docs/verification/tchecker.md).")
    reach.add_argument("model", help="the TChecker file (.tck, TChecker's text format)")
    reach.add_argument("--labels", "-l", default="",
                       help="comma-separated labels: reachable when one configuration's locations carry them all "
                            "(none: the whole zone graph is explored)")
    reach.add_argument("--grid", type=_positive, default=None, metavar="N",
                       help="read strict clock constraints on a time grid of 1/N ('x < c' as 'x <= c - 1/N'); "
                            "required when the file has one")
    reach.add_argument("--max-states", type=_positive, default=None, help="stop after this many symbolic states")
    reach.add_argument("--time-limit", type=_positive, default=None, metavar="SECONDS",
                       help="stop the search after this many seconds (verdict unknown)")
    reach.add_argument("--no-trace", action="store_true", help="do not compute a trace to the labels")


def _positive(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, not '{text}'") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, not {v}")
    return v


def reach_command(args, out, err) -> int:
    from runtime.diagnostics import DiagnosticError
    from runtime.engine import EngineError
    from runtime.explore.progress import Progress
    from runtime.tchecker.reach import reach
    from runtime.zones.model import Unsupported

    labels = [x.strip() for x in args.labels.split(",") if x.strip()]
    try:
        r = reach(args.model, labels, args.grid, args.max_states, Progress(err), not args.no_trace,
                  args.time_limit)
    except DiagnosticError as e:
        print(e.render(), file=err)
        return EXIT_ERRORS
    except (Unsupported, EngineError) as e:
        print(f"{args.model}: error: the zone engine does not take this model: {e}", file=err)
        return EXIT_ERRORS
    if r.unknown_labels:
        print(f"{args.model}: warning: no location carries label(s) {', '.join(r.unknown_labels)}: "
              "they are not reachable", file=err)
    verdict = r.verdict
    if verdict == "unknown":
        verdict += f" (stopped at the {'time limit' if r.stopped == 'time-limit' else 'state limit'})"
    if verdict == "unreachable" and not r.exact:
        verdict += f" (on the 1/{r.grid} time grid: the model has strict clock constraints)"
    print(f"labels: {','.join(labels)}" if labels else "labels: none (the whole zone graph is explored)", file=out)
    print(f"verdict: {verdict}", file=out)
    print(f"stored states: {r.states:,} ({r.kept:,} not covered at the end, {r.discrete:,} discrete)", file=out)
    print(f"visited transitions: {r.transitions:,}", file=out)
    print(f"time: {r.seconds:.6f} s searching ({r.build_seconds:.3f} s building the zone model first)", file=out)
    print(f"memory: {r.peak_rss / 2**20:.1f} MiB peak (the search holds {r.zone_bytes / 2**20:.2f} MiB)", file=out)
    if r.verdict == "reachable" and not args.no_trace:
        if r.trace_note:
            print(f"trace: {r.trace_note}", file=out)
        else:
            print("trace:", file=out)
            for delay, step in r.trace:
                print(f"  delay {delay}" if delay else "  delay 0", f"then {step}", file=out)
    return {"reachable": EXIT_VIOLATED, "unreachable": EXIT_OK}.get(r.verdict, EXIT_INCONCLUSIVE)
