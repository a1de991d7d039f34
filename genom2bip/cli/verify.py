"""``genom2bip verify MODEL``: deadlocks, properties and LTS/Promela exports, on our explorer or on SPIN.

MODEL is description files or directories (the functional level is built as
``genom2bip generate`` builds it, rules included) or one ``.bip`` file
(``--root`` names the root, default the last compound type).  It prints a
summary line per check and writes the details and traces to a directory
(genom2bip/cli/verify_report.py, docs/output.md).  Exit status:
0 every check passed, 4 a deadlock, a violated property or a model error was
found, 5 a limit stopped the search before an answer, 1 bad input, 2 usage.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from genom2bip.cli.printers import Printer, print_lines, print_trace, step_sources
from genom2bip.cli.verify_report import active, running
from genom2bip.cli.verbs import (
    EXIT_ERRORS, EXIT_INCONCLUSIVE, EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE, EXIT_VIOLATED, Failure,
    add_preprocessor_arguments, add_rules_arguments, description_files, error, load_externs, parse_defines,
    print_diagnostics, verb,
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
    what = parser.add_argument_group("what to check (default: --deadlock, also with --aut/--dot)")
    what.add_argument("--deadlock", action="store_true", help="report every reachable deadlock with a shortest trace")
    what.add_argument("--property", metavar="FILE", action="append", default=[],
                      help="check the properties of FILE (MCL-style; docs/verification/properties.md); may be repeated")
    search = parser.add_argument_group("exploration")
    search.add_argument("--engine", choices=("compiled", "python", "spin", "explore"), default="compiled",
                        help="our explorer compiled to C (default; Python where it cannot be compiled), our explorer "
                             "in Python, or SPIN on the Promela translation ('explore' is 'compiled')")
    search.add_argument("--max-memory", type=int, metavar="MB",
                        help="stop the search past MB megabytes (default: half the machine's memory)")
    search.add_argument("--max-states", type=int, metavar="N", help="stop after N states")
    search.add_argument("--max-depth", type=int, metavar="N", help="do not expand states deeper than N steps")
    search.add_argument("--time-limit", metavar="DURATION",
                        help="clock zones (--timed on a platform): stop the search after DURATION (e.g. 10 min) and "
                             "report the verdicts found and the response times reached so far, as lower bounds")
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
    answer = parser.add_argument_group("the answer (docs/output.md)")
    answer.add_argument("--traces", metavar="DIR",
                        help="write the details (DIR/verify.txt) and each trace (DIR/NAME.txt, DIR/NAME.json) to DIR "
                             "and print a summary line per check; 'terminal' prints everything here as it comes "
                             "(default: out/traces/MODEL, or $GENOM2BIP_TRACES)")
    answer.add_argument("--json", action="store_true",
                        help="print one JSON document: model, platform, checks with verdicts, figures and trace "
                             "files (schema: genom2bip/cli/verify_schema.json)")
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
    from genom2bip.cli.verify_smc import add_arguments as add_smc_arguments
    add_smc_arguments(parser)


# --------------------------------------------------------------------------- loading


def load_model(args: argparse.Namespace):
    """The :class:`~genom2bip.verify.Model` of a .bip file or of descriptions (rules, defines, time options)."""
    from genom2bip.cli.verify_timed import time_settings, warn_untimed
    from genom2bip.generate import GenerateError
    from genom2bip.verify import build_model
    from runtime.diagnostics import DiagnosticError

    try:
        if any(p.endswith(".bip") for p in args.paths):  # one .bip file, or the usage error of a mix
            return build_model(args.paths, root=args.root)
        description_files(args.paths)  # a missing path is named before the options are read
        defines = parse_defines(args.defines)
        model = build_model(args.paths, rules=args.rules, no_rules=args.no_rules, defines=defines,
                            include_dirs=args.include_dirs, name=args.name, root=args.root,
                            time=time_settings(args), report=print_diagnostics)
    except DiagnosticError as exc:
        print(exc.render(), file=sys.stderr)
        raise Failure(EXIT_ERRORS) from None
    except GenerateError as exc:
        error(str(exc))
        raise Failure(EXIT_ERRORS) from None
    warn_untimed(model.package)
    return model


def _check_options(args) -> None:
    for name in ("max_states", "max_depth", "requests", "max_memory"):
        value = getattr(args, name)
        if value is not None and value < 0:
            error(f"--{name.replace('_', '-')} must be >= 0")
            raise Failure(EXIT_USAGE)
    if args.time_limit is not None:
        from genom2bip.durations import parse_duration

        us = parse_duration(args.time_limit)
        if not us:
            error(f"--time-limit: '{args.time_limit}' is not a positive duration (e.g. 30 s, 10 min)")
            raise Failure(EXIT_USAGE)
        args.time_limit_s = us / 1e6
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
    """Build or read the model, run the checks asked for; a summary line per check, the details and traces in files
    (or as they come with ``--traces terminal``, or one JSON document with ``--json``)."""
    from genom2bip.cli.verify_compositional import check_arguments as check_compositional

    _check_options(args)
    check_compositional(args)
    from genom2bip.cli import verify_smc

    if verify_smc.wanted(args):  # statistical: its own lines (runs, estimates, intervals), no traces directory
        return _verify_smc(args, verify_smc.settings(args))
    report = _report(args)
    try:
        with running(report):
            status = _verify(args, report)
    except KeyboardInterrupt:  # a Ctrl-C the search did not take: what is known is said (and written) first
        if report.captured:
            args._interrupted = True
            _finish(report, EXIT_INTERRUPTED, args)
        raise
    except BaseException:
        _spill(report)
        raise
    return _finish(report, status, args)


def _verify(args: argparse.Namespace, report) -> int:
    """Load the model and run every check asked for, printing as they come; the worst exit status."""
    from genom2bip.cli.verify_compositional import run as run_compositional
    from genom2bip.cli.verify_native import search_options
    from runtime.engine import EngineError

    model = load_model(args)
    _describe(report, model, args)
    try:
        model.flat
    except EngineError as exc:
        error(f"{model.title}: {exc}")
        return EXIT_ERRORS
    options, listener = search_options(args), Printer(args)
    from runtime.native.build import tell

    shown = (args.progress or sys.stderr.isatty()) and not args.quiet  # a compile is said where progress is shown
    tell((lambda text: print(f"genom2bip: {text}", file=sys.stderr, flush=True)) if shown else None)
    if args.method == "explore":
        return _explore(model, args, options, listener, EXIT_OK)
    localized = None
    if args.method == "compositional" and args.property:  # every property classified before anything runs
        from genom2bip.cli.verify_localized import read_localizable
        localized = read_localizable(args, model)
    report.line(f"model {model.title}")
    load_externs(args.externs)
    compositional = run_compositional(model, args, options, listener)
    if args.method == "both":
        print("exploration")
        return _explore(model, args, options, listener, compositional)
    kinds = _observer_kinds(args)
    if kinds:
        from genom2bip.cli.verify_localized import observers as localized_observers
        compositional = max(compositional, localized_observers(model, kinds, options, listener))
    if localized is not None:
        from genom2bip.cli.verify_localized import run as run_localized
        return max(compositional, run_localized(localized, model, args, options, listener, compositional))
    return compositional


def _verify_smc(args: argparse.Namespace, smc) -> int:
    """Statistical model checking (genom2bip/cli/verify_smc.py) of the model the arguments name."""
    from genom2bip.cli import verify_smc
    from runtime.engine import EngineError
    from runtime.native.build import tell

    model = load_model(args)
    try:
        model.flat
    except EngineError as exc:
        error(f"{model.title}: {exc}")
        return EXIT_ERRORS
    shown = (args.progress or sys.stderr.isatty()) and not args.quiet  # a compile is said where progress is shown
    tell((lambda text: print(f"genom2bip: {text}", file=sys.stderr, flush=True)) if shown else None)
    load_externs(args.externs)
    return verify_smc.run(model, args, smc)


def _report(args: argparse.Namespace):
    """Where the answer goes (--traces, --json, $GENOM2BIP_TRACES); a directory that cannot take the traces is
    refused before anything runs."""
    import os

    from genom2bip.cli.verify_report import TERMINAL, Report, check_directory, traces_directory
    from genom2bip.generate import system_name

    option = args.traces or os.environ.get("GENOM2BIP_TRACES") or None
    if args.traces == "":
        error("--traces: give a directory, or 'terminal'")
        raise Failure(EXIT_USAGE)
    name = Path(args.paths[0]).stem if args.paths[0].endswith(".bip") else \
        (args.name or "-".join(system_name([p]) for p in args.paths))
    name += "-timed" if getattr(args, "timed", False) else ""  # the main job verifies NDD untimed, then timed
    directory = traces_directory(option, name)
    if directory is not None:
        why = check_directory(directory, _inputs(args))
        if why is not None:
            error(f"--traces {directory}: {why}" if args.traces else
                  f"{why} (the traces' default directory; --traces DIR or --traces terminal chooses another place)")
            raise Failure(EXIT_ERRORS)
    return Report(TERMINAL if directory is None else "files", directory, args.json)


def _inputs(args: argparse.Namespace) -> list[Path]:
    return [Path(p) for p in (*args.paths, *args.property, args.rules) if p]


def _describe(report, model, args: argparse.Namespace) -> None:
    """What the JSON document says of the model: title, root, files, time."""
    from genom2bip.verify import tick_us

    tick = tick_us(model.package)
    report.model = {"title": model.title, "root": model.root, "paths": list(args.paths), "timed": tick is not None,
                    "tick_ms": tick / 1000 if tick else None, "rules": not getattr(args, "no_rules", False)}
    report.platform = _platform_of(model) or (_dedicated() if tick else None)
    report.tick_ms = tick / 1000 if tick else None


def _dedicated() -> str:
    from genom2bip.platform import DEDICATED
    return DEDICATED


def _spill(report) -> None:
    """A run that stops on an error or a second Ctrl-C: the details printed so far are not lost."""
    if report.captured:
        (sys.stderr if report.as_json else sys.stdout).write(report.log.getvalue())


def _finish(report, status: int, args: argparse.Namespace) -> int:
    """The summary (or the JSON document) after the run, and the details and traces written; the exit status."""
    import json

    from genom2bip.cli.verify_report import write_directory
    from genom2bip.output import OutputError

    if not report.captured:
        return status
    if report.directory is not None:
        try:
            write_directory(report, _inputs(args))
        except (OutputError, OSError) as exc:
            error(f"--traces {report.directory}: the details and traces were not written: "
                  f"{getattr(exc, 'strerror', None) or exc}")
            report.directory = None
            status = status or EXIT_ERRORS
    if report.as_json:
        print(json.dumps(report.document(status, bool(getattr(args, "_interrupted", False))), indent=1))
    else:
        for line in report.summary_lines(status):
            print(line)
    return status


def _response_observers(model) -> list:
    """The response-time observers the model was built with."""
    from genom2bip.verify.zones import observers

    return list(observers(model, ("response", "pending")))


def _explore(model, args: argparse.Namespace, options, listener, compositional: int) -> int:
    """``--method explore`` (and the second half of ``both``): one state space for every check asked for."""
    from genom2bip.cli.verify_localized import print_warnings
    from genom2bip.verify import read_properties, state_space
    from runtime.diagnostics import DiagnosticError
    from runtime.engine import EngineError
    from runtime.explore import ExploreError

    try:
        properties, _ = read_properties(model, args.property, print_warnings)
    except DiagnosticError as exc:
        print(exc.render(), file=sys.stderr)
        return EXIT_ERRORS
    observers = _observer_kinds(args)
    responses = bool(getattr(args, "response_times", False))
    # the default check is deadlock freedom: an LTS export explores the whole space anyway, so a deadlock it meets
    # is reported (exit 4); a Promela translation alone explores nothing, it is for SPIN to search
    promela_alone = args.promela and not (args.aut or args.dot)
    deadlock = args.deadlock or not (properties or promela_alone or observers or responses)
    load_externs(args.externs)
    zones = _zones(model, args, options) if observers or responses else None  # the zone explorer, if it takes it
    if responses and not zones and not _response_observers(model):  # no clock at all: no task, no service
        print(f"response times: none to measure ({model.title} has no periodic task and no service)")
        responses = False
    elif responses and not zones:  # response times are the zone explorer's: ticks would print nothing for them
        error("--response-times: response times are measured with clock zones; "
              + ("drop --time-search ticks" if getattr(args, "time_search", None) == "ticks" else
                 "this model is not one clock zones take (see the note above)"))
        raise Failure(EXIT_USAGE)
    if zones:
        from genom2bip.cli.verify_timed import check_timing_zones
        if args.method == "explore":
            active().line(f"model {model.title}")
        from genom2bip.cli.verify_timed import platform_line
        platform_line(model)
        worst, stopped = check_timing_zones(model, observers, responses, options, listener, zones)
        left = (["deadlock"] if deadlock else []) + [f"property {p.name}" for p in properties]
        left += [f"--{k} export" for k in ("aut", "dot", "promela") if getattr(args, k)]
        args._interrupted = stopped == "interrupted"
        if stopped == "interrupted" and left:  # one Ctrl-C stops the whole command, after what was found
            print(f"interrupted: not run: {', '.join(left)}")
            active().not_run += left
        if stopped == "interrupted" or not left:
            return max(compositional, worst)
        observers, responses = set(), False
        compositional = max(compositional, worst)
    try:
        space = state_space(model, options, properties, keep_edges=bool(properties or args.aut or args.dot))
    except (ExploreError, EngineError) as exc:
        error(f"{model.title}: {exc}")
        return EXIT_ERRORS
    if args.promela:
        code = _write_promela(space, properties, args.promela)
        if code != EXIT_OK:
            return code
    if args.method == "explore":
        active().line(f"model {model.title}")
    if args.engine == "spin":
        from genom2bip.cli.verify_spin import run_spin
        return run_spin(space, args, options, listener, deadlock, properties)
    worst = max(compositional, _run_explorer(space, args, options, listener, deadlock, properties))
    if observers and getattr(args, "_interrupted", False):
        print("interrupted: not run: the timing observers")
        active().not_run.append("the timing observers")
    elif observers:
        from genom2bip.cli.verify_timed import check_observers
        worst = max(worst, check_observers(model, observers, space, options, listener))
    return worst


def _zones(model, args, options):
    """Time by clock zones (asked for, or by default on a platform model the zone explorer takes): the zone
    explorer made to tell, which then searches; None for ticks."""
    choice = getattr(args, "time_search", None)
    if choice == "ticks" or (choice is None and not _platform_of(model)):
        return None
    from genom2bip.verify.zones import ZonesUnsupported, explorer
    try:
        return explorer(model, options)
    except ZonesUnsupported as exc:
        if choice == "zones":  # asked for: nothing is explored, so the message does not say it is
            error(f"--time-search zones: clock zones do not take this model ({exc}); try --time-search ticks")
            raise Failure(EXIT_USAGE) from None
        print(f"note: clock zones do not take this model ({exc}): exploring tick by tick")
        return None


def _platform_of(model) -> str | None:
    ann = next((a for a in model.package.annotations if a.name == "timed"), None)
    return ann.arguments.get("platform") if ann is not None else None


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
    active().wrote(path, f"Promela, {len(monitors)} observer(s)")
    return EXIT_OK


def _run_explorer(space, args, options, listener, deadlock: bool, properties) -> int:
    """Deadlocks (and the LTS exports) by one exploration, then each property; print them, the worst status."""
    from genom2bip.verify import Verdict, check_deadlock, check_property, explore

    worst = EXIT_OK
    sources = step_sources(space.engine.flat)
    lts = bool(args.aut or args.dot)
    if deadlock or lts:
        exploration = explore(space, options, listener, lts)
        print(f"explored: {exploration.result.summary()}")
        error_ = exploration.model_error
        if error_ is not None:
            worst = EXIT_VIOLATED
            print(f"model error in state {error_.state}: {error_.message}")
            active().check("model-error", "model error", "error", message=error_.message,
                           how=_figures_in_words(exploration))
            with active().trace("model error", "model-error", error_.trace, "trace"):
                print("  trace to the state where it happens:")
                print_trace(error_.trace.steps, sources=sources)
            _trace_picture(args, space.engine, error_.trace.steps, [f"model error: {error_.message}"])
        if deadlock:
            worst = max(worst, _report_deadlocks(space, check_deadlock(space, options, listener, lts, exploration),
                                                 args, sources))
        if not exploration.result.complete and worst == EXIT_OK:
            worst = EXIT_INCONCLUSIVE
        args._interrupted = exploration.result.stopped_by == "interrupted"
        if lts:
            if not exploration.result.complete:
                error("the LTS is not complete (a limit stopped the exploration): not exported")
                worst = max(worst, EXIT_INCONCLUSIVE)
            else:
                worst = max(worst, _export_lts(space, args))
    for k, item in enumerate(properties):
        if getattr(args, "_interrupted", False):  # one Ctrl-C stops the whole command, after what was found
            print(f"interrupted: not run: {', '.join(f'property {p.name}' for p in properties[k:])}")
            active().not_run += [f"property {p.name}" for p in properties[k:]]
            break
        found = check_property(space, item, options, listener)
        args._interrupted = found.limit == "interrupted"
        print(f"property {found.subject}")
        stats = (f"{found.method}, {found.figures.states:,} states, {found.figures.seconds:.2f} s"
                 if found.method else "")
        print(f"  {found.word}" + (f" ({stats})" if stats else "") + (f": {found.message}" if found.message else ""))
        subject = f"property {found.name or found.subject}"
        active().check("property", subject, found.verdict.value, found, how=stats)
        if found.evidence:
            what = "counterexample" if found.evidence == "counterexample" else "witness"
            n = len(found.trace)
            with active().trace(subject, f"{subject} {what}", found.trace, what):
                print(f"  {what} ({n} step{'s' if n != 1 else ''}):")
                print_trace(found.trace.steps, sources=sources)
                if found.trace.loop is not None:
                    print(f"    ... and back to the state after step {found.trace.loop}, forever")
            if found.verdict is Verdict.VIOLATED:
                _trace_picture(args, space.engine, found.trace.steps, [f"violates {found.subject}"]
                               + ([f"then back to step {found.trace.loop}, forever"]
                                  if found.trace.loop is not None else []))
        if found.verdict in (Verdict.VIOLATED, Verdict.ERROR):
            worst = max(worst, EXIT_VIOLATED)
        elif found.verdict is Verdict.INCONCLUSIVE and worst == EXIT_OK:
            worst = EXIT_INCONCLUSIVE
    return worst


def _report_deadlocks(space, found, args, sources) -> int:
    """Each deadlock with its trace and state (the first one drawn with --trace-picture)."""
    how = _figures_in_words(found)
    if not found.deadlocks:
        print("deadlocks: none reachable" + ("" if found.complete else " in the explored part"))
        active().check("deadlock", "deadlock freedom", found.verdict.value, found, how=how,
                       message="" if found.complete else "none reachable in the explored part")
        return EXIT_OK
    n = len(found.deadlocks)
    shortest = ", each with a shortest trace" if found.shortest else ""
    print(f"deadlocks: {n} reachable state{'s' if n != 1 else ''} without enabled interaction{shortest}")
    active().check("deadlock", "deadlock freedom", found.verdict.value, found, how=how,
                   message=f"{n} reachable deadlock{'s' if n != 1 else ''}")
    for k, d in enumerate(found.deadlocks, 1):
        with active().trace("deadlock freedom", f"deadlock-{k}", d.trace, "deadlock", d.text):
            print(f"deadlock {k} of {n} (state {d.state}, {len(d.trace)} steps):")
            print_trace(d.trace.steps, sources=sources)
            print("  state:")
            print_lines(d.text)
        if k == 1:
            _trace_picture(args, space.engine, d.trace.steps, [f"deadlock {k} of {n}: no interaction enabled"]
                           + d.moved)
    return EXIT_VIOLATED


def _figures_in_words(result) -> str:
    """A search's figures as the summary shows them: states, transitions, time."""
    f = getattr(result, "figures", None)
    if f is None:
        return ""
    moves = f", {f.transitions:,} transitions" if f.transitions is not None else ""
    method = getattr(result, "method", "")
    return f"{method + ', ' if method else ''}{f.states:,} states{moves}, {f.seconds:.2f} s"


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
    active().wrote(path, f"sequence diagram of the first counterexample, {len(steps)} steps")


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
        active().wrote(path, f"{what}: {states:,} states, {transitions:,} transitions")
    return EXIT_OK
