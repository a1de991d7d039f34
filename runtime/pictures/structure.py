"""What the pictures draw, derived once from a flat BIP system: atoms grouped by compound, and links.

A *link* is one connector seen from its first port (the one that initiates
it: a request acceptor, a scheduler, a starting controller) towards every
other atom it joins, classified by the ports it binds, so that a picture can
draw interruptions, constraints and rules differently:

- ``abort``/``cancel`` of another service → ``interrupts``;
- a ``status`` port read by a trigger or refuse connector → ``constraint``
  (the description's ``after``/``before``) or ``rule`` (the rule file), with
  the rule ids the connector's ``@rule``/``@wait`` annotations name;
- ``write`` of a poster → ``write``; anything else → ``sync``.

The services-interface data of a generated package (``INTERFACE``), when
given, adds what the BIP model leaves out on purpose: poster reads (GenoM's
``port in`` never blocks, so it is no connector), codel names and periods.
"""
from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field
from typing import Any

from runtime.engine.flatten import FlatConnector, FlatSystem

@dataclass
class Link:
    """Connector ``label`` joins atom ``tail`` (its initiator) with atom ``head`` through ``ports`` of ``head``."""

    kind: str
    tail: str
    head: str
    label: str
    ports: list[str]
    rules: list[str] = field(default_factory=list)


@dataclass
class Flow:
    """Poster ``module.poster`` is read by the ``codels`` of ``reader`` (a GenoM ``port in``)."""

    module: str
    poster: str
    reader: str
    codels: list[str]


@dataclass
class Structure:
    """Atoms by compound path, links between atoms, and poster reads."""

    system: str
    atoms: dict[str, str]  # atom path -> atom type name
    links: list[Link]
    flows: list[Flow]
    modules: list[str]
    roles: dict[str, str]  # atom path -> "requests", "control", "activity", "timer", "scheduler", "poster", ...
    owners: dict[str, str]  # atom path -> "Module.Service" or "Module.task" it belongs to (GenoM models)
    periods: dict[str, str] = field(default_factory=dict)  # "Module.task" -> "every 100 ms"

    def module_of(self, atom: str) -> str:
        return atom.split(".", 1)[0]

    def owner_of(self, atom: str) -> str:
        """The ``Module.Service`` (or ``Module.task``) an atom belongs to; its parent path without an interface."""
        return self.owners.get(atom) or atom.rsplit(".", 1)[0]


def _annotation(connector: FlatConnector, name: str, key: str) -> list[str]:
    for a in connector.instance.annotations:
        if a.name == name and a.arguments.get(key):
            return [x for x in a.arguments[key].split(",") if x]
    return []


def _role(type_name: str, annotations: list[str]) -> str:
    if "timer" in annotations:
        return "timer"
    if "scheduler" in annotations:
        return "scheduler"
    for suffix, role in (("_Requests", "requests"), ("_Control", "control"), ("_Activity", "activity")):
        if type_name.endswith(suffix):
            return role
    return "poster" if type_name in ("Poster", "UnwrittenPoster") else "atom"


def _owners(interface: dict[str, Any] | None, atoms: list[str]) -> dict[str, str]:
    """Atom path -> the service or task it belongs to, from the instances the interface names."""
    if not interface:
        return {}
    prefixes: dict[str, str] = {}
    for cname, comp in interface.get("components", {}).items():
        for key in ("services", "tasks"):
            for name, item in comp.get(key, {}).items():
                prefixes[item.get("instance", f"{cname}.{name}")] = f"{cname}.{name}"
    out = {}
    for atom in atoms:
        parent = atom.rsplit(".", 1)[0]
        if parent in prefixes:
            out[atom] = prefixes[parent]
    return out


def _status_kind(label: str, rules: list[str]) -> str:
    """A description constraint when every rule id is one the description made (``M.S.after``), else a rule."""
    service = label.split(":", 1)[0]
    return "constraint" if rules and all(r.startswith(service + ".") for r in rules) else "rule"


def structure(flat: FlatSystem, interface: dict[str, Any] | None = None) -> Structure:
    """The atoms, links and poster reads of ``flat`` (and of ``interface`` when given).

    A ``status`` port is drawn from the service that provides it to the
    controller it constrains; a provider named by a ``refuse`` connector gets
    that connector's rule, one named only by the trigger gets its ``wait`` rules.
    """
    atoms = {a.name: a.type.name for a in flat.atoms}
    roles = {a.name: _role(a.type.name, [x.name for x in a.type.annotations]) for a in flat.atoms}
    owners = _owners(interface, list(atoms))
    tops = [(c, [flat.ports[p] for p in flat.leaves(c)]) for c in flat.connectors if c.top]
    refused = {(c.label.split(":")[0], flat.atoms[p.atom].name)
               for c, ports in tops if c.label.endswith(":refuse") for p in ports if p.name == "status"}
    links: list[Link] = []
    for c, ports in tops:
        if not ports:
            continue
        tail = flat.atoms[ports[0].atom].name
        rules, waits = _annotation(c, "rule", "name"), _annotation(c, "wait", "rules")
        guarded = next((flat.atoms[p.atom].name for p in ports if p.name in ("trigger", "refuse")), None)
        by_head: dict[str, list[str]] = defaultdict(list)
        for p in ports[1:]:
            head = flat.atoms[p.atom].name
            if p.name == "status" and guarded is not None:
                service = c.label.split(":")[0]
                if c.label.endswith(":refuse"):
                    links.append(Link(_status_kind(c.label, rules), head, guarded, c.label, ["status"], rules))
                elif (service, head) not in refused:
                    links.append(Link(_status_kind(c.label, waits), head, guarded, c.label, ["status"], waits))
            elif head != tail:
                by_head[head].append(p.name)
        if not by_head and len(ports) == 1:
            links.append(Link("sync", tail, tail, c.label, [ports[0].name]))
        for head, names in by_head.items():
            interrupt = names[0] in ("abort", "cancel") and owners.get(head, head) != owners.get(tail, tail)
            kind = "interrupts" if interrupt else "write" if names == ["write"] else "sync"
            links.append(Link(kind, tail, head, c.label, names))
    modules = list(dict.fromkeys(a.split(".", 1)[0] for a in atoms if "." in a))
    flows = _flows(interface) if interface else []
    return Structure(flat.package.name, atoms, links, flows, modules, roles, owners, _periods(interface))


def _periods(interface: dict[str, Any] | None) -> dict[str, str]:
    """``Module.task`` -> ``every 100 ms`` for the periodic tasks the interface lists."""
    out = {}
    for cname, comp in (interface or {}).get("components", {}).items():
        for tname, task in comp.get("tasks", {}).items():
            if task.get("period_us"):
                out[f"{cname}.{tname}"] = f"every {task['period_us'] / 1000:g} ms"
    return out


def _flows(interface: dict[str, Any]) -> list[Flow]:
    """Poster reads: a ``port in`` matched by name to the one other module writing it, with the codels reading it."""
    comps = interface.get("components", {})
    writers: dict[str, list[str]] = defaultdict(list)
    for cname, comp in comps.items():
        for pname, port in comp.get("ports", {}).items():
            if port.get("direction") == "out":
                writers[pname].append(cname)
    flows = []
    for cname, comp in comps.items():
        reading: dict[str, list[str]] = defaultdict(list)
        for key in ("services", "tasks"):
            for name, item in comp.get(key, {}).items():
                for codel in item.get("codels", {}).values():
                    for p in codel.get("params", []):
                        if p.get("source") == "port" and p.get("direction") == "in":
                            reading[p["path"].split(".")[0].split("[")[0]].append(codel["codel"])
        for pname, port in comp.get("ports", {}).items():
            if port.get("direction") != "in":
                continue
            sources = [w for w in writers.get(pname, []) if w != cname]
            if len(sources) == 1:
                flows.append(Flow(sources[0], pname, cname, list(dict.fromkeys(reading.get(pname, [])))))
    return flows
