"""The ``genom2bip`` command: the verbs it has, its parser, and ``main`` with the one mapping of errors to exit codes.

Every verb lives in a module of its own and is listed here, in the order
``--help`` shows them.  Diagnostics (``file:line:column``, the source line, a
caret) or any other :class:`~runtime.errors.Genom2bipError` are a message on
stderr and exit code 1 (:func:`~genom2bip.cli.verbs.exit_status`, the one place
that maps them); bad usage exits 2; an unexpected
exception is a bug, reported on one "internal error" line with exit code 3
(``--traceback`` shows where).  The whole table, shared with ``python -m runtime``,
is runtime/exits.py; every ``--help`` ends with it.
"""
from __future__ import annotations

import argparse
import os
import sys
import traceback
from pathlib import Path
from typing import Sequence

from genom2bip.cli import call, campaign, check, generate, graph, mission, verify
from genom2bip.cli.pipes import ClosedAware
from genom2bip.cli.verbs import (
    DEFAULT_VERB, EXIT_INCONCLUSIVE, EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_USAGE, Verb, error, exit_status, version,
)
from runtime.errors import Genom2bipError
from runtime.exits import epilog

#: Every verb of the command line, in the order ``--help`` lists them.
VERBS: dict[str, Verb] = {fn.verb.name: fn.verb for fn in (
    check.verb_check, generate.verb_generate, call.verb_call, verify.verb_verify, graph.verb_graph,
    mission.verb_mission, campaign.verb_campaign,
)}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="genom2bip",
        description="GenoM module descriptions to BIP component models: check, generate, run, verify.",
        epilog=epilog(), formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"%(prog)s {version()}")
    parser.add_argument("--traceback", action="store_true",
                        help="on an internal error, print the whole traceback (also GENOM2BIP_TRACEBACK=1)")
    sub = parser.add_subparsers(dest="verb", metavar="COMMAND")
    sub.required = True
    for v in VERBS.values():
        p = sub.add_parser(v.name, help=v.help, description=v.help,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
        if v.arguments is not None:
            v.arguments(p)
        p.epilog = (p.epilog + "\n\n" if p.epilog else "") + epilog()  # a verb's own words, then the one table
        p.set_defaults(run=v.run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code (0 ok, 1 errors in the input, 2 usage, 3 internal error)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    show_traceback = "--traceback" in argv or os.environ.get("GENOM2BIP_TRACEBACK", "") not in ("", "0")
    argv = [a for a in argv if a != "--traceback"]
    for stream in (sys.stdout, sys.stderr):  # a file name the terminal cannot show is escaped, not a crash
        if hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="backslashreplace")
    # a reader gone (`| head`, `2>&1 | head`): printing stops quietly, the exit status stays the command's own
    stdout, stderr = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = ClosedAware(stdout), ClosedAware(stderr)
    try:
        return _run(argv, show_traceback)
    finally:
        sys.stdout, sys.stderr = stdout, stderr


def _run(argv: list[str], show_traceback: bool) -> int:
    parser = build_parser()
    if argv and not argv[0].startswith("-") and argv[0] not in VERBS and DEFAULT_VERB in VERBS:
        if not Path(argv[0]).exists():
            parser.print_usage(sys.stderr)
            error(f"'{argv[0]}' is neither a command ({', '.join(VERBS)}) nor a file or directory")
            return EXIT_USAGE
        argv.insert(0, DEFAULT_VERB)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: --help, --version, usage errors
        return int(exc.code) if isinstance(exc.code, int) else EXIT_USAGE
    try:
        return args.run(args)
    except Genom2bipError as exc:
        return exit_status(exc)
    except KeyboardInterrupt:
        print("genom2bip: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except MemoryError as exc:  # the system refused memory (a ulimit, a container): a limit, not a bug
        print(f"genom2bip: out of memory ({exc or 'the system refused more'}); --max-memory MB stops a search "
              "earlier and reports what it found", file=sys.stderr)
        return EXIT_INCONCLUSIVE
    except Exception as exc:  # noqa: BLE001 - the last resort: one line, the traceback only when asked for
        if show_traceback:
            traceback.print_exc()
        print(f"genom2bip: internal error: {type(exc).__name__}: {exc}", file=sys.stderr)
        if not show_traceback:
            print("genom2bip: run again with --traceback (or GENOM2BIP_TRACEBACK=1) to see where", file=sys.stderr)
        return EXIT_INTERNAL


def entry_point() -> None:
    """Console-script wrapper: exit with main()'s code."""
    sys.exit(main())
