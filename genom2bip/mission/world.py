"""Checking a world file (ir-sim YAML) before the controller starts: what the simulation and DALA's codels need.

ir-sim reads far more keys than these; what is checked here is the shape of
the file (ir-sim's five top-level keys, a robot, obstacles as mappings), the
robot DALA's codels drive (a differential-drive base carrying a ``lidar2d``)
and the range of every number they read: each problem with ``file:line:column``
and what was expected, where ir-sim would stop with an exception, or run a
world with a NaN in it.  Every number of the file is finite
(:mod:`genom2bip.yamlfile`).
"""
from __future__ import annotations

import difflib
import math
from pathlib import Path
from typing import Any

import yaml

from genom2bip.yamlfile import compose_file, keyed, span_of
from runtime.diagnostics import Reporter, Span

KEYS = ("world", "gui", "robot", "obstacle", "custom")
COLLISION_MODES = ("stop", "unobstructed", "unobstructed_obstacles", "contact")
#: Metres: the size of a world, a coordinate, a length.
FAR = 1e4
#: Objects one robot or obstacle entry may make (``number:``).
MAX_OBJECTS = 1000


class _Checker:
    """Walks the world's node tree; each problem is reported at the node at fault."""

    def __init__(self, path: Path, reporter: Reporter) -> None:
        self.path, self.reporter = path, reporter

    def error(self, node: yaml.Node, where: str, expected: str) -> None:
        shown = node.value if isinstance(node, yaml.ScalarNode) else {
            yaml.MappingNode: "a mapping", yaml.SequenceNode: "a list"}[type(node)]
        self.reporter.error(span_of(self.path, node), f"{where}: {expected} expected, got {shown!r}"
                            if isinstance(node, yaml.ScalarNode) else f"{where}: {expected} expected, got {shown}")

    def fields(self, node: yaml.Node, where: str, expected: str) -> dict[str, tuple[yaml.Node, yaml.Node]] | None:
        if not isinstance(node, yaml.MappingNode):
            self.error(node, where, expected)
            return None
        return keyed(self.path, node, self.reporter, where)

    def number(self, node: yaml.Node, where: str, low: float, high: float, *, above: bool = False,
               integer: bool = False) -> float | None:
        """A number in [low, high] (``above``: greater than low); reported otherwise."""
        value = _value(node)
        kinds = (int,) if integer else (int, float)
        fits = isinstance(value, kinds) and not isinstance(value, bool) and math.isfinite(value) and (
            value > low if above else value >= low) and value <= high
        if not fits:
            bounds = f"above {low:g} and at most {high:g}" if above else f"from {low:g} to {high:g}"
            self.error(node, where, f"{'an integer' if integer else 'a number'} {bounds}")
            return None
        return value

    def numbers(self, node: yaml.Node, where: str, count: int, high: float = FAR) -> None:
        """A list of at least ``count`` numbers within ``high`` in magnitude."""
        if not isinstance(node, yaml.SequenceNode) or len(node.value) < count:
            self.error(node, where, f"a list of {count} numbers")
            return
        for i, item in enumerate(node.value):
            self.number(item, f"{where}[{i}]", -high, high)

    def world(self, node: yaml.Node) -> None:
        fields = self.fields(node, "world", "a mapping (width, height, step_time...)")
        for key, (_, value) in (fields or {}).items():
            if key in ("width", "height"):
                self.number(value, f"world: {key}", 0, FAR, above=True)
            elif key in ("step_time", "sample_time"):
                self.number(value, f"world: {key}", 0, 10, above=True)
            elif key == "offset":
                self.numbers(value, "world: offset", 2)
            elif key == "collision_mode" and _value(value) not in COLLISION_MODES:
                self.error(value, "world: collision_mode", f"one of {', '.join(COLLISION_MODES)}")

    def objects(self, node: yaml.Node, what: str) -> list[dict[str, tuple[yaml.Node, yaml.Node]]]:
        """The entries of ``robot`` or ``obstacle``: a mapping or a list of mappings, each checked."""
        items = node.value if isinstance(node, yaml.SequenceNode) else [node]
        out = []
        for i, item in enumerate(items):
            where = f"{what}[{i}]" if isinstance(node, yaml.SequenceNode) else what
            fields = self.fields(item, where, "a mapping (shape, state...)")
            if fields is None:
                continue
            out.append(fields)
            if "number" in fields:
                self.number(fields["number"][1], f"{where}: number", 1, MAX_OBJECTS, integer=True)
            if "state" in fields:
                self.numbers(fields["state"][1], f"{where}: state", 2)
            if "shape" in fields:
                self.shape(fields["shape"][1], f"{where}: shape")
        return out

    def shape(self, node: yaml.Node, where: str) -> None:
        fields = self.fields(node, where, "a mapping with a name (circle, rectangle, polygon, linestring...)")
        if fields is None:
            return
        if not isinstance(_value(fields.get("name", (None, node))[1]), str):
            self.error(fields.get("name", (None, node))[1], f"{where}: name", "a shape name")
        for key in ("radius", "length", "width"):
            if key in fields:
                self.number(fields[key][1], f"{where}: {key}", 0, FAR, above=True)
        if "vertices" in fields:
            vertices = fields["vertices"][1]
            if not isinstance(vertices, yaml.SequenceNode) or len(vertices.value) < 2:
                self.error(vertices, f"{where}: vertices", "a list of at least 2 points [x, y]")
            else:
                for i, point in enumerate(vertices.value):
                    self.numbers(point, f"{where}: vertices[{i}]", 2)

    def robot(self, fields: dict[str, tuple[yaml.Node, yaml.Node]], node: yaml.Node) -> None:
        """The robot DALA's codels drive: a diff-drive base with a lidar2d, speeds and lidar within range."""
        if "kinematics" not in fields:
            self.reporter.error(span_of(self.path, node), "robot: kinematics {name: diff} expected (DALA drives a "
                                                          "differential-drive base)")
        else:
            kinematics = self.fields(fields["kinematics"][1], "robot: kinematics", "a mapping {name: diff}")
            name = (kinematics or {}).get("name", (None, fields["kinematics"][1]))[1]
            if kinematics is not None and _value(name) != "diff":
                self.error(name, "robot: kinematics: name", "diff (DALA drives a differential-drive base)")
        for key in ("vel_max", "vel_min", "acce"):
            if key in fields:
                self.numbers(fields[key][1], f"robot: {key}", 2, high=1e3)
        sensors = fields.get("sensors", (None, node))[1]
        lidars = [s for s in (sensors.value if isinstance(sensors, yaml.SequenceNode) else [])
                  if isinstance(s, yaml.MappingNode) and any(k.value == "name" and v.value == "lidar2d"
                                                             for k, v in s.value)]
        if not lidars:
            self.error(sensors, "robot: sensors", "a list with a lidar2d (LaserRF reads it)")
            return
        lidar = {str(k.value): v for k, v in lidars[0].value}
        low = self.number(lidar["range_min"], "lidar2d: range_min", 0, FAR) if "range_min" in lidar else 0
        if "range_max" in lidar:
            self.number(lidar["range_max"], "lidar2d: range_max", low or 0, FAR, above=True)
        if "number" in lidar:
            self.number(lidar["number"], "lidar2d: number", 1, 10_000, integer=True)
        if "angle_range" in lidar:
            self.number(lidar["angle_range"], "lidar2d: angle_range", 0, 2 * math.pi + 1e-9, above=True)


def _value(node: Any) -> Any:
    """The Python value of a scalar node (None for a collection)."""
    if not isinstance(node, yaml.ScalarNode):
        return None
    return yaml.constructor.SafeConstructor().construct_object(node)


def check_world(path: str | Path, reporter: Reporter | None = None) -> None:
    """Raise DiagnosticError naming every problem of the world file ``path`` (file:line:column, what was expected)."""
    path = Path(path)
    reporter = reporter or Reporter()
    ok, root = compose_file(path, reporter, "world file")
    if ok:
        _check(_Checker(path, reporter), root)
    reporter.raise_if_errors()


def _check(checker: _Checker, root: yaml.Node | None) -> None:
    """The top of the file: its keys, the world, the robots (the first one DALA's), the obstacles."""
    top = checker.fields(root, "a world file", "a mapping of world, robot and obstacle") if root is not None else None
    if top is None:
        if root is None:
            checker.reporter.error(Span(str(checker.path), 1, 1), "a world file is a mapping of world, robot and "
                                                                  "obstacle: this one is empty")
        return
    if "irsim" in top and isinstance(top["irsim"][1], yaml.MappingNode):  # shared with another simulator
        top = {str(k.value): (k, v) for k, v in top["irsim"][1].value}
    for key, (knode, _) in top.items():
        if key not in KEYS:
            close = difflib.get_close_matches(key, KEYS, n=1)
            checker.reporter.error(span_of(checker.path, knode), f"unknown key '{key}' (keys: {', '.join(KEYS)})",
                                   f"did you mean '{close[0]}'?" if close else None)
    if "world" in top:
        checker.world(top["world"][1])
    if "robot" not in top:
        checker.reporter.error(span_of(checker.path, root), "a world file needs a robot (DALA's codels drive one)")
    else:
        robots = checker.objects(top["robot"][1], "robot")
        if robots:
            checker.robot(robots[0], top["robot"][1])
        elif isinstance(top["robot"][1], yaml.SequenceNode) and not top["robot"][1].value:
            checker.error(top["robot"][1], "robot", "a robot (a mapping, or a list of them)")
    if "obstacle" in top and not (isinstance(top["obstacle"][1], yaml.ScalarNode) and _value(top["obstacle"][1])
                                  is None):
        checker.objects(top["obstacle"][1], "obstacle")
