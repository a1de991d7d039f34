"""``verify --timed``: the options of symbolic time, and the timing observers' verdicts printed.

Each observer of the timed model (the period observer of every periodic
task, the latency observers of the observer file) is checked by the
verification API (genom2bip/verify/timing.py); a violation is printed with a
shortest trace whose steps carry their time (ticks times the model's
resolution, ``@timed(tick_us=...)``).
"""
from __future__ import annotations

import argparse
import sys

from genom2bip.cli.verbs import EXIT_USAGE, Failure, error
from genom2bip.cli.verify_report import active

EXIT_OK, EXIT_VIOLATED, EXIT_INCONCLUSIVE = 0, 4, 5


def add_time_arguments(parser: argparse.ArgumentParser, verify: bool = False) -> None:
    """--timed and what it takes: resolution, default WCET, observer file (and, for verify, what to check)."""
    time = parser.add_argument_group("symbolic time (docs/verification/time.md)")
    time.add_argument("--timed", action="store_true",
                      help="add ticks, clocks, codel WCETs, a period observer per periodic task and the observers")
    time.add_argument("--tick", metavar="DURATION",
                      help="tick resolution (default: the gcd of periods, WCETs and observer bounds), e.g. 5ms")
    time.add_argument("--default-wcet", metavar="DURATION",
                      help="WCET of a codel that declares none (default: 0, with a warning naming it)")
    time.add_argument("--observers", metavar="FILE",
                      help="latency observers (YAML); default: observers.yaml in the directory given")
    time.add_argument("--client", metavar="MISSION",
                      help="a mission file whose steps are the environment: its requests in order, each once the "
                           "previous one is accepted, started or over (default: any request, once per period)")
    time.add_argument("--platform", metavar="FILE",
                      help="the computer: cores, scheduling policy, codel execution intervals, task offsets (YAML; "
                           "docs/verification/platform.md); default: a core per task, codels take their WCET")
    if not verify:
        time.add_argument("--monitor", action="store_true",
                          help="add the observers without ticks: the controller measures them in real time "
                               "(docs/runtime.md, Online monitoring)")
    if verify:
        time.add_argument("--schedulability", action="store_true",
                          help="check the period observers: is an overrun of each periodic task reachable?")
    time.add_argument("--response-times", action="store_true",
                      help="the largest response time of each periodic task (release to end of cycle) and of each "
                           "service (request to final report), each with a trace that reaches it" if verify else
                           "add a response-time observer per periodic task and per service, which "
                           "'verify MODEL.bip --timed --response-times' measures")
    time.add_argument("--no-exceptions", action="store_true",
                      help="codels take their declared yields only: no exception is explored (timing as the "
                           "GenoM3 templates model it)")
    if verify:
        time.add_argument("--time-search", choices=("zones", "ticks"),
                          help="explore time with clock zones (default on a platform) or tick by tick")


def _duration(text: str | None, option: str) -> int | None:
    from genom2bip.durations import parse_duration

    if text is None:
        return None
    value = parse_duration(text)
    if value is None:
        error(f"--{option}: '{text}' is not a duration (e.g. 10ms, 1s, 500us)")
        raise Failure(EXIT_USAGE)
    return value


def time_settings(args: argparse.Namespace):
    """The :class:`~genom2bip.loading.TimeSettings` of the command line (None without --timed or --monitor)."""
    from genom2bip.loading import TimeSettings

    timed, monitor = getattr(args, "timed", False), getattr(args, "monitor", False)
    if timed and monitor:
        error("--timed and --monitor exclude each other: a timed model is verified, a monitored one runs")
        raise Failure(EXIT_USAGE)
    if timed and getattr(args, "engine", "explore") == "spin":
        error("the observers of --timed are checked by our explorer: drop --engine spin")
        raise Failure(EXIT_USAGE)
    for option in ("platform", "client", "response_times", "time_search", "no_exceptions"):
        if getattr(args, option, None) and not timed:
            error(f"--{option.replace('_', '-')} needs --timed")
            raise Failure(EXIT_USAGE)
    if not (timed or monitor):
        if getattr(args, "schedulability", False) or getattr(args, "observers", None):
            error("--schedulability and --observers need --timed" + ("" if hasattr(args, "schedulability")
                                                                     else " or --monitor"))
            raise Failure(EXIT_USAGE)
        return None
    tick = _duration(args.tick, "tick")
    if tick is not None and tick <= 0:
        error("--tick must be positive")
        raise Failure(EXIT_USAGE)
    return TimeSettings(ticks=timed, tick_us=tick, default_wcet_us=_duration(args.default_wcet, "default-wcet"),
                        observers=args.observers, platform=getattr(args, "platform", None),
                        client=getattr(args, "client", None), responses=bool(getattr(args, "response_times", False)),
                        exceptions=not getattr(args, "no_exceptions", False))


def warn_untimed(package) -> None:
    """The warning that names the codels without a WCET (they take the default)."""
    from genom2bip.verify.model import untimed_codels

    default, codels = untimed_codels(package)
    if codels:
        print(f"genom2bip: warning: codels without wcet take {default / 1000:g} ms: {', '.join(codels)}",
              file=sys.stderr)


def timed_trace(trace, indent: str = "    ") -> None:
    """A trace whose steps carry their time; consecutive ticks are folded into one line."""
    from genom2bip.build.timed import TICK

    tick = trace.tick_us

    def show(t: int) -> str:
        return f"{t * tick / 1000:g} ms" if tick else f"{t} ticks"

    def passes(run: int, now: int) -> None:
        if run:
            ticks = f"{run} tick{'s' if run > 1 else ''}"
            print(f"{indent}{'':4}  [{show(now - run)} .. {show(now)}] time passes ({ticks})")

    run = 0
    for n, (step, now) in enumerate(zip(trace.steps, trace.ticks), 1):
        if step.label == TICK:
            run += 1
            continue
        passes(run, now)
        run = 0
        print(f"{indent}{n:4d}  [{show(now)}] {step}")
    passes(run, trace.ticks[-1] if trace.ticks else 0)
    if not trace.steps:
        print(f"{indent}(the initial state)")


def check_observers(model, kinds, space, options, listener, localized: bool = False) -> int:
    """Check every observer of the given kinds, print each verdict as it comes (a violation with its timed trace);
    the worst exit status.  ``localized``: by localization (``--method compositional``), else by the explorer."""
    from genom2bip.verify import Verdict, check_observer, check_observer_localized, observers, tick_us
    from genom2bip.verify.results import timed
    from genom2bip.verify.timing import subject

    tick = tick_us(model.package)
    atoms = observers(model, kinds)
    if not atoms:
        print("observers: none in the model" + ("" if tick else " (build it with --timed)"))
        return EXIT_OK
    if tick:
        platform_line(model)
        active().line(f"time: one tick is {tick / 1000:g} ms")
    worst = EXIT_OK
    for atom in atoms:
        if localized:
            print(f"{subject(atom, tick)}:", flush=True)
            found = check_observer_localized(model, atom, options, listener)
        else:
            found = check_observer(model, atom, space, options, listener)
        what = "overrun" if atom.kind == "overrun" else "violation"
        how = f"{found.method}, " if localized and found.method else ""
        figures = f"{how}{found.figures.states:,} states, {found.figures.seconds:.2f} s"
        if found.verdict is Verdict.HOLDS:
            print(f"{found.subject}: no {what} reachable ({figures})")
            active().check("observer", found.subject, "holds", found, how=figures, message=f"no {what} reachable")
        elif found.verdict is Verdict.VIOLATED:
            trace = found.trace if found.trace is not None else timed([], tick)
            active().check("observer", found.subject, "violated", found, how=figures, message=f"{what} reachable")
            with active().trace(found.subject, f"{what} {found.subject}", trace, "counterexample"):
                print(f"{found.subject}: {what} reachable ({how}{len(trace)} steps):")
                timed_trace(trace)
            worst = EXIT_VIOLATED
        else:
            print(f"{found.subject}: inconclusive ({found.message})")
            active().check("observer", found.subject, found.verdict.value, found, how=figures)
            worst = max(worst, EXIT_VIOLATED if found.verdict is Verdict.ERROR else EXIT_INCONCLUSIVE)
    return worst


def print_zone_verdict(found, early: bool = False) -> int:
    """One observer's verdict from a zone search (a violation with its timed trace); its exit status.  ``early``:
    a violation found while the search goes on (when is said)."""
    from genom2bip.verify import Verdict

    what = "overrun" if found.kind == "overrun" else "violation"
    figures = f"{found.method}, {found.figures.states:,} symbolic states, {found.figures.seconds:.2f} s"
    if found.verdict is Verdict.HOLDS:
        said = found.message or f"no {what} reachable"  # a task with nothing to run says why without a search
        print(f"{found.subject}: {said} ({figures})")
        active().check("observer", found.subject, "holds", found, message=said)
        return EXIT_OK
    if found.verdict is Verdict.VIOLATED:
        when = (f"found after {found.figures.states:,} symbolic states, {found.figures.seconds:.1f} s; "
                if early else "")
        if early and active().captured:  # the details come at the end: the terminal hears of it now
            print(f"genom2bip: found: {found.subject}: {what} reachable ({when.rstrip('; ')})", file=sys.stderr)
        if not early:
            active().check("observer", found.subject, "violated", found, message=f"{what} reachable")
        with active().trace(found.subject, f"{what} {found.subject}", found.trace, "counterexample"):
            print(f"{found.subject}: {what} reachable" + (f" ({when}{len(found.trace)} steps):" if found.trace else
                                                          f" ({when}{found.message})"))
            if found.trace is not None:
                timed_trace(found.trace)
        sys.stdout.flush()
        return EXIT_VIOLATED
    why = _stopped_by(found.limit or found.message)
    print(f"{found.subject}: inconclusive ({why})")
    active().check("observer", found.subject, "inconclusive", found, message=why)
    return EXIT_INCONCLUSIVE


#: Why a search stopped early, in words.
STOPPED = {"interrupted": "interrupted by Ctrl-C", "time-limit": "past --time-limit", "max-states": "at --max-states",
           "max-memory": "at --max-memory"}


def _stopped_by(limit: str) -> str:
    return STOPPED.get(limit, limit)


def check_timing_zones(model, kinds, responses: bool, options, listener, z=None) -> tuple[int, str]:
    """The observers of ``kinds`` and, with ``responses``, the response times, by one zone exploration (``z``: the
    zone explorer, if made already); printed as the tick explorer prints verdicts (a violation as soon as found,
    when the listener prints it), the response times as a table with a trace each; the worst exit status, and why
    the search stopped early ("" if it did not, or because every verdict was known)."""
    from genom2bip.verify import Verdict, tick_us
    from genom2bip.verify.zones import ResponseResult, check_timing

    tick = tick_us(model.package)
    if tick:
        active().line(f"time: one tick is {tick / 1000:g} ms; explored with clock zones")
    results = check_timing(model, kinds, responses, options, listener, z)
    if results and active().captured:
        f = results[0]
        active().header.append(f"one search by clock zones for every check below ({f.method}, {f.figures.states:,} "
                               f"symbolic states, {f.figures.seconds:.2f} s)")
    told = getattr(listener, "told", set())
    limit = next((r.limit for r in results if r.verdict is Verdict.INCONCLUSIVE and r.limit), "")
    if limit:
        states = results[0].figures
        print(f"search stopped ({_stopped_by(limit)}) after {states.states:,} symbolic states, {states.seconds:.2f} s: "
              "the verdicts known so far, the response times reached so far (lower bounds)")
    worst = EXIT_OK
    for found in results:
        if isinstance(found, ResponseResult):
            continue
        if found.observer in told and found.verdict is Verdict.VIOLATED:
            what = f"{'overrun' if found.kind == 'overrun' else 'violation'} reachable"
            print(f"{found.subject}: {what} (trace above)")
            active().check("observer", found.subject, "violated", found, message=what)
            worst = _worse(worst, EXIT_VIOLATED)
            continue
        worst = _worse(worst, print_zone_verdict(found))
    times = [r for r in results if isinstance(r, ResponseResult)]
    if responses and not times:
        print("response times: the model has no response-time observer (a .bip carries them when generated with "
              "--timed --response-times)")
    if times:
        print(f"response times ({times[0].method}, {times[0].figures.states:,} symbolic states, "
              f"{times[0].figures.seconds:.2f} s):")
        width = max(len(r.owner) for r in times)
        for r in times:
            owner = r.owner
            period = f"  (period {r.ms(r.period_ticks):g} ms)" if r.period_ticks else ""
            print(f"  {owner:<{width}}  {_response_value(r)}{period}")
        figures = f"{times[0].method}, {times[0].figures.states:,} symbolic states, {times[0].figures.seconds:.2f} s"
        for r in times:
            _record_response(r, figures)
        for r in times:
            owner = r.owner
            if r.trace is not None:
                what = "lasso" if r.trace.loop is not None else "trace"
                with active().trace(f"response time of {owner}", f"response {owner}", r.trace, what):
                    print(f"{owner}: {_response_value(r)} ({len(r.trace)} steps):")
                    timed_trace(r.trace)
                    if r.trace.loop is not None:
                        print(f"    ... and back to the state after step {r.trace.loop}, forever")
            elif r.message and r.message != _response_value(r) and (r.verdict is not Verdict.INCONCLUSIVE
                                                                     or r.no_lasso):  # not a limit's lower bound
                print(f"{owner}: {r.message}")
        if any(r.verdict is Verdict.INCONCLUSIVE for r in times):
            worst = _worse(worst, EXIT_INCONCLUSIVE)
    return worst, limit


def _record_response(r, figures: str) -> None:  # noqa: ARG001 - the figures are the search's, said once
    """A response time's summary line: its value in words, the period beside a task's."""
    from genom2bip.verify.zones import response_value

    value = response_value(r)
    word = f"{value:g} ms" if isinstance(value, float | int) else _SHORT.get(value, value)
    period = f"period {r.ms(r.period_ticks):g} ms" if r.period_ticks else ""
    full = _response_value(r)
    message = "" if full == word or full.startswith(f"{word} ") and r.verdict.value == "holds" else full
    if word == "until stopped":
        message = message.removeprefix("runs until stopped: ")
    active().check("response", f"response time of {r.owner}", r.verdict.value, r, how=period, message=message,
                   value=word, value_ms=r.value_ms if isinstance(value, float | int) else None)


#: A response time without a number, in the summary's first column.
_SHORT = {"unbounded": "no bound", "until stopped": "until stopped", "inconclusive": "inconclusive",
          "bounded, not measured": "bounded", "never requested": "never requested"}


def _worse(a: int, b: int) -> int:
    """The exit status of two verdicts: a violation found is an answer, whatever stayed inconclusive beside it."""
    return EXIT_VIOLATED if EXIT_VIOLATED in (a, b) else max(a, b)


def _response_value(r) -> str:
    """A response time in words: ``40 ms``, ``no bound``, ``more than 200 ms`` (the campaign's value, worded)."""
    from genom2bip.verify import Verdict
    from genom2bip.verify.zones import ABOVE_CAP, NO_LASSO, UNTIL_STOPPED, response_value

    if r.verdict is Verdict.INCONCLUSIVE and r.value_ticks is not None:  # reached so far: a lower bound
        return f"≥ {r.value_ms:g} ms so far ({_stopped_by(r.limit)})"
    value = response_value(r)
    if isinstance(value, float | int):
        return f"{value:g} ms"
    if r.no_lasso:  # the search ended: no limit to name
        return NO_LASSO
    if r.verdict is Verdict.INCONCLUSIVE and r.message == ABOVE_CAP:
        return f"more than {r.ms(r.cap_ticks):g} ms so far ({_stopped_by(r.limit)})"
    return {"inconclusive": f"inconclusive ({_stopped_by(r.limit)})",
            "unbounded": "no bound: a request can wait for ever",
            "until stopped": r.message if r.keeps_running else UNTIL_STOPPED,
            "bounded, not measured": "every request ends (not measured: its codels can cycle)"}.get(value, value)


def platform_line(model) -> None:
    """What the tasks of a timed model run on, in one line (a timed model without --platform says so too)."""
    ann = next((a for a in model.package.annotations if a.name == "timed"), None)
    if ann is None:
        return
    from genom2bip.platform import DEDICATED
    active().line(f"platform: {ann.arguments.get('platform') or DEDICATED}")
