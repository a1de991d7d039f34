"""``genom2bip verify MODEL``: deadlocks, properties and LTS/Promela exports, on our explorer or on SPIN.

MODEL is description files or directories (the functional level is built as
``genom2bip generate`` builds it, rules included) or one ``.bip`` file
(``--root`` names the root, default the last compound type).  Exit status:
0 every check passed, 4 a deadlock, a violated property or a model error was
found, 5 a limit stopped the search before an answer, 1 bad input, 2 usage.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from genom2bip.cli.printers import print_state, print_trace, progress, step_sources
from genom2bip.cli.verbs import (
    EXIT_ERRORS, EXIT_INCONCLUSIVE, EXIT_OK, EXIT_USAGE, EXIT_VIOLATED, Failure, add_preprocessor_arguments,
    add_rules_arguments, error, load_externs, verb,
)


def _arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("paths", metavar="MODEL", nargs="+",
                        help="one .bip file, or description files (.gen) / directories of them")
    add_preprocessor_arguments(parser)
    parser.epilog = ("exit status: 0 all checks pass, 4 deadlock/violation/model error found, "
                     "5 stopped by a limit before an answer, 1 bad input, 2 usage")
    parser.add_argument("--root", help="root instance of a .bip model (default: the last compound type)")
    add_rules_arguments(parser)
    parser.add_argument("--name", metavar="SYSTEM", help="system name when building from descriptions")
    what = parser.add_argument_group("what to check (default: --deadlock)")
    what.add_argument("--deadlock", action="store_true", help="report every reachable deadlock with a shortest trace")
    what.add_argument("--property", metavar="FILE", action="append", default=[],
                      help="check the properties of FILE (MCL-style; docs/verification.md); may be repeated")
    search = parser.add_argument_group("exploration")
    search.add_argument("--engine", choices=("compiled", "python", "spin", "explore"), default="compiled",
                        help="our explorer compiled to C (default; Python where it cannot be compiled), our explorer "
                             "in Python, or SPIN on the Promela translation ('explore' is 'compiled')")
    search.add_argument("--max-memory", type=int, metavar="MB",
                        help="stop the search past MB megabytes (default: half the machine's memory)")
    search.add_argument("--max-states", type=int, metavar="N", help="stop after N states")
    search.add_argument("--max-depth", type=int, metavar="N", help="do not expand states deeper than N steps")
    search.add_argument("--dfs", action="store_true", help="depth-first (traces are then not shortest)")
    search.add_argument("--requests", type=int, metavar="N",
                        help="each service receives at most N requests (default: any number, one at a time)")
    search.add_argument("--no-reduce", action="store_true",
                        help="keep dead variables (no reset): the exact engine states, a larger state space")
    search.add_argument("--externs", metavar="MODULE",
                        help="Python module binding extern functions that are not codels")
    search.add_argument("--por", action="store_true",
                        help="compiled explorer: partial-order reduction (same deadlocks and safety verdicts, "
                             "fewer states; traces not shortest)")
    from genom2bip.cli.verify_native import add_arguments as add_native_arguments
    add_native_arguments(search)
    search.add_argument("--progress", action="store_true", help="show progress even when stderr is not a terminal")
    search.add_argument("--quiet", action="store_true", help="no progress line")
    out = parser.add_argument_group("exports")
    out.add_argument("--aut", metavar="FILE", help="write the explored LTS in Aldebaran format (CADP, mCRL2)")
    out.add_argument("--dot", metavar="FILE", help="write the explored LTS as a Graphviz graph")
    out.add_argument("--promela", metavar="FILE", help="write the model as Promela (observers of --property included)")
    out.add_argument("--trace-picture", metavar="FILE",
                     help="draw the first counterexample (deadlock, violated property, model error) as a sequence "
                          "diagram: .svg, .png or .dot")
    spin = parser.add_argument_group("SPIN (--engine spin)")
    spin.add_argument("--spin-cores", type=int, default=1, metavar="N", help="SPIN's multi-core search on N cores")
    spin.add_argument("--spin-bitstate", action="store_true", help="bitstate hashing (approximate, little memory)")
    spin.add_argument("--spin-hash-bits", type=int, default=27, metavar="B", help="hash table / bit array of 2^B")
    spin.add_argument("--spin-swarm", type=int, metavar="N", help="N bitstate runs with different hashes and orders")
    spin.add_argument("--spin-dir", metavar="DIR", help="keep SPIN's files (model.pml, pan.c, trails) in DIR")
    from genom2bip.cli.verify_compositional import add_arguments as add_compositional_arguments
    add_compositional_arguments(parser)
    from genom2bip.cli.verify_timed import add_time_arguments
    add_time_arguments(parser, verify=True)


# --------------------------------------------------------------------------- loading


def load_model(args: argparse.Namespace):
    """(package, root, title) from a .bip file or from descriptions."""
    paths = args.paths
    if len(paths) == 1 and paths[0].endswith(".bip"):
        from runtime.bip2 import parse_file
        from runtime.diagnostics import DiagnosticError

        if not Path(paths[0]).is_file():
            error(f"{paths[0]}: no such file")
            raise Failure(EXIT_ERRORS)
        try:
            package = parse_file(paths[0])
        except DiagnosticError as exc:
            print(exc.render(), file=sys.stderr)
            raise Failure(EXIT_ERRORS) from None
        if not package.compound_types and not args.root:
            error(f"{paths[0]}: no compound type to use as root; give --root")
            raise Failure(EXIT_ERRORS)
        root = args.root or package.compound_types[-1].name + "()"
        return package, root, f"{paths[0]} ({root})"
    if any(p.endswith(".bip") for p in paths):
        error("give either one .bip file or description files, not both")
        raise Failure(EXIT_USAGE)
    from genom2bip.cli.verbs import load, load_rules
    from genom2bip.generate import GenerateError, model_of, system_name
    from genom2bip.cli.verify_timed import time_options, warn_untimed
    from runtime.diagnostics import DiagnosticError

    description = load(args)
    rules = load_rules(args, description)
    system = args.name or system_name(paths)
    try:
        package, root, _ = model_of(description, system, rules, time_options(args, description))
    except GenerateError as exc:
        error(str(exc))
        raise Failure(EXIT_ERRORS) from None
    except DiagnosticError as exc:
        print(exc.render(), file=sys.stderr)
        raise Failure(EXIT_ERRORS) from None
    warn_untimed(package)
    if args.root:
        root = args.root
    return package, root, f"{system} ({root})"


def _check_options(args) -> None:
    for name in ("max_states", "max_depth", "requests", "max_memory"):
        value = getattr(args, name)
        if value is not None and value < 0:
            error(f"--{name.replace('_', '-')} must be >= 0")
            raise Failure(EXIT_USAGE)
    if args.spin_cores < 1:
        error("--spin-cores must be >= 1")
        raise Failure(EXIT_USAGE)
    if args.por and args.engine not in ("compiled", "explore"):
        error("--por belongs to the compiled explorer (--engine compiled); SPIN reduces by itself")
        raise Failure(EXIT_USAGE)
    from genom2bip.cli.verify_native import check_arguments as check_native_arguments
    if (wrong := check_native_arguments(args)) is not None:
        error(wrong)
        raise Failure(EXIT_USAGE)
    if args.engine == "spin" and (args.dfs or args.max_depth is not None or args.aut or args.dot):
        error("--dfs, --max-depth, --aut and --dot belong to --engine explore")
        raise Failure(EXIT_USAGE)
    from genom2bip.output import OutputError, check_files_are_not_inputs

    try:  # an export never overwrites what verify reads
        check_files_are_not_inputs([Path(p) for p in (args.aut, args.dot, args.promela) if p],
                                   [Path(p) for p in (*args.paths, *args.property, args.rules) if p])
    except OutputError as exc:
        error(str(exc))
        raise Failure(EXIT_ERRORS) from None


# --------------------------------------------------------------------------- the verb


@verb("verify", help="explore the BIP model: deadlocks, properties (MCL-style), LTS and Promela exports, SPIN",
      arguments=_arguments)
def verb_verify(args: argparse.Namespace) -> int:
    """Build or read the model, then run the checks asked for and print a verdict for each."""
    from runtime.diagnostics import DiagnosticError
    from runtime.engine import EngineError, flatten
    from runtime.props import read_property_file

    _check_options(args)
    from genom2bip.cli.verify_compositional import check_arguments as check_compositional
    check_compositional(args)
    package, root, title = load_model(args)
    try:
        flat = flatten(package, root)
    except EngineError as exc:
        error(f"{title}: {exc}")
        return EXIT_ERRORS
    compositional = EXIT_OK
    localized = None
    if args.method == "compositional" and args.property:  # every property classified before anything runs
        from genom2bip.cli.verify_localized import read_localizable
        localized = read_localizable(args, flat)
    if args.method != "explore":
        from genom2bip.cli.verify_compositional import run as run_compositional
        print(f"model {title}")
        compositional = run_compositional(flat, package, root, args, load_externs(args.externs))
        if args.method == "compositional":
            kinds = _observer_kinds(args)
            if kinds:
                from genom2bip.cli.verify_localized import observers as localized_observers
                compositional = max(compositional, localized_observers(package, root, flat, kinds, args,
                                                                       load_externs(args.externs)))
            if localized is not None:
                from genom2bip.cli.verify_localized import run as run_localized
                return max(compositional, run_localized(localized, package, root, args, load_externs(args.externs),
                                                        compositional))
            return compositional
        print("exploration")
    properties = []
    for path in args.property:
        try:
            props, warnings = read_property_file(path, flat)
        except DiagnosticError as exc:
            print(exc.render(), file=sys.stderr)
            return EXIT_ERRORS
        for w in warnings:
            print(w.render(), file=sys.stderr)
        properties.extend(props)
    observers = _observer_kinds(args)
    deadlock = args.deadlock or not (properties or args.aut or args.dot or args.promela or observers)
    observed = set().union(*(p.observed for p in properties)) if properties else set()
    from runtime.explore import ExploreError, StateSpace

    try:
        space = StateSpace(package, root, load_externs(args.externs), args.requests, not args.no_reduce, observed,
                           keep_edges=bool(properties or args.aut or args.dot), max_states=args.max_states)
    except (ExploreError, EngineError) as exc:
        error(f"{title}: {exc}")
        return EXIT_ERRORS
    if args.promela:
        code = _write_promela(space, properties, args.promela)
        if code != EXIT_OK:
            return code
    if args.method == "explore":
        print(f"model {title}")
    if args.engine == "spin":
        from genom2bip.cli.verify_spin import run_spin
        return run_spin(space, args, deadlock, properties)
    worst = max(compositional, _run_explorer(space, args, deadlock, properties))
    if observers:
        from genom2bip.cli.verify_timed import check_observers
        worst = max(worst, check_observers(space, flat, package, root, observers, progress(args), args))
    return worst


def _observer_kinds(args) -> set[str]:
    """The observers ``--timed`` checks: every one, or the period observers alone with --schedulability."""
    if not getattr(args, "timed", False):
        return set()
    return {"overrun"} if args.schedulability and not args.observers else {"overrun", "latency"}


def _write_promela(space, properties, path: str) -> int:
    from genom2bip.output import write_file
    from runtime.export.interactions import all_interactions
    from runtime.export.monitors import build_monitor, spin_shape
    from runtime.export.promela import PromelaError, write_promela

    monitors = []
    try:
        statics = all_interactions(space.engine)
        for k, p in enumerate(properties):
            if spin_shape(p) == "observer":
                monitors.append(build_monitor(p, statics, f"p{k}")[0])
        text = write_promela(space, monitors)
        write_file(Path(path), lambda f: f.write(text))
    except PromelaError as exc:
        error(f"cannot write Promela: {exc}")
        return EXIT_ERRORS
    except OSError as exc:
        error(f"cannot write {path}: {exc.strerror or exc}")
        return EXIT_ERRORS
    print(f"wrote {path} ({len(monitors)} observer(s))")
    return EXIT_OK


def _run_explorer(space, args, deadlock: bool, properties) -> int:
    from runtime.props import describe

    worst = EXIT_OK
    need_full = deadlock or args.aut or args.dot
    if need_full:
        from genom2bip.cli.verify_native import explore_model
        result, view = explore_model(space, args, progress(args))
        print(f"explored: {result.summary()}")
        if result.error is not None:
            worst = EXIT_VIOLATED
            print(f"model error in state {result.error.state}: {result.error.message}")
            print("  trace to the state where it happens:")
            print_trace(result.error.trace, sources=step_sources(space.engine.flat))
            _trace_picture(args, space.engine, result.error.trace, [f"model error: {result.error.message}"])
        if deadlock:
            worst = max(worst, _report_deadlocks(view, result, args))
        if not result.complete and worst == EXIT_OK:
            worst = EXIT_INCONCLUSIVE
        if args.aut or args.dot:
            if not result.complete:
                error("the LTS is not complete (a limit stopped the exploration): not exported")
                worst = max(worst, EXIT_INCONCLUSIVE)
            else:
                worst = max(worst, _export_lts(space, args))
    for item in properties:
        from genom2bip.cli.verify_native import check_property
        verdict = check_property(space, item, args, progress(args))
        print(f"property {describe(item)}")
        head = f"  {verdict.word}"
        stats = f"{verdict.method}, {verdict.states:,} states, {verdict.seconds:.2f} s" if verdict.method else ""
        print(head + (f" ({stats})" if stats else "") + (f": {verdict.note}" if verdict.note else ""))
        if verdict.evidence:
            what = "counterexample" if verdict.evidence == "counterexample" else "witness"
            print(f"  {what} ({len(verdict.trace)} step{'s' if len(verdict.trace) != 1 else ''}):")
            print_trace(verdict.trace, sources=step_sources(space.engine.flat))
            if verdict.loop >= 0:
                print(f"    ... and back to the state after step {verdict.loop}, forever")
            if verdict.holds is False:
                _trace_picture(args, space.engine, verdict.trace, [f"violates {describe(item)}"]
                               + ([f"then back to step {verdict.loop}, forever"] if verdict.loop >= 0 else []))
        if verdict.holds is False or verdict.error:
            worst = max(worst, EXIT_VIOLATED)
        elif verdict.holds is None and worst == EXIT_OK:
            worst = EXIT_INCONCLUSIVE
    return worst


def _report_deadlocks(space, result, args) -> int:
    if not result.deadlocks:
        print("deadlocks: none reachable" + ("" if result.complete else " in the explored part"))
        return EXIT_OK
    n = len(result.deadlocks)
    shortest = "" if args.dfs or getattr(args, "por", False) else ", each with a shortest trace"
    print(f"deadlocks: {n} reachable state{'s' if n != 1 else ''} without enabled interaction{shortest}")
    for k, sid in enumerate(result.deadlocks, 1):
        trace = space.trace_to(sid)
        print(f"deadlock {k} of {n} (state {sid}, {len(trace)} steps):")
        print_trace(trace, sources=step_sources(space.engine.flat))
        print("  state:")
        state = space.concrete(trace)
        print_state(space.engine, state)
        if k == 1:
            _trace_picture(args, space.engine, trace, [f"deadlock {k} of {n}: no interaction enabled"]
                           + moved_atoms(space.engine, space.concrete([]), state))
    return EXIT_VIOLATED


def moved_atoms(engine, initial, state, most: int = 10) -> list[str]:
    """``atom: PLACE`` for the atoms that are not in their initial places (what a deadlock picture shows)."""
    first = engine.describe_state(initial)
    now = engine.describe_state(state)
    moved = [f"{a}: {','.join(v['places']) or '-'}" for a, v in now.items() if v["places"] != first[a]["places"]]
    return moved[:most] + ([f"… and {len(moved) - most} more atoms"] if len(moved) > most else [])


def _trace_picture(args, engine, steps, ending: list[str]) -> None:
    """Write ``--trace-picture`` once, for the first counterexample found."""
    path = getattr(args, "trace_picture", None)
    if not path or getattr(args, "_trace_picture_done", False):
        return
    from runtime.pictures import PictureError, render, sequence

    args._trace_picture_done = True
    try:
        render(sequence(engine, steps, ending, title=f"counterexample, {len(steps)} steps"), path,
               fixed_positions=True)
    except PictureError as exc:
        error(str(exc))
        return
    print(f"wrote {path} (sequence diagram of this trace)")


def _export_lts(space, args) -> int:
    from genom2bip.output import write_file
    from runtime.export.lts import write_aut, write_dot

    for path, writer, what in ((args.aut, write_aut, "Aldebaran LTS"), (args.dot, write_dot, "DOT graph")):
        if not path:
            continue
        try:
            states, transitions = write_file(Path(path), lambda f, writer=writer: writer(space, f))
        except OSError as exc:
            error(f"cannot write {path}: {exc.strerror or exc}")
            return EXIT_ERRORS
        print(f"wrote {path} ({what}: {states:,} states, {transitions:,} transitions)")
    return EXIT_OK
