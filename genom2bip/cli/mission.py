"""``genom2bip mission MISSION [--world WORLD]``: run a mission against the generated controller in a simulated world.

Starts the generated package's controller (``--package``, default the
package that holds the mission's components: genom2bip.mission.package)
with its codels and services interface, loads the world
(ir-sim YAML), sends the mission's requests through the client, then prints
the report and writes the trajectory picture and the trace (``--out``);
``--codel-times FILE`` records how long each codel ran, writes it to FILE and
prints it after the report.  ``--view`` serves the live page meanwhile, the
robot drawn over the world.
Exit status 0 when every expectation of the mission is met and real time held (no period missed or overrun, no
codel past its bound), 4 otherwise (the table of runtime/exits.py), 1 when an input cannot be used.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from genom2bip.cli.verbs import EXIT_ERRORS, EXIT_OK, EXIT_USAGE, EXIT_VIOLATED, error, verb


def _port(text: str) -> int:
    """A TCP port, 0 for a free one."""
    if not text.isdigit() or int(text) > 65535:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port (a number from 0 to 65535; 0: a free one)")
    return int(text)


def _arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("mission", metavar="MISSION", help="the mission file (YAML; docs/missions.md)")
    parser.add_argument("--world", metavar="WORLD", help="the world file (ir-sim YAML); default: the mission's")
    parser.add_argument("--package", metavar="DIR",
                        help="the generated package to run (default: the one in a gen/ folder, of the working "
                             "directory or above the mission, that holds the components the mission names)")
    parser.add_argument("--codels", metavar="DIR|MODULE", help="the codels (default: the package's, docs/runtime.md)")
    parser.add_argument("--out", metavar="DIR", default="out",
                        help="where MISSION.png and MISSION.jsonl are written (default: out)")
    parser.add_argument("--live", action="store_true",
                        help="show the simulation in a window as it runs, in real time (needs a display)")
    parser.add_argument("--realtime", action="store_true",
                        help="run the controller in real time (default: as fast as it can, periods kept)")
    parser.add_argument("--view", action="store_true",
                        help="serve the live page (the level, requests, posters, the robot over the world) while "
                             "the mission runs, in real time; its address is printed")
    parser.add_argument("--port", type=_port, default=0, help="the port of --view's page (default: a free one)")
    parser.add_argument("--token-file", metavar="FILE",
                        help="the token every request to the controller must send, in the first line of FILE "
                             "(default: the environment variable GENOM2BIP_TOKEN), as for `python -m PACKAGE run`")
    parser.add_argument("--quiet", action="store_true", help="print only the report")
    parser.add_argument("--json", action="store_true",
                        help="print the report as one JSON document, nothing else (schema: "
                             "genom2bip/cli/mission_schema.json; docs/output.md)")
    parser.add_argument("--codel-times", metavar="FILE",
                        help="record how long each codel runs (calls; longest, p99 and mean CPU and wall time), "
                             "write it to FILE (JSON) and print it after the report")


@verb("mission", help="run a mission (requests, waits, expectations) on the controller in a simulated world",
      arguments=_arguments)
def verb_mission(args: argparse.Namespace) -> int:
    """Read and check the mission, its world, its inputs and its outputs; run it; write the trace, print the report,
    draw the picture."""
    from genom2bip.mission import picture, report
    from genom2bip.mission.inputs import check_inputs
    from genom2bip.mission.outputs import output_problem
    from genom2bip.mission.package import NoPackage, find_package
    from genom2bip.mission.session import load_package, run_mission, write_trace
    from genom2bip.mission.spec import read_mission
    from genom2bip.mission.world import check_world
    from runtime.controller.codel_times import unwritable, write_json
    from runtime.diagnostics import Reporter
    from runtime.services.run import UsageError, token_of

    mission = read_mission(args.mission)
    world = Path(args.world) if args.world else mission.world
    if world is not None and not os.path.lexists(world):
        error(f"{args.world or world}: no such world file")
        return EXIT_ERRORS
    if world is not None:
        check_world(world)
    why = (unwritable(args.codel_times) or output_problem(Path(args.codel_times).parent, [Path(args.codel_times).name])
           if args.codel_times else None)
    if why:
        error(f"--codel-times {args.codel_times}: cannot write it: {why}")
        return EXIT_ERRORS
    if args.live and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        error("--live needs a display (DISPLAY is not set); the run is headless without it")
        return EXIT_ERRORS
    try:
        token = token_of(argparse.Namespace(token=None, token_file=args.token_file))
    except UsageError as exc:
        error(str(exc))
        return EXIT_USAGE
    try:
        package = load_package(args.package or find_package(mission))
    except (FileNotFoundError, ImportError, NoPackage) as exc:
        error(str(exc))
        return EXIT_ERRORS
    reporter = Reporter()
    check_inputs(mission, package.INTERFACE, reporter)
    reporter.raise_if_errors()
    out = Path(args.out)
    trace, png = out / f"{mission.name}.jsonl", out / f"{mission.name}.png"
    why = output_problem(out, [trace.name, png.name])
    if why:  # said before the run: a run lost after the fact cannot be had again
        error(f"--out {args.out}: the mission's trace and picture cannot be written there: {why}")
        return EXIT_ERRORS
    if sys.stderr.isatty() and not (args.quiet or args.json):  # importing the simulator alone takes seconds
        print(f"genom2bip: starting the controller{' and the world' if world is not None else ''} ...",
              file=sys.stderr, flush=True)
    run = run_mission(mission, package, args.codels, world, realtime=args.realtime, live=args.live,
                      log=None if args.quiet or args.json else print, times=bool(args.codel_times),
                      view=args.port if args.view else None, token=token)
    written = []
    try:
        out.mkdir(parents=True, exist_ok=True)
        write_trace(run, trace)  # first: the run's record, before anything that reads it could fail
        written.append(str(trace))
    except OSError as exc:
        _print_report(args, run, written, EXIT_ERRORS)
        error(f"cannot write the trace {trace}: {exc.strerror or exc}")
        return EXIT_ERRORS
    if not args.json:
        print(report.text(run))
    status = EXIT_OK if run.ok else EXIT_VIOLATED
    if run.world is not None:
        try:
            picture.draw(run, png)
            written.insert(0, str(png))
        except OSError as exc:
            _wrote(args, run, written, EXIT_ERRORS)
            error(f"cannot write the picture {png}: {exc.strerror or exc}")
            return EXIT_ERRORS
    if run.codel_times is not None:
        try:
            write_json(args.codel_times, run.codel_times)
        except OSError as exc:
            _wrote(args, run, written, EXIT_ERRORS)
            error(f"--codel-times {args.codel_times}: cannot write it: {exc.strerror or exc}")
            return EXIT_ERRORS
        written.append(args.codel_times)
    _wrote(args, run, written, status)
    return status


def _print_report(args: argparse.Namespace, run, written: list[str], status: int) -> None:
    """The report, as text or (``--json``) as one document."""
    from genom2bip.mission import report

    if args.json:
        import json
        print(json.dumps(report.document(run, written, status), indent=1))
    else:
        print(report.text(run))


def _wrote(args: argparse.Namespace, run, written: list[str], status: int) -> None:
    """The files written, after the report (in the document with ``--json``)."""
    if args.json:
        _print_report(args, run, written, status)
    else:
        print("  wrote " + ", ".join(written))
