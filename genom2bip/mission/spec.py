"""Reading a mission file (YAML): its steps, each with the line it came from; errors name file:line:column.

```yaml
mission: corridor
world: ../worlds/corridor.yaml        # relative to this file; --world overrides it
steps:
  - send: NDD.SetSpeed                # Module.Service
    with: {max_speed: {v: 0.4}}       # its inputs (defaults for the others)
    expect: ok                        # a status, or {status, rule, exception, by}
  - send: NDD.GoTo
    as: goto                          # a name to await it later
    until: started                    # queued | started | final (default)
    after: 10 ms                      # sent this long after the previous step is over
    timeout: 60                       # controller seconds (default 120)
  - wait: 2.0                         # controller seconds
  - await: goto
    expect: {status: interrupted, by: NDD.Stop}
```
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from genom2bip.durations import parse_duration
from genom2bip.filenames import name_problem
from genom2bip.yamlfile import compose_file, keyed, span_of
from runtime.diagnostics import Reporter, Span

STATUSES = ("ok", "rejected", "failed", "interrupted", "refused")
#: Seconds of controller time a wait or a timeout may ask for: a day.
MAX_SECONDS = 86_400.0
EXPECT_KEYS = ("status", "rule", "exception", "by", "reason")
UNTIL = ("queued", "started", "final")
DEFAULT_TIMEOUT = 120.0
#: The service whose ``goal`` input is a goal of the drive: the report's goals, the live page's stars.
GOAL_SERVICE = "NDD.GoTo"
#: The poster the live page draws over the world: POM's fused estimate, in the world's frame (RFLEX.Odo is in the
#: odometry's own frame, and Aspect.Obs's origin is the map's).
POSE_POSTER = {"poster": "POM.Pos", "path": "estimate"}


def goal_point(goal: Any) -> tuple[float, float] | None:
    """A goal's (x, y) when it has them as finite numbers, else None (a package whose schema says nothing takes
    any value: the report, the picture and the live page then draw no star for it)."""
    if not isinstance(goal, dict) or not {"x", "y"} <= set(goal):
        return None
    x, y = goal["x"], goal["y"]
    numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in (x, y))
    return (float(x), float(y)) if numbers else None


@dataclass
class Step:
    """One line of a mission: ``send``, ``wait`` or ``await``."""

    kind: str
    span: Span
    target: str = ""  # send: Module.Service; await: the name given with ``as``
    inputs: dict[str, Any] = field(default_factory=dict)
    name: str | None = None
    until: str = "final"
    expect: dict[str, str] | None = None
    timeout: float = DEFAULT_TIMEOUT
    seconds: float = 0.0
    after: float = 0.0  # send: seconds to wait once the previous step is over
    inputs_span: Span | None = None  # send: where ``with:`` gives the inputs

    @property
    def where(self) -> str:
        return f"{self.span.file}:{self.span.line}"


@dataclass
class Mission:
    name: str
    path: Path
    world: Path | None
    steps: list[Step]


def _plain(node: yaml.Node) -> Any:
    return yaml.safe_load(yaml.serialize(node))


class _Reader:
    def __init__(self, path: Path, reporter: Reporter) -> None:
        self.path, self.reporter = path, reporter

    def span(self, node: yaml.Node) -> Span:
        return span_of(self.path, node)

    def error(self, node: yaml.Node, message: str) -> None:
        self.reporter.error(self.span(node), message)

    def name(self, node: yaml.Node | None) -> str | None:
        """The mission's name (``mission:``, else the file's): it names the files written, so one plain component
        of a path; None after reporting why not."""
        if node is not None and not isinstance(node, yaml.ScalarNode):
            self.error(node, "mission: a name expected (it names the files written: NAME.png, NAME.jsonl)")
            return None
        name = node.value if node is not None else self.path.stem
        problem = name_problem(name)
        if problem:
            self.reporter.error(self.span(node) if node is not None else Span(str(self.path), 0, 0),
                                f"mission: {name!r} cannot name the files written: {problem}")
            return None
        return name

    def unique(self, node: yaml.Node, what: str) -> None:
        """Report every key given twice in the mappings of ``node`` (a request's inputs, at any depth)."""
        stack = [node]
        while stack:
            item = stack.pop()
            if isinstance(item, yaml.MappingNode):
                keyed(self.path, item, self.reporter, what)
                stack.extend(v for _, v in item.value)
            elif isinstance(item, yaml.SequenceNode):
                stack.extend(item.value)

    def number(self, node: yaml.Node, what: str) -> float | None:
        value = _plain(node)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not value >= 0:
            self.error(node, f"{what}: a number of seconds (0 or more) expected, got {node.value!r}")
            return None
        if value > MAX_SECONDS:
            self.error(node, f"{what}: at most {MAX_SECONDS:g} seconds (a day) expected, got {node.value!r}")
            return None
        return float(value)

    def delay(self, node: yaml.Node, what: str) -> float | None:
        """Seconds, as a number (``0.5``) or a duration (``10 ms``), at most a day."""
        if isinstance(node, yaml.ScalarNode) and parse_duration(node.value) is not None:
            return parse_duration(node.value) / 1e6
        return self.number(node, what)

    def expect(self, node: yaml.Node) -> dict[str, str] | None:
        value = _plain(node)
        if isinstance(value, str):
            value = {"status": value}
        if not isinstance(value, dict) or not value:
            self.error(node, "expect: a status (ok, rejected, failed, interrupted) or a mapping of "
                             f"{', '.join(EXPECT_KEYS)} expected")
            return None
        for key, item in zip(node.value if isinstance(node, yaml.MappingNode) else [], value):
            if item not in EXPECT_KEYS:
                self.error(key[0], f"expect: unknown key {item!r} (keys: {', '.join(EXPECT_KEYS)})")
        status = value.get("status")
        if status is not None and status not in STATUSES:
            self.error(node, f"expect: unknown status {status!r} (statuses: {', '.join(STATUSES[:4])})")
        return {k: str(v) for k, v in value.items()}

    def step(self, node: yaml.Node, names: set[str]) -> Step | None:
        if not isinstance(node, yaml.MappingNode):
            self.error(node, "a step is a mapping: send, wait or await")
            return None
        fields = keyed(self.path, node, self.reporter, "step")
        kinds = [k for k in ("send", "wait", "await") if k in fields]
        if len(kinds) != 1:
            self.error(
                node, "a step has exactly one of send, wait, await" + (f" (has {', '.join(kinds)})" if kinds else "")
            )
            return None
        kind = kinds[0]
        allowed = {"send": {"send", "with", "as", "until", "expect", "timeout", "after"}, "wait": {"wait"},
                   "await": {"await", "expect", "timeout"}}[kind]
        ok = True
        for key, (knode, _) in fields.items():
            if key not in allowed:
                self.error(knode, f"{kind} step: unknown key {key!r} (keys: {', '.join(sorted(allowed))})")
                ok = False
        step = Step(kind, self.span(node))
        value = fields[kind][1]
        if kind == "wait":
            seconds = self.number(value, "wait")
            step.seconds = seconds or 0.0
            return step if ok and seconds is not None else None
        text = value.value if isinstance(value, yaml.ScalarNode) else None
        if kind == "send" and (not text or text.count(".") != 1 or not all(text.split("."))):
            self.error(value, f"send: Module.Service expected, got {text or _plain(value)!r}")
            ok = False
        if kind == "await" and text not in names:
            self.error(value, f"await: no earlier step named {text!r} (names: {', '.join(sorted(names)) or 'none'})")
            ok = False
        step.target = text or ""
        if "with" in fields:
            self.unique(fields["with"][1], "with")
            inputs = _plain(fields["with"][1])
            if not isinstance(inputs, dict):
                self.error(fields["with"][1], "with: a mapping of the service's inputs expected")
                ok = False
            step.inputs = inputs if isinstance(inputs, dict) else {}
            step.inputs_span = self.span(fields["with"][1])
        if "as" in fields:
            node = fields["as"][1]
            if not isinstance(node, yaml.ScalarNode) or not node.value:
                self.error(node, "as: a name expected")
                ok = False
            elif node.value in names:
                self.error(node, f"as: {node.value!r} names an earlier step already: await would not know which")
                ok = False
            else:
                step.name = node.value
                names.add(step.name)
        if "until" in fields:
            step.until = str(fields["until"][1].value)
            if step.until not in UNTIL:
                self.error(fields["until"][1], f"until: one of {', '.join(UNTIL)} expected, got {step.until!r}")
                ok = False
        if "expect" in fields:
            step.expect = self.expect(fields["expect"][1])
            ok = ok and step.expect is not None
        if "after" in fields:
            after = self.delay(fields["after"][1], "after")
            ok = ok and after is not None
            step.after = after or 0.0
        if "timeout" in fields:
            t = self.number(fields["timeout"][1], "timeout")
            ok = ok and t is not None
            step.timeout = t if t is not None else DEFAULT_TIMEOUT
        return step if ok else None

    def mission(self, root: yaml.Node | None) -> Mission | None:
        if not isinstance(root, yaml.MappingNode):
            self.reporter.error(
                Span(str(self.path), 1, 1), "a mission file is a mapping with 'steps' (and 'mission', 'world')"
            )
            return None
        fields = keyed(self.path, root, self.reporter, "mission file")
        for key, (knode, _) in fields.items():
            if key not in ("mission", "world", "steps", "doc"):
                self.error(knode, f"unknown key {key!r} (keys: doc, mission, steps, world)")
        if "steps" not in fields or not isinstance(fields["steps"][1], yaml.SequenceNode):
            self.error(root, "'steps': a list of send, wait and await steps expected")
            return None
        world = None
        if "world" in fields:
            world = Path(os.path.normpath(self.path.parent.absolute() / str(fields["world"][1].value)))
        names: set[str] = set()
        steps = [self.step(n, names) for n in fields["steps"][1].value]
        name = self.name(fields["mission"][1] if "mission" in fields else None)
        if name is None:
            return None
        return Mission(name, self.path, world, [s for s in steps if s is not None])


def read_mission(path: str | Path, reporter: Reporter | None = None) -> Mission:
    """The mission in ``path``; raises DiagnosticError listing every problem (file:line:column)."""
    path = Path(path)
    reporter = reporter or Reporter()
    ok, root = compose_file(path, reporter, "mission file")
    reporter.raise_if_errors()
    mission = _Reader(path, reporter).mission(root)
    reporter.raise_if_errors()
    return mission
