"""Step records of a run, to a JSON-lines file and/or a readable console trace.

A tracer has three hooks the run loop calls: ``start(engine, state)``,
``step(n, enabled, chosen, values, new_state)`` and ``finish(summary)``.
JSON lines: one ``{"initial": ...}`` record, one record per step
(``step``, ``enabled`` labels, ``chosen`` label, ``index``, ``ports``,
``values`` received by each atom port), then ``{"summary": ...}``.
"""
from __future__ import annotations

import json
import sys
from dataclasses import asdict, dataclass, field
from typing import Any, TextIO


@dataclass
class StepRecord:
    """One step of a run, as traces store it."""

    step: int
    enabled: list[str]
    chosen: str
    index: int
    ports: list[str]
    values: dict[str, dict[str, Any]] = field(default_factory=dict)


def record(n: int, enabled, chosen, values) -> StepRecord:
    return StepRecord(n, [i.label for i in enabled], chosen.label, chosen.index, list(chosen.ports), values)


class Tracer:
    """Does nothing; subclasses override what they need."""

    def start(self, engine, state) -> None:
        self.engine = engine

    def step(self, n: int, enabled, chosen, values, state) -> None:
        pass

    def finish(self, summary) -> None:
        pass


class MemoryTracer(Tracer):
    """Keeps the records in a list (for tests and the API)."""

    def __init__(self) -> None:
        self.records: list[StepRecord] = []
        self.summary = None

    def step(self, n, enabled, chosen, values, state) -> None:
        self.records.append(record(n, enabled, chosen, values))

    def finish(self, summary) -> None:
        self.summary = summary

    @property
    def labels(self) -> list[str]:
        return [r.chosen for r in self.records]


class JsonlTracer(Tracer):
    """Writes every record as one JSON object per line."""

    def __init__(self, path_or_file) -> None:
        self.own = isinstance(path_or_file, (str, bytes)) or hasattr(path_or_file, "__fspath__")
        self.file: TextIO = open(path_or_file, "w", encoding="utf-8") if self.own else path_or_file

    def _write(self, obj) -> None:
        self.file.write(json.dumps(obj, default=repr) + "\n")

    def start(self, engine, state) -> None:
        self.engine = engine
        self._write({"initial": engine.describe_state(state), "model": engine.package.name, "root": engine.root})

    def step(self, n, enabled, chosen, values, state) -> None:
        self._write(asdict(record(n, enabled, chosen, values)))

    def finish(self, summary) -> None:
        end = {"steps": summary.steps, "outcome": summary.outcome, "message": summary.message}
        if summary.state is not None and hasattr(self, "engine"):
            end["state"] = self.engine.describe_state(summary.state)
        self._write({"summary": end})
        if self.own:
            self.file.close()
        else:
            self.file.flush()


#: Columns a step's line may take: the values and the list of alternatives are cut to fit (``--trace`` has all).
WIDTH = 120


def _cut(text: str, room: int) -> str:
    return text if len(text) <= room else text[:max(0, room - 3)] + "..."


class ConsoleTracer(Tracer):
    """``[   3] label  x=1`` per step, the enabled ones when there is a choice, the state at a deadlock.

    A line stays within :data:`WIDTH` columns: long values are cut with ``...``, and the alternatives are only
    counted when their labels would not fit (a level of five modules has thirty); ``--trace FILE`` keeps them all.
    """

    def __init__(self, stream: TextIO | None = None, show_enabled: bool = True) -> None:
        self.stream = stream or sys.stdout
        self.show_enabled = show_enabled

    def step(self, n, enabled, chosen, values, state) -> None:
        data = "; ".join(f"{port}({', '.join(f'{k}={v!r}' for k, v in vals.items())})"
                         for port, vals in values.items() if vals)
        line = f"[{n:5d}] {chosen.label}"
        if data:
            line += "  " + _cut(data, max(20, WIDTH - len(line) - 24))
        if self.show_enabled and len(enabled) > 1:
            every = f"    (of {len(enabled)}: {', '.join(i.label for i in enabled)})"
            line += every if len(line) + len(every) <= WIDTH else f"    (1 of {len(enabled)} enabled)"
        print(line, file=self.stream)

    def finish(self, summary) -> None:
        if summary.outcome == "deadlock" and summary.state is not None and hasattr(self, "engine"):
            print("deadlock state:", file=self.stream)
            for line in self.engine.format_state(summary.state).splitlines():
                print(f"  {line}", file=self.stream)


class MultiTracer(Tracer):
    """Sends every hook to several tracers."""

    def __init__(self, *tracers: Tracer) -> None:
        self.tracers = [t for t in tracers if t is not None]

    def start(self, engine, state) -> None:
        for t in self.tracers:
            t.start(engine, state)

    def step(self, *args) -> None:
        for t in self.tracers:
            t.step(*args)

    def finish(self, summary) -> None:
        for t in self.tracers:
            t.finish(summary)
