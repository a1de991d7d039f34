"""Rules between services: the rule file (YAML) and the description's own constraints, in one vocabulary.

In the paper a central controller (R2C) enforced the safety rules between
modules; here every rule becomes guarded BIP connectors between the local
controllers of the services (docs/rules.md).  The description's ``after``,
``before`` and ``interrupts`` are rules of the same kinds, so one mechanism
generates both.

A rule file looks like::

    rules:
      - id: goto-after-pom-run
        doc: NDD navigates only once POM has localised the robot
        service: NDD.GoTo
        requires: [POM.Run]
        completed: once          # or: latest (its latest run succeeded)
        on_violation: reject     # or: wait (held until the rule allows it)

Every problem (unknown key, module or service, contradiction, unsatisfiable
cycle, duplicate id) is reported with the file, line and column of the value
at fault and the id of the rule.
"""
from __future__ import annotations

import difflib
from dataclasses import dataclass, field
from graphlib import CycleError, TopologicalSorter
from pathlib import Path

import yaml

from genom2bip import ir
from genom2bip.yamlfile import compose_file, span_of
from runtime.diagnostics import NOWHERE, Reporter, Span

Ref = tuple[str, str]  # (component, service)

#: Rule kinds that guard a service's start, and the status field of the others each one reads.
GUARD_KINDS = ("requires", "requires_running", "forbidden_while", "before")
KINDS = GUARD_KINDS + ("interrupts", "exclusive")
KEYS = ("id", "doc", "service", "completed", "on_violation") + KINDS
VIOLATIONS = ("reject", "wait")
COMPLETIONS = ("once", "latest")


@dataclass
class Rule:
    """One rule on starting ``service``: a condition on the status of ``others``, or an interruption of them."""

    id: str
    kind: str  # one of GUARD_KINDS, or "interrupts"
    service: Ref
    others: list[Ref]
    completed: str = "once"
    on_violation: str = "reject"
    doc: str | None = None
    origin: str = "rules"  # "rules" (a rule file) or "description"
    span: Span = field(default=NOWHERE, compare=False, repr=False)

    @property
    def status_field(self) -> str:
        """The status field of the others that the rule reads (see genom2bip/build/library.STATUS_FIELDS)."""
        if self.kind == "requires":
            return "ok" if self.completed == "latest" else "done"
        if self.kind in ("requires_running", "forbidden_while"):
            return "running"
        return "done"  # before

    @property
    def negated(self) -> bool:
        """True when the rule holds while the others' field is false (``forbidden_while``, ``before``)."""
        return self.kind in ("forbidden_while", "before")

    def describe(self) -> str:
        others = ", ".join(f"{m}.{s}" for m, s in self.others)
        what = {
            "requires": f"only after {others} {'succeeded last time' if self.completed == 'latest' else 'completed'}",
            "requires_running": f"only while {others} run",
            "forbidden_while": f"never while {others} run",
            "before": f"only before {others} completed",
            "interrupts": f"interrupts {others}",
        }[self.kind]
        return f"{self.service[0]}.{self.service[1]} {what}"


# --------------------------------------------------------------------------- description constraints


def description_rules(description: ir.Description) -> list[Rule]:
    """The ``after``, ``before`` and ``interrupts`` of every service, as rules (ids ``Module.Service.after``)."""
    out: list[Rule] = []
    for c in description.components:
        names = [s.name for s in c.services]
        for s in c.services:
            me = (c.name, s.name)
            if s.after:
                out.append(Rule(f"{c.name}.{s.name}.after", "requires", me, [(c.name, n) for n in s.after],
                                origin="description", span=s.span))
            if s.before:
                out.append(Rule(f"{c.name}.{s.name}.before", "before", me, [(c.name, n) for n in s.before],
                                origin="description", span=s.span))
            victims = names if "all" in s.interrupts else [n for n in s.interrupts if n in names]
            victims = [n for n in victims if n != s.name]
            if victims:
                out.append(Rule(f"{c.name}.{s.name}.interrupts", "interrupts", me, [(c.name, n) for n in victims],
                                origin="description", span=s.span))
    return out


# --------------------------------------------------------------------------- the rule file


class _Reader:
    """Walks the YAML node tree so that every value keeps its position for messages."""

    def __init__(self, path: str, description: ir.Description, reporter: Reporter) -> None:
        self.path = path
        self.description = description
        self.reporter = reporter
        self.services: dict[Ref, ir.Service] = {
            (c.name, s.name): s for c in description.components for s in c.services}

    def span(self, node: yaml.Node) -> Span:
        return span_of(self.path, node)

    def error(self, node: yaml.Node, message: str, hint: str | None = None) -> None:
        self.reporter.error(self.span(node), message, hint)

    def scalar(self, node: yaml.Node, what: str, rule: str) -> str | None:
        if not isinstance(node, yaml.ScalarNode) or node.value == "":
            self.error(node, f"rule {rule}: {what} must be a single value")
            return None
        return node.value

    def ref(self, node: yaml.Node, rule: str) -> Ref | None:
        text = self.scalar(node, "a service", rule)
        if text is None:
            return None
        module, dot, service = text.partition(".")
        if not dot or not module or not service:
            self.error(node, f"rule {rule}: '{text}' is not Module.Service", "name a service as NDD.GoTo")
            return None
        modules = [c.name for c in self.description.components]
        if module not in modules:
            self.error(node, f"rule {rule}: unknown module '{module}'", _suggest(module, modules))
            return None
        names = [s for m, s in self.services if m == module]
        if service not in names:
            self.error(node, f"rule {rule}: module {module} has no service '{service}'", _suggest(service, names))
            return None
        return (module, service)

    def refs(self, node: yaml.Node, key: str, rule: str) -> list[Ref] | None:
        items = node.value if isinstance(node, yaml.SequenceNode) else [node]
        if not items:
            self.error(node, f"rule {rule}: '{key}' names no service")
            return None
        out = [self.ref(item, rule) for item in items]
        return None if any(r is None for r in out) else out  # type: ignore[return-value]

    def rules(self, root: yaml.Node | None) -> list[Rule]:
        if root is None:
            return []
        if not isinstance(root, yaml.MappingNode):
            self.error(root, "a rule file is a mapping with a 'rules' list", "start the file with 'rules:'")
            return []
        body = None
        for k, v in root.value:
            if k.value == "rules":
                body = v
            else:
                self.error(k, f"unknown top-level key '{k.value}'", "the file has one key, 'rules'")
        if body is None:
            self.error(root, "missing 'rules' list")
            return []
        if isinstance(body, yaml.ScalarNode) and body.value in ("", "null", "~"):
            return []
        if not isinstance(body, yaml.SequenceNode):
            self.error(body, "'rules' must be a list of rules")
            return []
        out: list[Rule] = []
        seen: dict[str, Span] = {}
        for index, node in enumerate(body.value, 1):
            out += self.rule(node, index, seen)
        return out

    def rule(self, node: yaml.Node, index: int, seen: dict[str, Span]) -> list[Rule]:
        if not isinstance(node, yaml.MappingNode):
            self.error(node, f"rule #{index} must be a mapping of keys (id, service, requires...)")
            return []
        fields: dict[str, yaml.Node] = {}
        keys: dict[str, yaml.Node] = {}
        for k, v in node.value:
            if k.value in fields:
                self.error(k, f"rule #{index}: key '{k.value}' given twice")
            elif k.value not in KEYS:
                self.error(k, f"rule #{index}: unknown key '{k.value}'",
                           _suggest(k.value, list(KEYS)) or f"keys are {', '.join(KEYS)}")
            else:
                fields[k.value] = v
                keys[k.value] = k
        name = f"#{index}"
        if "id" not in fields:
            self.error(node, f"rule #{index} has no 'id'", "give every rule an id; reports name it")
        else:
            rid = self.scalar(fields["id"], "its id", name)
            if rid is not None:
                name = rid
                if rid in seen:
                    self.error(fields["id"], f"duplicate rule id '{rid}'", f"first used at {seen[rid]}")
                else:
                    seen[rid] = self.span(fields["id"])
        kinds = [k for k in KINDS if k in fields]
        if len(kinds) != 1:
            where = keys[kinds[1]] if len(kinds) > 1 else node
            self.error(where, f"rule {name}: give exactly one of {', '.join(KINDS)}"
                       + (f" (found {', '.join(kinds)})" if kinds else ""))
            return []
        kind = kinds[0]
        others = self.refs(fields[kind], kind, name)
        completed = self._choice(fields, "completed", COMPLETIONS, name, kind in ("requires",))
        violation = self._choice(fields, "on_violation", VIOLATIONS, name, kind != "interrupts")
        doc = self.scalar(fields["doc"], "doc", name) if "doc" in fields else None
        span = self.span(fields["id"] if "id" in fields else node)
        if kind == "exclusive":
            if "service" in fields:
                self.error(keys["service"], f"rule {name}: 'exclusive' takes its services in its own list",
                           "write exclusive: [A.S, B.T]")
                return []
            if others is None or completed is None or violation is None:
                return []
            if len(set(others)) < 2:
                self.error(fields[kind], f"rule {name}: 'exclusive' needs at least two different services")
                return []
            return [Rule(name, "forbidden_while", a, [b for b in others if b != a], on_violation=violation,
                         doc=doc, span=span) for a in others]
        if "service" not in fields:
            self.error(node, f"rule {name} has no 'service' (the service the rule constrains)")
            return []
        service = self.ref(fields["service"], name)
        if service is None or others is None or completed is None or violation is None:
            return []
        if service in others:
            self.error(fields[kind], f"rule {name}: {service[0]}.{service[1]} names itself in '{kind}'")
            return []
        return [Rule(name, kind, service, others, completed, violation, doc, span=span)]

    def _choice(self, fields, key, allowed, rule, applies) -> str | None:
        if key not in fields:
            return allowed[0]
        value = self.scalar(fields[key], key, rule)
        if value is None:
            return None
        if not applies:
            self.error(fields[key], f"rule {rule}: '{key}' does not apply to this kind of rule")
            return None
        if value not in allowed:
            self.error(fields[key], f"rule {rule}: {key} is '{value}'; expected {' or '.join(allowed)}")
            return None
        return value


def _suggest(word: str, choices: list[str]) -> str | None:
    close = difflib.get_close_matches(word, choices, n=1)
    return f"did you mean '{close[0]}'?" if close else (f"known: {', '.join(choices)}" if choices else None)


def load_rules(path: Path, description: ir.Description, reporter: Reporter) -> list[Rule]:
    """Read and check a rule file against the description; problems go to ``reporter``."""
    ok, root = compose_file(path, reporter, "rule file")
    return _Reader(str(path), description, reporter).rules(root) if ok else []


# --------------------------------------------------------------------------- consistency


def check_rules(rules: list[Rule], description: ir.Description, reporter: Reporter) -> None:
    """Rules that can never be satisfied: contradictions and cycles of requirements."""
    kinds: dict[Ref, dict[str, set[Ref]]] = {}
    for r in rules:
        for o in r.others:
            kinds.setdefault(r.service, {}).setdefault(r.kind, set()).add(o)

    def holds(service: Ref, kind: str, other: Ref) -> bool:
        return other in kinds.get(service, {}).get(kind, set())

    for r in rules:
        for o in r.others:
            clash = None
            if r.kind == "requires" and holds(r.service, "before", o):
                clash = "before"
            elif r.kind == "requires_running" and holds(r.service, "forbidden_while", o):
                clash = "forbidden_while"
            if clash:
                other = next(x for x in rules if x.service == r.service and x.kind == clash and o in x.others)
                reporter.error(r.span, f"rule {r.id} contradicts {other.id} ({other.origin}): "
                               f"{r.service[0]}.{r.service[1]} could never start",
                               f"{r.describe()}, but {other.describe()}")
    edges = [(r.service, o, r) for r in rules if r.kind in ("requires", "requires_running") for o in r.others]
    needs: dict[tuple[str, str], set[tuple[str, str]]] = {}
    for service, other, _ in edges:
        needs.setdefault(service, set()).add(other)
    try:
        TopologicalSorter(needs).prepare()  # the standard library says whether there is a cycle at all
        return
    except CycleError:
        pass
    import networkx as nx  # here, not at the top: every command reads rules, few have rules that cycle

    graph = nx.DiGraph()
    for service, other, r in edges:
        graph.add_edge(service, other, rule=r)
    order = {id(r): i for i, r in enumerate(rules)}
    for cycle in sorted(nx.simple_cycles(graph), key=lambda c: sorted(c)):
        # Start the cycle where its earliest rule starts, so that messages do not depend on hashing.
        first = min(
            range(len(cycle)), key=lambda i: order[id(graph.edges[cycle[i], cycle[(i + 1) % len(cycle)]]["rule"])]
        )
        cycle = cycle[first:] + cycle[:first]
        edges = [graph.edges[a, b]["rule"] for a, b in zip(cycle, cycle[1:] + cycle[:1])]
        at = next((e for e in edges if e.origin == "rules"), edges[0])
        names = " -> ".join(f"{m}.{s}" for m, s in cycle + cycle[:1])
        reporter.error(at.span, f"rules {', '.join(sorted({e.id for e in edges}))} form a cycle of requirements "
                       f"that can never be satisfied: {names}",
                       "each service waits for another one of the cycle to complete or run first")


def all_rules(description: ir.Description, rules_file: Path | None, reporter: Reporter) -> list[Rule]:
    """The description's constraints plus the rule file's rules, checked together."""
    rules = description_rules(description)
    if rules_file is not None:
        rules += load_rules(rules_file, description, reporter)
    if not reporter.has_errors:
        check_rules(rules, description, reporter)
    return rules
