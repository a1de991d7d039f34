"""``verify --timed``: build the model with symbolic time and check its observers (overruns, latencies).

Each observer of the timed model (an atom whose type is annotated
``@observer``: the period observer of every periodic task, the latency
observers of the observer file) is checked as ``invariant not (ATOM @ ERROR)``
by the compiled explorer (the Python one with ``--engine python``, or where
the C step does not take the model, with a note); a violation is printed with a shortest trace whose steps
carry their time (ticks times the model's resolution, ``@timed(tick_us=...)``).
"""
from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

from genom2bip.cli.verbs import EXIT_ERRORS, Failure, error, print_diagnostics
from runtime.diagnostics import Reporter

EXIT_OK, EXIT_VIOLATED, EXIT_INCONCLUSIVE = 0, 4, 5


def add_time_arguments(parser: argparse.ArgumentParser, verify: bool = False) -> None:
    """--timed and what it takes: resolution, default WCET, observer file (and, for verify, what to check)."""
    time = parser.add_argument_group("symbolic time (docs/verification.md, Time)")
    time.add_argument("--timed", action="store_true",
                      help="add ticks, clocks, codel WCETs, a period observer per periodic task and the observers")
    time.add_argument("--tick", metavar="DURATION",
                      help="tick resolution (default: the gcd of periods, WCETs and observer bounds), e.g. 5ms")
    time.add_argument("--default-wcet", metavar="DURATION",
                      help="WCET of a codel that declares none (default: 0, with a warning naming it)")
    time.add_argument("--observers", metavar="FILE",
                      help="latency observers (YAML); default: observers.yaml in the directory given")
    if not verify:
        time.add_argument("--monitor", action="store_true",
                          help="add the observers without ticks: the controller measures them in real time "
                               "(docs/runtime.md, Online monitoring)")
    if verify:
        time.add_argument("--schedulability", action="store_true",
                          help="check the period observers: is an overrun of each periodic task reachable?")


def _duration(text: str | None, option: str) -> int | None:
    from genom2bip.observers import parse_duration

    if text is None:
        return None
    value = parse_duration(text)
    if value is None:
        error(f"--{option}: '{text}' is not a duration (e.g. 10ms, 1s, 500us)")
        raise Failure(2)
    return value


def observers_file(args: argparse.Namespace) -> Path | None:
    """``--observers FILE``; else ``observers.yaml`` in the directory of descriptions given."""
    if getattr(args, "observers", None):
        return Path(args.observers)
    first = Path(args.paths[0])
    default = first / "observers.yaml"
    return default if first.is_dir() and default.is_file() else None


def time_options(args: argparse.Namespace, description):
    """The TimeOptions of the command line (None without --timed); prints problems and fails on errors."""
    from genom2bip.build.timed import DEFAULT_WCET_US, TimeOptions
    from genom2bip.observers import load_observers

    timed, monitor = getattr(args, "timed", False), getattr(args, "monitor", False)
    if timed and monitor:
        error("--timed and --monitor exclude each other: a timed model is verified, a monitored one runs")
        raise Failure(2)
    if timed and getattr(args, "engine", "explore") == "spin":
        error("the observers of --timed are checked by our explorer: drop --engine spin")
        raise Failure(2)
    if not (timed or monitor):
        if getattr(args, "schedulability", False) or getattr(args, "observers", None):
            error("--schedulability and --observers need --timed" + ("" if hasattr(args, "schedulability")
                                                                     else " or --monitor"))
            raise Failure(2)
        return None
    tick = _duration(args.tick, "tick")
    if tick is not None and tick <= 0:
        error("--tick must be positive")
        raise Failure(2)
    default = _duration(args.default_wcet, "default-wcet")
    latencies = []
    path = observers_file(args)
    if path is not None:
        if not path.is_file():
            error(f"{path}: no such observer file")
            raise Failure(EXIT_ERRORS)
        reporter = Reporter()
        latencies = load_observers(path, description, reporter)
        if reporter.diagnostics:
            print_diagnostics(reporter.diagnostics, reporter.sources)
        if reporter.has_errors:
            raise Failure(EXIT_ERRORS)
    return TimeOptions(tick, DEFAULT_WCET_US if default is None else default, latencies, ticks=timed)


def warn_untimed(package) -> None:
    """The warning that names the codels without a WCET (they take the default)."""
    ann = next((a for a in package.annotations if a.name == "timed"), None)
    if ann is not None and ann.arguments.get("untimed"):
        print(f"genom2bip: warning: codels without wcet take {int(ann.arguments['default_wcet_us']) / 1000:g} ms: "
              f"{ann.arguments['untimed'].replace(',', ', ')}", file=sys.stderr)


@dataclass
class ObserverAtom:
    path: str
    kind: str  # "overrun" or "latency"
    bound: int  # ticks


def observer_atoms(package, root: str) -> list[ObserverAtom]:
    """Every instance of an ``@observer`` atom type under the root, by path."""
    out: list[ObserverAtom] = []

    def walk(type_name: str, prefix: str) -> None:
        compound = package.compound_type(type_name)
        if compound is None:
            return
        for c in compound.components:
            path = f"{prefix}.{c.name}" if prefix else c.name
            atom = package.atom_type(c.type)
            if atom is None:
                walk(c.type, path)
                continue
            ann = next((a for a in atom.annotations if a.name == "observer"), None)
            if ann is not None:
                bound = c.args[0].value if c.args and hasattr(c.args[0], "value") else 0
                out.append(ObserverAtom(path, ann.arguments.get("kind", "?"), int(bound)))

    walk(root.split("(")[0], "")
    return out


def tick_us(package) -> int | None:
    ann = next((a for a in package.annotations if a.name == "timed"), None)
    return int(ann.arguments["tick_us"]) if ann else None


def timed_trace(steps, tick: int | None, indent: str = "    ") -> None:
    """A trace whose steps carry their time; consecutive ticks are folded into one line."""
    from genom2bip.build.timed import TICK

    now = 0
    n = 0
    run = 0

    def show(t: int) -> str:
        return f"{t * tick / 1000:g} ms" if tick else f"{t} ticks"

    def flush() -> None:
        nonlocal run
        if run:
            print(
                f"{indent}{'':4}  [{show(now - run)} .. {show(now)}] time passes ({run} tick{'s' if run > 1 else ''})"
            )
            run = 0

    for step in steps:
        n += 1
        if step.label == TICK:
            now += 1
            run += 1
            continue
        flush()
        print(f"{indent}{n:4d}  [{show(now)}] {step}")
    flush()
    if not steps:
        print(f"{indent}(the initial state)")


def check_observers(space, flat, package, root: str, kinds: set[str], progress, args=None, decide=None) -> int:
    """Check ``invariant not (OBS @ ERROR)`` for every observer of the given kinds; print verdicts and traces.

    ``decide(item)`` gives each verdict (localization, with ``--method compositional``); else, with the command
    line's ``args``, the compiled explorer (``--engine``, ``--max-states``, ``--por``, ...), else the Python checker.
    """
    from genom2bip.cli.verify_native import check_property
    from runtime.props import check, read_property_text

    tick = tick_us(package)
    atoms = [a for a in observer_atoms(package, root) if a.kind in kinds]
    if not atoms:
        print("observers: none in the model" + ("" if tick else " (build it with --timed)"))
        return EXIT_OK
    if tick:
        print(f"time: one tick is {tick / 1000:g} ms")
    worst = EXIT_OK
    for a in atoms:
        item = read_property_text(f"invariant not ({a.path} @ ERROR)", flat)
        what = ("overrun" if a.kind == "overrun" else "violation")
        limit = f"{a.bound * tick / 1000:g} ms" if tick else f"{a.bound} ticks"
        subject = (f"period of {a.path.rsplit('.', 1)[0]} ({limit})" if a.kind == "overrun"
                   else f"latency {a.path} (within {limit})")
        if decide is not None:
            print(f"{subject}:", flush=True)
            verdict = decide(item)
        elif args is None:
            verdict = check(space, item, progress)
        else:
            verdict = check_property(space, item, args, progress)
        how = f"{verdict.method}, " if decide is not None and verdict.method else ""
        if verdict.holds is True:
            print(f"{subject}: no {what} reachable ({how}{verdict.states:,} states, {verdict.seconds:.2f} s)")
        elif verdict.holds is False:
            print(f"{subject}: {what} reachable ({how}{len(verdict.trace)} steps):")
            timed_trace(verdict.trace, tick)
            worst = EXIT_VIOLATED
        else:
            print(f"{subject}: inconclusive ({verdict.error or verdict.note})")
            worst = max(worst, EXIT_VIOLATED if verdict.error else EXIT_INCONCLUSIVE)
    return worst
