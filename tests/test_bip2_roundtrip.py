"""read(write(m)) == m and write(read(text)) is stable, on every fixture, on models built in code, and on random
guards and actions."""
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from genom2bip.back.bip2 import BINARY_OPERATORS, UNARY_OPERATORS, write_package
from genom2bip.generate import write_bip_file
from runtime.bip2 import parse_file, parse_text
from runtime.model import (
    Annotation, Assign, AtomPriority, AtomType, Binary, Call, ComponentInstance, CompoundType, ConnectorExport,
    ConnectorInstance, ConnectorParam, ConnectorType, Const, Constant, DataDecl, DataParam, DefineGroup, DefinePort,
    Do, ExportData, ExportPort, ExternFunction, If, InitialTransition, InteractionPattern, InteractionSpec, Package,
    PortData, PortDecl, PortRef, PortType, Priority, Transition, Unary, Var,
)

FIXTURES = sorted((Path(__file__).parent / "fixtures" / "bip" / "roundtrip").glob("*.bip"))


def roundtrip(model: Package) -> str:
    text = write_package(model)
    again = parse_text(text, f"{model.name}.bip")
    assert again == model
    assert write_package(again) == text
    return text


@pytest.mark.parametrize("path", FIXTURES, ids=lambda p: p.stem)
def test_fixture_roundtrip(path):
    model = parse_file(path)
    roundtrip(model)


@pytest.mark.parametrize("path", FIXTURES, ids=lambda p: p.stem)
def test_written_file_reads_back(path, tmp_path):
    model = parse_file(path)
    written = write_bip_file(model, tmp_path)
    assert written == tmp_path / f"{model.name}.bip"
    assert parse_file(written) == model
    assert [p.name for p in tmp_path.iterdir()] == [written.name]  # no temp file left


def test_fixture_set_covers_every_construct():
    models = [parse_file(p) for p in FIXTURES]
    atoms = [a for m in models for a in m.atom_types]
    conns = [c for m in models for c in m.connector_types]
    comps = [k for m in models for k in m.compound_types]
    assert any(t.internal for a in atoms for t in a.transitions)
    assert {p.policy for a in atoms for p in a.ports if p.extern} == {"remember", "ignore", "error", None}
    assert any(len(t.sources) > 1 for a in atoms for t in a.transitions)
    assert any(len(a.initial.targets) > 1 for a in atoms)
    assert any(p.guard is not None and "*" in (p.low, p.high) for a in atoms for p in a.priorities)
    assert any(p.guard is not None for k in comps for p in k.priorities)
    assert any(p.high.connector == "*" for k in comps for p in k.priorities)
    assert any(c.export is not None and c.data for c in conns)
    assert any(s.up and s.down for c in conns for s in c.interactions)
    assert any(any(i.trigger for i in c.define.items) and len(c.define.items) > 2 for c in conns)
    assert any(k.connector(r.component) for k in comps for c in k.connectors for r in c.ports)  # nested connectors
    assert any(m.compound_type(c.type) for m in models for k in m.compound_types for c in k.components)
    assert any(k.data for k in comps) and any(len(e.targets) > 1 for k in comps for e in k.ports)
    assert any(m.extern_types and m.extern_functions and m.constants and m.annotations for m in models)
    assert any(isinstance(s, If) and s.orelse for a in atoms for t in a.transitions for s in t.action)


def small_model() -> Package:
    """A model as a generator would build it: every field set by hand, with comments (not compared)."""
    port = PortType("Port")
    int_port = PortType("IntPort", [DataParam("int", "v")], annotations=[Annotation("mapping")])
    atom = AtomType(
        "Counter", params=[DataParam("int", "limit")],
        data=[DataDecl("int", "n", Const(0), exported=True), DataDecl("int", "k", Var("limit"), const=True)],
        ports=[PortDecl("IntPort", "inc", ["n"], exported=True), PortDecl("Port", "reset", [], exported=True)],
        places=["Low", "High"],
        initial=InitialTransition(["Low"], [Assign(Var("n"), Const(0))]),
        transitions=[
            Transition("inc", ["Low"], ["Low"], Binary("<", Var("n"), Var("k")),
                       [Assign(Var("n"), Binary("+", Var("n"), Const(1)))]),
            Transition(None, ["Low"], ["High"], Binary(">=", Var("n"), Var("k"))),
            Transition("reset", ["High"], ["Low"], None, [Do(Call("note", (Const("reset"),)))],
                       annotations=[Annotation("why", {"text": "back to zero"})]),
        ],
        priorities=[AtomPriority("resetFirst", "inc", "reset", Binary("==", Var("n"), Const(-1)))],
    )
    sync = ConnectorType(
        "Sync", [ConnectorParam("IntPort", "a"), ConnectorParam("IntPort", "b")],
        DefineGroup([DefinePort("a", True), DefinePort("b")]),
        data=[DataDecl("int", "m")],
        export=ConnectorExport("IntPort", "out", ["m"]),
        interactions=[InteractionSpec(["a"], None, [Assign(Var("m"), PortData("a", "v"))]),
                      InteractionSpec(["a", "b"], Binary("!=", PortData("a", "v"), PortData("b", "v")),
                                      [Assign(Var("m"), PortData("a", "v"))], [Assign(PortData("b", "v"), Var("m"))])],
    )
    single = ConnectorType("Single", [ConnectorParam("Port", "p")], DefineGroup([DefinePort("p")]))
    top = CompoundType(
        "Top", params=[DataParam("int", "size")],
        components=[ComponentInstance("Counter", "c1", [Var("size")]),
                    ComponentInstance("Counter", "c2", [Binary("*", Var("size"), Const(2))])],
        connectors=[ConnectorInstance("Sync", "s", [PortRef("c1", "inc"), PortRef("c2", "inc")],
                                      comment="both counters move together"),
                    ConnectorInstance("Single", "r1", [PortRef("c1", "reset")]),
                    ConnectorInstance("Single", "r2", [PortRef("c2", "reset")])],
        priorities=[Priority("resetsFirst", InteractionPattern("s", None), InteractionPattern("r1", None),
                             Binary(">", PortData("c1", "n"), Const(3)), comment="line one\nline two")],
        ports=[ExportPort("IntPort", "out", [PortRef("s", "out")])],
        data=[ExportData("int", "first", PortRef("c1", "n"))],
    )
    outer = CompoundType("Outer", components=[ComponentInstance("Top", "t", [Const(3)])],
                         ports=[ExportPort("IntPort", "out", [PortRef("t", "out")])],
                         data=[ExportData("int", "seen", PortRef("t", "first"))])
    return Package(
        "Small", constants=[Constant("int", "MAX", Const(10))], extern_types=["Blob"],
        extern_functions=[ExternFunction("note", None, ["string"]), ExternFunction("size_of", "int", ["Blob"])],
        port_types=[port, int_port], atom_types=[atom], connector_types=[sync, single],
        compound_types=[top, outer], annotations=[Annotation("cpp", {"include": "small.hpp"})],
        extern_type_annotations={"Blob": [Annotation("cpp", {"include": "blob.hpp"})]},
    )


def test_model_built_in_code_roundtrips():
    text = roundtrip(small_model())
    assert "    // both counters move together\n    connector Sync s(c1.inc, c2.inc)\n" in text
    assert "    // line one\n    // line two\n    priority resetsFirst s:* < r1:*" in text


# ---------------------------------------------------------------------- random guards and actions
NAMES = st.sampled_from(["a", "b", "c"])
FLOATS = st.floats(allow_nan=False, allow_infinity=False)
LITERALS = st.one_of(st.booleans(), st.integers(-10**12, 10**12), FLOATS, st.text(max_size=8)).map(Const)


def expressions():
    leaves = st.one_of(NAMES.map(Var), LITERALS)
    return st.recursive(leaves, lambda inner: st.one_of(
        st.builds(Unary, st.sampled_from(UNARY_OPERATORS), inner),
        st.builds(Binary, st.sampled_from(BINARY_OPERATORS), inner, inner),
        st.builds(lambda x, y: Call("f", (x, y)), inner, inner),
        inner.map(lambda x: Call("g", (x,))),
    ), max_leaves=12)


def statements():
    simple = st.one_of(st.builds(Assign, NAMES.map(Var), expressions()),
                       expressions().map(lambda e: Do(Call("h", (e,)))))
    return st.recursive(simple, lambda inner: st.builds(
        If, expressions(), st.lists(inner, min_size=1, max_size=3).map(tuple),
        st.lists(inner, max_size=2).map(tuple)), max_leaves=6)


def host(guard, action) -> Package:
    return Package(
        "Random",
        extern_functions=[ExternFunction("f", "int", ["int", "int"], param_const=[True, True]),
                          ExternFunction("g", "int", ["int"], param_const=[True]), ExternFunction("h", None, ["int"])],
        atom_types=[AtomType("A", data=[DataDecl("int", n) for n in "abc"], places=["S"],
                             initial=InitialTransition(["S"]),
                             transitions=[Transition(None, ["S"], ["S"], guard, action)])],
    )


def test_a_string_holding_line_separators_roundtrips():
    """U+2028 and U+2029 written as is would split the line the string is on: they are escaped."""
    text = roundtrip(host(Binary("==", Var("a"), Const("x\u2028y\u2029z")), []))
    assert "\u2028" not in text and "\\u2028" in text


@settings(max_examples=300, deadline=None)
@given(expressions(), st.lists(statements(), max_size=4))
def test_random_guards_and_actions_roundtrip(guard, action):
    roundtrip(host(guard, action))
