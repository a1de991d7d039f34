"""User observers: latency properties in YAML beside the rules, checked like rule files.

An observer file (``observers.yaml`` beside ``rules.yaml``, or ``--observers FILE``)::

    observers:
      - name: obstacle-to-brake
        doc: a new scan reaches the wheels quickly
        from: LaserRF.Scan:write        # an event: Module.Name:port
        to: RFLEX.servo:exec
        within: 1 s

An event names interactions of the model: a label (``NDD.GoTo:trigger``), a
family of them (``RFLEX.servo:exec`` is every ``exec_<state>`` of the task or
service), or the writes of a poster (``LaserRF.Scan:write``: every codel step
that writes it).  Every problem is reported with the file, line and column of
the value at fault; nothing is built.
"""
from __future__ import annotations

import re
from pathlib import Path

import yaml

from genom2bip import ir
from genom2bip.build.timed import LatencySpec
from genom2bip.durations import parse_duration
from genom2bip import rules
from genom2bip.rules import _suggest
from genom2bip.yamlfile import compose_file
from runtime.diagnostics import Reporter, Span

KEYS = ("name", "doc", "from", "to", "within")
SERVICE_PORTS = ("trigger", "start", "finish", "fail", "interrupted", "reject", "refuse", "exec")
TASK_PORTS = ("period", "sleep", "exec")
class _Reader(rules._Reader):
    """The rule file's reader (positions, messages), reading observers."""

    def scalar(self, node: yaml.Node, what: str, name: str) -> str | None:
        if not isinstance(node, yaml.ScalarNode) or node.value == "":
            self.error(node, f"observer {name}: {what} must be a single value")
            return None
        return node.value

    def event(self, node: yaml.Node, name: str) -> str | None:
        """``Module.Name:port`` naming a service, task or poster of the description and one of its ports."""
        text = self.scalar(node, "an event", name)
        if text is None:
            return None
        m = re.fullmatch(r"([A-Za-z_]\w*)\.([A-Za-z_]\w*):([A-Za-z_]\w*)", text)
        if not m:
            self.error(node, f"observer {name}: '{text}' is not an event Module.Name:port",
                       "write e.g. NDD.GoTo:trigger, RFLEX.servo:exec or LaserRF.Scan:write")
            return None
        module, thing, port = m.groups()
        component = next((c for c in self.description.components if c.name == module), None)
        if component is None:
            self.error(node, f"observer {name}: unknown module '{module}'",
                       _suggest(module, [c.name for c in self.description.components]))
            return None
        services = {s.name: s for s in component.services}
        tasks = {t.name: t for t in component.tasks}
        posters = [p.name for p in component.ports if p.direction == "out"]
        if thing in services:
            states = services[thing].fsm_codels()
            allowed = list(SERVICE_PORTS) + [f"exec_{s}" for s in ir.fsm_states(states)]
        elif thing in tasks:
            allowed = list(TASK_PORTS) + [f"exec_{s}" for s in ir.fsm_states(tasks[thing].codels)]
        elif thing in posters:
            allowed = ["write"]
        else:
            self.error(node, f"observer {name}: module {module} has no service, task or poster '{thing}'",
                       _suggest(thing, list(services) + list(tasks) + posters))
            return None
        if port not in allowed:
            self.error(node, f"observer {name}: {module}.{thing} has no event '{port}'", _suggest(port, allowed))
            return None
        return text

    def observers(self, root: yaml.Node | None) -> list[LatencySpec]:
        if root is None:
            return []
        if not isinstance(root, yaml.MappingNode):
            self.error(
                root, "an observer file is a mapping with an 'observers' list", "start the file with 'observers:'"
            )
            return []
        body = None
        for k, v in root.value:
            if k.value == "observers":
                body = v
            else:
                self.error(k, f"unknown top-level key '{k.value}'", "the file has one key, 'observers'")
        if body is None:
            self.error(root, "missing 'observers' list")
            return []
        if not isinstance(body, yaml.SequenceNode):
            self.error(body, "'observers' must be a list of observers")
            return []
        out: list[LatencySpec] = []
        seen: dict[str, Span] = {}
        for index, node in enumerate(body.value, 1):
            spec = self.observer(node, index, seen)
            if spec is not None:
                out.append(spec)
        return out

    def observer(self, node: yaml.Node, index: int, seen: dict[str, Span]) -> LatencySpec | None:
        if not isinstance(node, yaml.MappingNode):
            self.error(node, f"observer #{index} must be a mapping of keys ({', '.join(KEYS)})")
            return None
        fields: dict[str, yaml.Node] = {}
        for k, v in node.value:
            if k.value in fields:
                self.error(k, f"observer #{index}: key '{k.value}' given twice")
            elif k.value not in KEYS:
                self.error(k, f"observer #{index}: unknown key '{k.value}'", _suggest(k.value, list(KEYS)))
            else:
                fields[k.value] = v
        name = f"#{index}"
        missing = [k for k in ("name", "from", "to", "within") if k not in fields]
        if missing:
            self.error(node, f"observer #{index} has no {', '.join(repr(k) for k in missing)}")
            return None
        value = self.scalar(fields["name"], "its name", name)
        if value is None:
            return None
        if not re.fullmatch(r"[A-Za-z_][\w-]*", value):
            self.error(fields["name"], f"observer name '{value}' must be letters, digits, '_' or '-'")
            return None
        name = value
        if name in seen:
            self.error(fields["name"], f"duplicate observer name '{name}'", f"first used at {seen[name]}")
            return None
        seen[name] = self.span(fields["name"])
        begin, end = self.event(fields["from"], name), self.event(fields["to"], name)
        within_text = self.scalar(fields["within"], "within", name)
        within = parse_duration(within_text) if within_text is not None else None
        if within_text is not None and (within is None or within <= 0):
            shown = within_text if len(within_text) <= 40 else within_text[:37] + "..."
            self.error(fields["within"], f"observer {name}: within is '{shown}'; expected a positive duration",
                       "write e.g. 1 s, 250 ms or 500 us (a day at most)")
            return None
        if begin is None or end is None or within is None:
            return None
        doc = self.scalar(fields["doc"], "doc", name) if "doc" in fields else None
        return LatencySpec(name, begin, end, within, doc, begin_span=self.span(fields["from"]),
                           end_span=self.span(fields["to"]))


def load_observers(path: Path, description: ir.Description, reporter: Reporter) -> list[LatencySpec]:
    """Read and check an observer file against the description; problems go to ``reporter``."""
    ok, root = compose_file(path, reporter, "observer file")
    return _Reader(str(path), description, reporter).observers(root) if ok else []
