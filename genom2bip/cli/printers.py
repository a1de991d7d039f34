"""Traces, states and progress as ``verify`` and its engines print them; :class:`Printer` is the verification
API's listener on a terminal."""
from __future__ import annotations

import sys

from genom2bip.verify.options import Listener


def print_trace(steps, indent: str = "    ", sources: dict[str, str] | None = None) -> None:
    """One line per step; with ``sources`` (:func:`step_sources`), each names the description line it comes from."""
    if not steps:
        print(f"{indent}(the initial state)")
    where = sources or {}
    for n, step in enumerate(steps, 1):
        source = where.get(getattr(step, "label", str(step)))
        print(f"{indent}{n:4d}  {step}" + (f"    ({source})" if source else ""))


def step_sources(flat) -> dict[str, str]:
    """Interaction label -> ``file:line:column`` of the service, codel or task it models (``@source``)."""
    from runtime.model import source_of

    out: dict[str, str] = {}
    for fc in flat.connectors:
        source = source_of(fc.instance.annotations)
        if source and fc.label not in out:
            out[fc.label] = source
    return out


def print_lines(text: str, indent: str = "    ") -> None:
    for line in text.splitlines():
        print(f"{indent}{line}")


def print_state(engine, state, indent: str = "    ") -> None:
    print_lines(engine.format_state(state), indent)


def progress(args):
    """The progress line of a search, as ``--progress`` / ``--quiet`` ask."""
    from runtime.explore import Progress
    return Progress(force=args.progress, enabled=not args.quiet)


class Printer(Listener):
    """What a check says while it runs, printed: progress on stderr, notes, phases and rounds on stdout."""

    def __init__(self, args) -> None:
        self.args = args
        self.told: set[str] = set()  # the observers whose violation was printed as soon as found

    def found(self, result) -> None:
        """A timing observer's violation, printed with its trace as soon as the search finds it."""
        from genom2bip.cli.verify_timed import print_zone_verdict

        print_zone_verdict(result, early=True)
        self.told.add(result.observer)

    def so_far(self, text: str) -> None:
        print(f"so far: {text}", file=sys.stderr, flush=True)

    def progress(self):
        return progress(self.args)

    def note(self, text: str) -> None:
        print(f"note: {text}")

    def unbounded(self, max_bytes: int, bounds: str = "--max-states or --max-depth") -> None:
        """On a terminal, a search given no bound says which one it has and how to stop it."""
        if self._shown():
            size = f"{max_bytes / 2**30:.1f} GB" if max_bytes >= 2**30 else f"{max_bytes / 2**20:.0f} MB"
            print(f"searching with no {bounds}: until complete or {size} "
                  "(--max-memory); Ctrl-C stops and reports what was explored", file=sys.stderr)

    def _shown(self) -> bool:
        """Progress is shown: on a terminal, or asked for with --progress, and not --quiet."""
        return bool((self.args.progress or sys.stderr.isatty()) and not self.args.quiet)

    def aside(self, line: str) -> None:
        """With the details going to a file, a step of a long check is still said as it ends, on stderr."""
        from genom2bip.cli.verify_report import active

        if active().captured and self._shown():
            print(f"genom2bip: {line.strip()}", file=sys.stderr, flush=True)

    def phase(self, line: str) -> None:
        print(f"  {line}", flush=True)
        self.aside(line)

    def round(self, number: int, r) -> None:
        """One line per localization round: kept atoms, states, time, outcome, replay."""
        what = "every atom kept (the exact search)" if r.kept == r.atoms else \
            f"{r.kept} of {r.atoms} atoms kept, {r.chaos} free"
        replayed = "replayed on the model" if r.outcome in ("violated", "run found") else "not replayed"
        tail = f", {replayed} ({r.concrete_states:,} states searched)" if r.concrete_states else ""
        line = f"round {number}: {what}: {r.states:,} states, {r.seconds:.2f} s: {r.outcome}{tail}"
        print(f"  {line}", flush=True)
        self.aside(line)
