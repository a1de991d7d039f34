"""Extern ports at run time: events pushed from outside the model, queued per port, taken as Verimag's engine does.

An ``extern port T p(x) as "Name" policy`` fires its atom's transition on
``p`` when an event is pending and the atom is *waiting* on ``p`` (a
transition on ``p`` is enabled at the current state): the guard reads the
state before the event, then the event's values are written to ``x`` and the
action runs.  Events arrive in order, each after a number of steps (0: before
the first).  Before every step, a pending event that its port cannot take is
kept (``remember``, the default), dropped (``ignore``, and the next one looked
at) or a model error (``error``: the reference engine's exit status 6).
While nothing else can fire, the engine lets the next events arrive instead
of reporting a deadlock.
"""
from __future__ import annotations

import bisect
import json
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from runtime.engine.cexpr import coerce
from runtime.engine.errors import EngineError, ModelError

POLICIES = ("remember", "ignore", "error")
_NATIVE = {"int": (int,), "float": (int, float), "bool": (bool,), "string": (str,)}


class UnexpectedEvent(ModelError):
    """An event reached an extern port with policy ``error`` while no transition could take it."""


@dataclass(frozen=True)
class Event:
    """One event for extern port ``port`` (``atom.port``), carrying ``values`` in the port's order."""

    port: str
    values: tuple = ()
    after: int = 0  # the number of steps after which it arrives


@dataclass
class _Port:
    source: int
    fp: Any  # the FlatPort
    policy: str
    queue: deque


class ExternPorts:
    """The extern ports of one engine: their queues, the events still to come, and the policies."""

    def __init__(self, flat, sources) -> None:
        self.ports: dict[str, _Port] = {}
        self.by_source: dict[int, _Port] = {}
        for src in sources:
            if src.kind == "port" and src.port.decl.extern:
                p = _Port(src.index, src.port, src.port.decl.policy or "remember", deque())
                self.ports[src.port.path] = self.by_source[src.index] = p
        self.coming: list[Event] = []
        self.steps = 0

    def push(self, port: str, *values: Any, after: int | None = None) -> None:
        """Queue an event for ``port`` (``atom.port``); it arrives once ``after`` steps are done (default: now)."""
        p = self.ports.get(port)
        if p is None:
            known = ", ".join(self.ports) or "none"
            raise EngineError(f"no extern port {port!r} (extern ports: {known})")
        if len(values) != len(p.fp.fields):
            raise EngineError(f"extern port {port} carries {len(p.fp.fields)} value(s) "
                              f"({', '.join(p.fp.fields) or 'none'}), the event has {len(values)}")
        for name, t, v in zip(p.fp.fields, p.fp.field_types, values):
            if t in _NATIVE and (not isinstance(v, _NATIVE[t]) or (t == "int" and isinstance(v, bool))):
                raise EngineError(f"event for extern port {port}: {name} is {t}, got {v!r}")
        typed = tuple(coerce(v, t) for t, v in zip(p.fp.field_types, values))
        event = Event(port, typed, self.steps if after is None else after)
        bisect.insort(self.coming, event, key=lambda e: e.after)  # after its equals: events due together keep order

    def arrive(self, steps: int) -> None:
        """Move the events due after ``steps`` steps to their ports' queues."""
        self.steps = steps
        while self.coming and self.coming[0].after <= steps:
            e = self.coming.pop(0)
            self.ports[e.port].queue.append(e.values)

    def next_arrival(self) -> int | None:
        """The step after which the next event arrives, if any is still to come."""
        return self.coming[0].after if self.coming else None

    def settle(self, enabled: list) -> list:
        """Apply the policies to events their ports cannot take now; the interactions that may fire.

        An extern port is offered only with an event pending; every other interaction passes.
        """
        waiting = {i.source for i in enabled if i.source in self.by_source}
        for p in self.ports.values():
            while p.queue and p.source not in waiting:
                if p.policy == "remember":
                    break
                if p.policy == "ignore":
                    p.queue.popleft()
                    continue
                raise UnexpectedEvent(f"port {p.fp.path} received an event while no transition can take it "
                                      f"and its event policy is 'error'", port=p.fp.name)
        return [i for i in enabled if i.source not in self.by_source or self.by_source[i.source].queue]

    def take(self, source: int) -> tuple:
        """The values of the event that the extern port of ``source`` consumes now."""
        return self.by_source[source].queue.popleft()

    def pending(self) -> dict[str, int]:
        """Events waiting in each port's queue."""
        return {name: len(p.queue) for name, p in self.ports.items() if p.queue}


def refuse_extern_data(flat) -> None:
    """Exploration offers an extern port as an environment choice; the values an event carries it cannot enumerate."""
    for fp in flat.ports:
        if fp.decl.extern and fp.fields:
            raise EngineError(f"extern port {fp.path} carries data ({', '.join(fp.fields)}): exploration takes an "
                              "extern port as an environment choice and cannot enumerate the values of its events")


def read_events(path: str | Path) -> list[Event]:
    """Events from a JSON-lines file: ``{"port": "A.p1", "values": [3], "after": 0}`` per line (values and
    after optional); blank lines and lines starting with ``#`` are skipped."""
    events = []
    if Path(path).exists() and not Path(path).is_file():  # a device or a FIFO: reading would never end or start
        raise EngineError(f"{path}: cannot read events: not a regular file (a device, a pipe or a directory)")
    try:
        lines = Path(path).read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as err:
        raise EngineError(f"cannot read events: {err}") from None
    for n, line in enumerate(lines, 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        try:
            item = json.loads(line)
            if not isinstance(item, dict) or not isinstance(item.get("port"), str):
                raise ValueError('expected an object with "port"')
            values = item.get("values", [])
            after = item.get("after", 0)
            if not isinstance(values, list) or not isinstance(after, int) or isinstance(after, bool) or after < 0:
                raise ValueError('"values" must be a list and "after" a step count >= 0')
        except ValueError as err:
            raise EngineError(f"{path}:{n}: bad event: {err}") from None
        events.append(Event(item["port"], tuple(values), after))
    return events
