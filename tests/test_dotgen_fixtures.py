"""Whole GenoM3 descriptions from tests/fixtures/genom3: the demo mobile, a permanent activity, includes."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from genom2bip.ir import BaseType, CodelParam, Duration, NamedType, SequenceType, to_json
from genom2bip.parser import parse_paths

FIXTURES = Path(__file__).parent / "fixtures" / "genom3"


@pytest.fixture(scope="module")
def demo():
    d = parse_paths([FIXTURES / "demo.gen"])
    return d, d.component("demo")


def test_demo_types_constants_and_pragma(demo):
    d, _ = demo
    assert d.constants["demo_types::max_speed"].value == 1.5
    assert d.constants["demo_types::history"].value == 16
    assert [m.name for m in d.types["demo_types::state"].members] == ["position", "speed"]
    assert d.types["demo_types::mode"].enumerators == ["IDLE", "MOVING", "STOPPED"]
    assert [(p.name, p.arguments, p.span.line) for p in d.pragmas] == [("requires", '"demo-types >= 1.0"', 4)]
    assert set(d.exceptions) == {"demo::out_of_range", "demo::too_fast"}


def test_demo_component_properties_ids_and_ports(demo):
    _, c = demo
    assert c.properties["doc"] == "A one-axis mobile used by the tests."
    assert c.properties["require"] == ["demo-types >= 1.0"]
    assert c.properties["codels-require"] == ["libdemo"]
    assert [(m.name, m.type) for m in c.ids] == [
        ("state", NamedType("demo_types::state")), ("speed_ref", BaseType("double")),
        ("mode", NamedType("demo_types::mode")), ("trace", SequenceType(BaseType("double"), 16))]
    mobile, target = c.ports
    assert (mobile.name, mobile.direction, mobile.type, mobile.doc) == (
        "Mobile", "out", NamedType("demo_types::state"), "The current state of the mobile.")
    assert (target.name, target.direction) == ("Target", "in")


def test_demo_motion_task(demo):
    _, c = demo
    (t,) = c.tasks
    assert (t.name, t.period, t.priority, t.stack) == ("motion", Duration(0.05, "50 ms"), 50, 8192)
    assert [(k.name, k.triggers, [str(y) for y in k.yields]) for k in t.codels] == [
        ("motion_start", ["start"], ["main"]),
        ("motion_main", ["main"], ["pause::main", "stop"]),
        ("motion_stop", ["stop"], ["ether"]),
    ]
    assert t.codels[1].params == [CodelParam("state", "inout", "ids"), CodelParam("Mobile", "out", "port")]
    assert t.throws == ["demo::out_of_range"]


def test_demo_services(demo):
    _, c = demo
    assert [(s.name, s.kind) for s in c.services] == [
        ("SetSpeed", "attribute"), ("Stop", "function"), ("GoTo", "activity"), ("MoveDistance", "activity")]
    set_speed = c.service("SetSpeed")
    (p,) = set_speed.parameters
    assert (p.name, p.source, p.member, p.default, p.doc) == (
        "speed_ref",
        "ids",
        "speed_ref",
        0.5,
        "Reference speed (m/s)",
    )
    assert set_speed.validate.name == "check_speed" and set_speed.validate.wcet == Duration(1e-05, "10 us")
    assert set_speed.validate.params == [CodelParam("speed_ref", "in", "local")]
    assert set_speed.throws == ["demo::too_fast"]

    stop = c.service("Stop")
    assert stop.interrupts == ["GoTo", "MoveDistance"] and stop.codels[0].name == "stop_motion"

    goto = c.service("GoTo")
    assert goto.task == "motion" and goto.validate.name == "check_position"
    assert goto.states() == ["start", "drive", "stop"]
    assert [[str(y) for y in k.yields] for k in goto.codels] == [
        ["drive", "ether"],
        ["pause::drive", "ether"],
        ["ether"],
    ]
    assert [k.wcet and k.wcet.seconds for k in goto.codels] == [0.001, 0.002, None]
    assert goto.interrupts == ["GoTo"] and goto.throws == ["demo::out_of_range", "demo::too_fast"]
    (pos,) = goto.parameters
    assert (pos.name, pos.type, pos.source, pos.default, pos.doc) == (
        "position", BaseType("double"), "local", 0.0, "Target position (m)")

    move = c.service("MoveDistance")
    assert [m.name for m in move.locals] == ["start"] and move.after == ["SetSpeed"]
    assert move.codels[1].params[2] == CodelParam("state", "inout", "ids", "s")
    assert move.parameters[0].default is None and move.parameters[0].doc == "Distance to move (m)"


def test_demo_spans_point_into_the_file(demo):
    _, c = demo
    goto = c.service("GoTo")
    assert Path(goto.span.file).name == "demo.gen" and (goto.span.line, goto.span.column) == (65, 12)
    assert (goto.codels[1].span.line, goto.codels[1].span.column) == (70, 19)
    assert goto.codels[1].yields[0].span.line == 71


def test_demo_is_json_serialisable(demo):
    d, _ = demo
    text = json.dumps(to_json(d))
    assert '"GoTo"' in text and '"pause": true' in text


def test_permanent_activity_component():
    d = parse_paths([FIXTURES / "counter.gen"])
    c = d.component("counter")
    (t,) = c.tasks
    assert (t.period.seconds, t.delay.seconds, t.scheduling) == (0.01, 0.002, "real-time")
    assert [(k.name, k.triggers, [str(y) for y in k.yields], k.is_async) for k in t.codels] == [
        ("clock_init", ["start"], ["count"], True),
        ("clock_count", ["count"], ["pause::count", "pause::idle", "stop"], False),
        ("clock_idle", ["idle"], ["pause::idle", "pause::count"], False),
        ("clock_stop", ["stop"], ["ether"], False),
    ]
    get, set_ = c.services
    assert [(p.direction, p.name, p.source) for p in get.parameters] == [("out", "ticks", "ids")]
    assert set_.parameters[0].default is True


def test_includes_guards_pragmas_and_provided_interface():
    d = parse_paths([FIXTURES / "include" / "main.gen"], include_dirs=[str(FIXTURES / "include" / "idl")])
    # one copy despite three inclusions; each ids block is a struct type of its scope
    assert set(d.types) == {"geo::point", "geo::path", "navigation::ids", "rover::ids"}
    assert [(p.name, p.arguments) for p in d.pragmas] == [("requires", '"geometry >= 2.0"')]
    assert Path(d.pragmas[0].span.file).name == "types.idl" and d.pragmas[0].span.line == 4
    c = d.component("rover")
    assert c.properties["require"] == ["geometry >= 2.0"]
    assert c.provides == ["navigation"]
    assert [m.name for m in c.ids] == ["goal", "range"]
    assert [p.name for p in c.ports] == ["Goal"]
    assert [s.name for s in c.services] == ["SetGoal", "Follow"]
    assert c.service("SetGoal").throws == ["navigation::blocked"]
    assert [k.name for k in c.service("Follow").codels] == ["follow_start"]
    assert d.constants["rover::range_max"].value == 10
    assert Path(d.interfaces["navigation"].span.file).name == "shared.idl"


def test_defines_select_conditional_text():
    d = parse_paths([FIXTURES / "include" / "main.gen"], include_dirs=[str(FIXTURES / "include" / "idl")],
                    defines={"WITH_LASER": "1"})
    assert d.constants["rover::range_max"].value == 30


def test_directory_argument_reads_every_gen_file_sorted():
    d = parse_paths([FIXTURES])
    assert [c.name for c in d.components] == ["counter", "demo"]


def test_every_node_of_the_demo_has_a_span(demo):
    from dataclasses import fields, is_dataclass

    from runtime.diagnostics import NOWHERE

    missing = []

    def walk(node, path):
        if is_dataclass(node) and not isinstance(node, type):
            for f in fields(node):
                value = getattr(node, f.name)
                if f.name == "span":
                    if value is NOWHERE or value.line < 1:
                        missing.append(path)
                elif f.name != "ref_spans":
                    walk(value, f"{path}.{f.name}")
        elif isinstance(node, dict):
            for k, v in node.items():
                walk(v, f"{path}[{k!r}]")
        elif isinstance(node, list):
            for i, v in enumerate(node):
                walk(v, f"{path}[{i}]")

    d, _ = demo
    walk(d, "description")
    assert missing == []
