"""``python -m runtime run MODEL.bip --root 'System()' ...``: run a BIP2 model on the engine.

Every failure (unreadable or malformed file, bad root, missing extern
binding, model error at a step) is a message on stderr and a non-zero exit
status, never a traceback, from the one table of runtime/exits.py that
``genom2bip`` shares: 1 for bad input, 4 for what a run or an exploration
found (a model error during the run, an atom invariant that fails, an event
that an extern port with policy ``error`` cannot take, a violated timing
constraint; a deadlock or a time-lock that ``explore`` reaches, a label
that ``reach`` reaches), 5 for an exploration a limit stopped, 3 for an
internal error.  A run that ends in a deadlock, a time-lock or at the step
limit exits with 0: running is not checking.  (The Verimag engine gives the
run's failures 2, 5, 6 and 7; the message says which one it is.)
``explore`` runs the discrete-time exploration of a timed model
(runtime/timed_cli.py); ``reach`` decides reachability of labels in a
TChecker file (runtime/tchecker/cli.py).
"""
from __future__ import annotations

import argparse
import os
import sys
import traceback

from runtime.diagnostics import DiagnosticError
from runtime.exits import (
    EXIT_ERRORS, EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_OK, EXIT_VIOLATED, closed_output, epilog,
)
from runtime.timed_cli import explore_command, is_timed, run_timed_command


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m runtime", description="BIP engine: run a BIP2 model.",
                                 epilog=epilog(), formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    table = {"epilog": epilog(), "formatter_class": argparse.RawDescriptionHelpFormatter}
    run = sub.add_parser("run", help="execute a model, choosing among enabled interactions by a policy", **table)
    run.add_argument("model", help="the .bip file (package P lives in P.bip)")
    run.add_argument("--root", default="System()", help="root instance, e.g. 'System()' or 'Sys(3)'")
    add_run_options(run)
    run.add_argument(
        "--externs", metavar="MODULE", help="Python module (dotted name or .py path) binding extern functions"
    )
    run.add_argument("--show-source", action="store_true", help="print the generated step code and exit")
    run.add_argument("--real-time", action="store_true",
                     help="timed models: follow the engine's clock (wait for real) instead of simulated time")
    run.add_argument("--random-time", action="store_true",
                     help="timed models: plan each interaction at a random instant of its window (seeded by --seed), "
                          "as the Verimag engine does, instead of the earliest")
    explore = sub.add_parser("explore", help="timed models: explore in discrete time (a tick, capped clocks)",
                             **table)
    explore.add_argument("model", help="the .bip file")
    explore.add_argument("--root", default="System()", help="root instance")
    explore.add_argument("--tick", default="1ms", help="length of one tick: 1ms, 250us, 2s (default 1ms)")
    explore.add_argument("--max-states", type=int, default=1_000_000, help="stop after this many states")
    explore.add_argument("--externs", metavar="MODULE", help="Python module binding extern functions")
    from runtime.tchecker.cli import add_parser as add_reach

    add_reach(sub)
    run.add_argument("--no-maximal-progress", action="store_true",
                     help="offer every enabled interaction of a connector, not only the maximal ones")
    run.add_argument("--events", metavar="FILE",
                     help='events for the extern ports, JSON lines {"port": "a.p", "values": [1], "after": 0}')
    return ap


def run_command(args, out=None, err=None) -> int:
    from runtime.bip2 import parse_file
    from runtime.engine import Engine, EngineError

    out = out or sys.stdout
    err = err or sys.stderr
    try:
        package = parse_file(args.model)
        if is_timed(package) and not args.show_source:
            return run_timed_command(package, args, out, err)
        engine = Engine(package, args.root, externs=args.externs, maximal_progress=not args.no_maximal_progress)
        if args.events:
            push_events(engine, args.events)
    except DiagnosticError as e:
        print(e.render(), file=err)
        return EXIT_ERRORS
    except EngineError as e:
        print(f"{args.model}: error: {e}", file=err)
        return EXIT_ERRORS
    if args.show_source:
        print(engine.source, file=out)
        return EXIT_OK
    return execute(engine, args, args.model, out, err)


def execute(engine, args, name: str, out, err) -> int:
    """Run ``engine`` with the policy, limit and tracers asked for in ``args``; print the summary line."""
    from runtime.engine import ConsoleTracer, JsonlTracer, MultiTracer, make_policy

    if args.limit is not None and args.limit < 0:
        print("error: --limit must be >= 0", file=err)
        return EXIT_ERRORS
    policy = make_policy(args.policy, args.seed, engine.format_state)
    tracers = []
    if not args.quiet:
        tracers.append(ConsoleTracer(out))
    if args.trace:
        try:
            tracers.append(JsonlTracer(args.trace))
        except OSError as e:
            print(f"error: cannot write trace: {e}", file=err)
            return EXIT_ERRORS
    summary = engine.run(policy, args.limit, MultiTracer(*tracers))
    print(summary.line(), file=out)
    if summary.outcome == "error":
        print(f"{name}: model error: {summary.message}", file=err)
        return EXIT_VIOLATED
    if summary.outcome in ("invariant", "event"):
        print(f"{name}: ERROR: {summary.message}", file=err)
        return EXIT_VIOLATED
    return EXIT_OK


def push_events(engine, path: str) -> None:
    """Queue the events of the JSON-lines file ``path`` for the extern ports of ``engine``."""
    from runtime.engine import EngineError
    from runtime.engine.extern_ports import read_events

    events = read_events(path)
    if events and engine.extern is None:
        raise EngineError(f"{path}: the model has no extern port to take events")
    for e in events:
        engine.extern.push(e.port, *e.values, after=e.after)


def add_run_options(run: argparse.ArgumentParser) -> None:
    """Options of every command that runs a model: seed, limit, policy, trace, quiet."""
    run.add_argument("--seed", type=int, default=None, help="seed of the random policy")
    run.add_argument("--limit", type=int, default=None, help="stop after this many steps")
    run.add_argument("--policy", choices=("first", "random", "interactive"), default="random")
    run.add_argument("--trace", metavar="FILE", help="write the steps as JSON lines to FILE")
    run.add_argument("--quiet", action="store_true", help="print only the summary line")


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns its exit status (runtime/exits.py)."""
    try:
        args = _parser().parse_args(argv)
    except SystemExit as exc:  # argparse: --help (0), usage errors (2)
        return int(exc.code) if isinstance(exc.code, int) else EXIT_ERRORS
    try:
        if args.command == "run":
            return run_command(args)
        if args.command == "reach":
            from runtime.tchecker.cli import reach_command

            return reach_command(args, sys.stdout, sys.stderr)
        return explore_command(args, sys.stdout, sys.stderr)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # `python -m runtime run M.bip | head`: the reader has what it wanted
        return closed_output()
    except Exception as exc:  # noqa: BLE001 - a bug: one line, the traceback only when asked for
        if os.environ.get("GENOM2BIP_TRACEBACK", "") not in ("", "0"):
            traceback.print_exc()
        print(f"python -m runtime: internal error: {type(exc).__name__}: {exc}", file=sys.stderr)
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
