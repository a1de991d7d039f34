"""What each interaction of the generated model means at run time, read once from its ports and annotations.

The generated connectors join ports of service controllers (``control``),
activities (``activity``) and task activities (``permanent``); which ports an
interaction joins says which request it answers, which services it aborts or
reads, and which task period it opens or closes.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from runtime.controller.binding import Binder, Scope
from runtime.controller.requests import Service
from runtime.controller.timing import Timer, Timers
from runtime.engine import Interaction


@dataclass
class StepInfo:
    """What an interaction means at run time, worked out once per interaction from its ports."""

    # the service port it fires: trigger, refuse, reject, start, exec_<state>, finish, fail, interrupted
    kind: str | None = None
    service: Service | None = None
    scope: Scope | None = None  # a task whose permanent activity runs a codel
    victims: list[Service] = field(default_factory=list)  # services whose activity it aborts
    cancelled: list[Service] = field(default_factory=list)  # services whose accepted request it cancels
    reads: list[Service] = field(default_factory=list)  # services whose status it reads (rules)
    rule: dict[str, str] | None = None  # the connector's @rule annotation
    opens: Timer | None = None
    closes: Timer | None = None
    lazy_exec: str | None = None  # an untimed period: the exec port of its scheduler


class Meanings:
    """The run-time meaning of a flat model's ports and interactions: roles, interruptions, wait rules."""

    def __init__(self, flat, interface: dict[str, Any], binder: Binder, services: dict[str, Service],
                 timers: Timers) -> None:
        self.flat = flat
        self.services = services
        self.timers = timers
        self.roles = self._port_roles(interface, binder)
        self.interrupters = self._who_interrupts()
        self.cache: dict[int, StepInfo] = {}  # interaction index -> its meaning
        self.connectors = {fc.path: fc for fc in flat.connectors}
        self.waits = self._wait_rules()

    def _port_roles(self, interface: dict[str, Any], binder: Binder) -> dict[str, tuple[Any, str, str]]:
        """Atom port path -> (service or task scope, "control"/"activity"/"task", port name)."""
        by_instance = {svc.spec["instance"]: svc for svc in self.services.values()}
        tasks = {}
        for c, spec in interface["components"].items():
            for t, task in spec["tasks"].items():
                tasks[task["instance"]] = binder.tasks[f"{c}.{t}"]
        roles: dict[str, tuple[Any, str, str]] = {}
        for fa in self.flat.atoms:
            base, _, part = fa.name.rpartition(".")
            if part in ("control", "activity") and base in by_instance:
                owner, role = by_instance[base], part
            elif part == "permanent" and base in tasks:
                owner, role = tasks[base], "task"
            else:
                continue
            for port in fa.ports:
                roles[f"{fa.name}.{port}"] = (owner, role, port)
            if part == "control" and all(v in (d.name for d in fa.variables) for v in ("done", "ok", "running")):
                owner.status_slots = (fa.slot("done"), fa.slot("ok"), fa.slot("running"))
        return roles

    def leaves(self, fc) -> list[str]:
        """Atom ports under a connector, through its sub-connectors."""
        flat = self.flat
        return [flat.ports[p].path for p in flat.leaves(fc)]

    def _who_interrupts(self) -> dict[str, list[str]]:
        """Service label -> the services whose start aborts it (the description's and the rules' interruptions)."""
        found: dict[str, list[str]] = {}
        for fc in self.flat.connectors:
            if not fc.top:
                continue
            roles = [self.roles.get(p) for p in self.leaves(fc)]
            starts = [r[0].label for r in roles if r is not None and r[1] == "control" and r[2] == "start"]
            for r in roles:
                if r is not None and r[2] == "abort" and starts and r[0].label not in starts:
                    found.setdefault(r[0].label, []).extend(x for x in starts if x not in found.get(r[0].label, []))
        return found

    def _wait_rules(self) -> dict[str, tuple[list[str], list[Service]]]:
        """Service label -> (the rules that hold its requests, the services they read): ``@wait`` on its trigger."""
        out = {}
        for fc in self.flat.connectors:
            if not fc.label.endswith(":trigger"):
                continue
            for a in fc.instance.annotations:
                if a.name == "wait" and a.arguments.get("rules"):
                    label = fc.label.rsplit(":", 1)[0]
                    ports = set(self.leaves(fc))
                    reads = [svc for svc in self.services.values() if f"{svc.label}.control.status" in ports]
                    out[label] = (a.arguments["rules"].split(","), reads)
        return out

    def info(self, inter: Interaction) -> StepInfo:
        """The run-time meaning of ``inter`` (cached by its index)."""
        got = self.cache.get(inter.index)
        if got is not None:
            return got
        info = StepInfo()
        t = self.timers
        for p in inter.ports:
            if p in t.by_trigger:
                info.opens = t.by_trigger[p]
            elif p in t.by_sleep:
                info.closes = t.by_sleep[p]
            elif p in t.lazy:
                info.lazy_exec = t.lazy[p]
            role = self.roles.get(p)
            if role is None:
                continue
            owner, kind, port = role
            if kind == "task":
                info.scope = owner
            elif port == "abort":
                info.victims.append(owner)
            elif port == "cancel":
                info.cancelled.append(owner)
            elif port == "status":
                info.reads.append(owner)
            else:
                info.service, info.kind = owner, port
        if info.service is not None and inter.connector in self.connectors:
            for a in self.connectors[inter.connector].instance.annotations:
                if a.name == "rule":
                    info.rule = dict(a.arguments)
        if info.service is not None:
            info.victims = [v for v in info.victims if v is not info.service]
        self.cache[inter.index] = info
        return info
