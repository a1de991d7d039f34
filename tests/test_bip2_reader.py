"""The BIP2 reader builds the model the text says: structure, literals, annotations, define nesting."""
from pathlib import Path

import pytest

from runtime.bip2 import parse_file, parse_text
from runtime.bip2.defines import interactions
from runtime.diagnostics import DiagnosticError
from runtime.model import (
    Annotation, Assign, Binary, Call, Const, DefineGroup, DefinePort, Do, If, InteractionPattern, PortData, PortRef,
    Unary, Var,
)

FIXTURES = Path(__file__).parent / "fixtures" / "bip" / "roundtrip"


def read(name):
    return parse_file(FIXTURES / f"{name}.bip")


def guard_of(text):
    """The guard of one transition, read from a minimal package."""
    pkg = parse_text(f"package P extern function int f(const int) atom type A() data int x data int y "
                     f"port type_ q() place S initial to S internal from S to S provided ({text}) end end"
                     .replace("port type_ q()", ""))
    return pkg.atom_types[0].transitions[0].guard


def test_philosophers_structure():
    pkg = read("rt_philosophers")
    assert pkg.name == "rt_philosophers"
    phil = pkg.atom_type("Philosopher")
    assert phil.places == ["Thinking", "Eating"]
    assert phil.initial.targets == ["Thinking"]
    assert [(t.port, t.sources, t.targets) for t in phil.transitions] == [
        ("take", ["Thinking"], ["Eating"]), ("release", ["Eating"], ["Thinking"])]
    table = pkg.compound_type("Table")
    assert [c.name for c in table.components] == ["p0", "p1", "p2", "p3", "f0", "f1", "f2", "f3"]
    take3 = table.connector("take3")
    assert take3.ports == [PortRef("p3", "take"), PortRef("f3", "take"), PortRef("f0", "take")]


def test_broadcast_define_and_data_transfer():
    pkg = read("rt_broadcast")
    cast = pkg.connector_type("Broadcast3")
    assert cast.define == DefineGroup([DefinePort("s", True), DefinePort("r1"), DefinePort("r2")])
    assert sorted(sorted(i) for i in interactions(cast.define)) == [
        ["r1", "r2", "s"], ["r1", "s"], ["r2", "s"], ["s"]]
    full = cast.interactions[-1]
    assert full.ports == ["s", "r1", "r2"]
    assert full.guard == Binary(">", PortData("s", "v"), Const(0))
    assert full.up == [If(Binary(">", PortData("r1", "v"), PortData("r2", "v")),
                          (Assign(Var("best"), PortData("r1", "v")),), (Assign(Var("best"), PortData("r2", "v")),))]
    assert full.down[0] == Assign(PortData("r1", "v"), Binary("+", PortData("s", "v"), Var("best")))
    receiver = pkg.atom_type("Receiver")
    internal = [t for t in receiver.transitions if t.internal]
    assert len(internal) == 1 and internal[0].sources == ["Idle"] and internal[0].targets == ["Full"]


def test_hierarchy_exports_get_their_types_from_targets():
    pkg = read("rt_hierarchy")
    twin = pkg.compound_type("Twin")
    assert [(e.name, e.type, [str(t) for t in e.targets]) for e in twin.ports] == [
        ("put", "IntPort", ["both.ab"]), ("get", "IntPort", ["left.get", "right.get"]), ("tick", "Port", ["t.out"])]
    assert [(d.name, d.type, str(d.target)) for d in twin.data] == [("first", "int", "left.value")]
    system = pkg.compound_type("System")
    assert system.connector("chain").ports == [PortRef("upper", "ab"), PortRef("spare", "put")]
    assert system.data[0].type == "int"  # through Twin's export of Cell's data
    pair = pkg.connector_type("Pair")
    assert pair.export.port_type == "IntPort" and pair.export.data == ["sum"]
    twin_args = [c.args for c in system.components]
    assert twin_args == [[Const(1)], [Const(2)], [Const(0)]]


def test_priorities_in_atoms_and_compounds():
    pkg = read("rt_priorities")
    worker = pkg.atom_type("Worker")
    assert [(p.name, p.low, p.high) for p in worker.priorities] == [
        ("restFirst", "work", "rest"), ("reportLast", "report", "*"), ("idleLast", "idle", "*")]
    assert worker.priorities[0].guard == Binary(">", Var("load"), Const(5))
    assert worker.priorities[1].guard is None
    shop = pkg.compound_type("Shop")
    alone, busy, reports, balance = shop.priorities
    assert alone.low == InteractionPattern("resting", [PortRef("w1", "rest")])
    assert alone.high == InteractionPattern("resting", [PortRef("w1", "rest"), PortRef("w2", "rest")])
    assert busy.low == InteractionPattern("together", None)
    assert busy.guard == Binary(">", Binary("+", PortData("w1", "load"), PortData("w2", "load")), Const(8))
    assert reports.high == InteractionPattern("*", None)
    assert balance.guard is not None


def test_externs_constants_and_annotations():
    pkg = read("rt_externs")
    assert pkg.annotations == [Annotation("cpp", {"include": "rt_externs.hpp,stdio.h", "src": "rt_externs.cpp"}),
                               Annotation("generated")]
    assert [c.name for c in pkg.constants] == ["N", "LIMIT", "EPSILON", "HALF", "BELOW", "GREETING", "VERBOSE"]
    consts = {c.name: c.value for c in pkg.constants}
    assert consts["EPSILON"] == Const(1e-06)
    assert consts["BELOW"] == Const(-3)
    assert consts["GREETING"] == Const('hello "BIP"\n\tbye \\ é')
    assert consts["VERBOSE"] == Const(False)
    assert pkg.constants[5].annotations == [
        Annotation("doc", {"text": 'a greeting with "quotes", a tab\tand a newline\n'})
    ]
    assert pkg.extern_types == ["Pose", "Map"]
    assert pkg.extern_type_annotations == {"Pose": [Annotation("cpp", {"include": "pose.hpp"})]}
    log = [f for f in pkg.extern_functions if f.name == "log"]
    assert [(f.return_type, f.param_types) for f in log] == [(None, ["string"]), (None, ["string", "int"])]
    near = next(f for f in pkg.extern_functions if f.name == "near")
    assert near.param_types == ["Pose", "Pose", "float"] and near.param_const == [True, True, True]
    assert [(p.name, p.const) for p in pkg.port_type("Reading").params] == [("v", True), ("error_bound", False)]
    step = next(f for f in pkg.extern_functions if f.name == "step")
    assert step.param_const == [False, False]
    assert step.annotations == [Annotation("outcomes", {"ok": "", "fail": ""})]
    robot = pkg.atom_type("Robot")
    assert robot.params[1].type == "float"
    assert robot.variable("MAXSTEPS").const and robot.variable("pose").exported
    assert robot.variable("pose").annotations == [Annotation("label", {"name": "the pose"})]
    assert [d.name for d in robot.data][3:5] == ["steps", "status"]  # "data int steps = 0, status = 0"
    assert robot.port("where").annotations == [Annotation("annotated")]
    assert robot.initial.targets == ["Idle", "Sensing"]
    assert robot.initial.action[2] == Do(Call("log", (Var("GREETING"),)))
    where = robot.transitions[1]
    assert where.sources == ["Moving", "Sensing"] and where.annotations == [Annotation("trace", {"level": "2"})]
    exchange = pkg.connector_type("Exchange")
    assert exchange.annotations == [Annotation("cpp", {"name": "rdv"})]
    assert exchange.data[0].annotations == [Annotation("scratch")]
    assert exchange.export.annotations == [Annotation("exported")]
    assert exchange.interactions[0].annotations == [Annotation("interaction", {"kind": "exchange"})]
    fleet = pkg.compound_type("Fleet")
    assert fleet.components[0].annotations == [Annotation("first")]
    assert fleet.connectors[0].annotations == [Annotation("swap")]
    assert fleet.ports[0].annotations == [Annotation("public")]
    assert fleet.data[0].annotations == [Annotation("public", {"read": "true"})]
    assert fleet.data[0].type == "Pose"


def test_service_fixture_reads():
    pkg = read("rt_service")
    module = pkg.compound_type("Module")
    assert module.components[-1].args == [Var("PERIOD")]
    assert pkg.connector_type("Transfer").params[0].name == "from_"


@pytest.mark.parametrize("text, tree", [
    ("x + y * 2", Binary("+", Var("x"), Binary("*", Var("y"), Const(2)))),
    ("x - y - 1", Binary("-", Binary("-", Var("x"), Var("y")), Const(1))),
    ("x - (y - 1)", Binary("-", Var("x"), Binary("-", Var("y"), Const(1)))),
    ("x < 1 && y >= 2 || !(x == y)", Binary("||", Binary("&&", Binary("<", Var("x"), Const(1)),
                                                          Binary(">=", Var("y"), Const(2))),
                                          Unary("!", Binary("==", Var("x"), Var("y"))))),
    ("x | y ^ x & 3 == 1", Binary("|", Var("x"), Binary("^", Var("y"), Binary("&", Var("x"),
                                                                           Binary("==", Const(3), Const(1)))))),
    ("-1", Const(-1)),
    ("- 2.5e3", Const(-2500.0)),
    ("-(1)", Unary("-", Const(1))),
    ("-x % 3", Binary("%", Unary("-", Var("x")), Const(3))),
    ("~x", Unary("~", Var("x"))),
    ("f(x + 1) > .5", Binary(">", Call("f", (Binary("+", Var("x"), Const(1)),)), Const(0.5))),
    ("x == 1.", Binary("==", Var("x"), Const(1.0))),
    ('"a\\101\\u0042\\n" == "AB"', Binary("==", Const("aAB\n"), Const("AB"))),
    ("true != false", Binary("!=", Const(True), Const(False))),
])
def test_expression_precedence_and_literals(text, tree):
    assert guard_of(text) == tree


def test_comments_are_ignored_and_multi_declarations_split():
    pkg = parse_text("""
        // line comment
        package P /* block
        comment */ port type T()
          atom type A() data int a = 1, b, c = a export port T p(), q() place S initial to S end
          compound type K() component A x(), y() end
        end""")
    atom = pkg.atom_types[0]
    assert [(d.name, d.init) for d in atom.data] == [("a", Const(1)), ("b", None), ("c", Var("a"))]
    assert [(p.name, p.exported) for p in atom.ports] == [("p", True), ("q", True)]
    assert [c.name for c in pkg.compound_types[0].components] == ["x", "y"]


def test_define_nesting_and_quotes():
    pkg = parse_text("package P port type T() connector type C(T a, T b, T c, T d) "
                     "define ((a b)' c)' d on a b c d provided (true) down { } on a b provided (true) end end")
    define = pkg.connector_types[0].define
    assert define == DefineGroup([DefineGroup([DefineGroup([DefinePort("a"), DefinePort("b")], True),
                                               DefinePort("c")], True), DefinePort("d")])
    assert pkg.connector_types[0].interactions[0].down == []  # "down { }" is no action


def test_older_export_form_with_type_is_read():
    pkg = parse_text("package P port type T() atom type A() data int x export data int y export port T p() place S "
                     "initial to S end compound type K() component A a() export port T q is a.p "
                     "export data int z is a.y end end")
    k = pkg.compound_types[0]
    assert (k.ports[0].type, k.ports[0].name, k.ports[0].targets) == ("T", "q", [PortRef("a", "p")])
    assert (k.data[0].type, k.data[0].name) == ("int", "z")


def test_spans_point_at_names():
    pkg = parse_text(
        "package P\n  port type T()\n  atom type A()\n    place S\n    initial to S\n  end\nend\n", "m.bip"
    )
    atom = pkg.atom_types[0]
    assert (atom.span.file, atom.span.line, atom.span.column) == ("m.bip", 3, 13)
    assert (pkg.port_types[0].span.line, pkg.port_types[0].span.column) == (2, 13)


def test_file_must_be_named_after_package(tmp_path):
    path = tmp_path / "Other.bip"
    path.write_text("package P port type T() end\n")
    with pytest.raises(DiagnosticError) as err:
        parse_file(path)
    d = err.value.diagnostics[0]
    assert "package 'P' must be in a file named P.bip, not Other.bip" in d.message
    assert (d.span.line, d.span.column) == (1, 9)
    good = tmp_path / "P.bip"
    good.write_text("package P port type T() end\n")
    assert parse_file(good).port_types[0].name == "T"


def test_missing_file_is_a_diagnostic(tmp_path):
    with pytest.raises(DiagnosticError) as err:
        parse_file(tmp_path / "Nope.bip")
    assert "cannot read BIP2 file" in str(err.value)


def test_used_packages_and_qualified_names():
    text = ("package P use Q use R.S port type T() compound type K() component Q.Atom a(1) "
            "connector Q.Rdv c(a.p, a.q) export port a.p as p end end")
    pkg = parse_text(text)
    assert pkg.uses == ["Q", "R.S"]
    k = pkg.compound_types[0]
    assert k.components[0].type == "Q.Atom" and k.connectors[0].type == "Q.Rdv"
    assert k.ports[0].type == ""  # its type lives in package Q, which the reader does not load
    with pytest.raises(DiagnosticError) as err:
        parse_text(text.replace("use Q use R.S ", ""))
    assert err.value.diagnostics[0].hint == "a qualified name needs: use Q"


def test_merged_atom_port_export():
    pkg = read("rt_merged")
    src = pkg.atom_types[0]
    assert [(p.name, p.data, p.exported, p.export_as) for p in src.ports] == [
        ("p", ["x"], True, "out"), ("q", ["y"], True, "out"), ("r", ["z"], True, "out")]
    assert [p.name for p in src.exported_ports("out")] == ["p", "q", "r"] and src.exported_ports("p") == []
