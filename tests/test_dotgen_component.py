"""The GenoM part of the dotgen grammar: components, ids, tasks, ports, services, codels, interfaces."""
from __future__ import annotations

import pytest

from genom2bip.ir import ArrayType, BaseType, CodelParam, Duration, Member, NamedType, StringType, Yield
from genom2bip.parser import parse_text
from runtime.diagnostics import DiagnosticError


def comp(body: str, prelude: str = ""):
    return parse_text(f"{prelude}\ncomponent c {{\n{body}\n}};\n", "t.gen").components[0]


def errors(text: str) -> list:
    with pytest.raises(DiagnosticError) as info:
        parse_text(text, "t.gen")
    return info.value.diagnostics


def test_component_properties():
    c = comp('''
        doc "first " "second";
        version "1.0";
        lang "c";
        email "me@example.org";
        require "a >= 1", "b";
        requires "c";
        codels-require "eigen3";
        codels-requires "m";
        clock-rate 2 ms;
        stack 16k;
        exception e1, e2;
        throws e1;
        throw e2, e1;
    ''')
    assert c.name == "c" and c.dialect == "genom3" and c.file == "t.gen"
    p = c.properties
    assert p["doc"] == "first second" and p["version"] == "1.0" and p["lang"] == "c"
    assert p["email"] == "me@example.org"
    assert p["require"] == ["a >= 1", "b", "c"]
    assert p["codels-require"] == ["eigen3", "m"]
    assert p["stack"] == 16 * 1024
    assert c.clock_rate == Duration(0.002, "2 ms")
    assert c.throws == ["c::e1", "c::e2"]
    assert (c.span.line, c.span.column) == (2, 11)


def test_empty_and_bodyless_components():
    d = parse_text("component a; component b {};")
    assert [x.name for x in d.components] == ["a", "b"]


def test_ids_blocks_merge_in_order():
    c = comp("ids { long a; double b[2]; };\nids { string<8> name; };", "struct s { long v; };")
    assert [(m.name, m.type) for m in c.ids] == [
        ("a", BaseType("long")), ("b", ArrayType(BaseType("double"), [2])), ("name", StringType(8))]
    assert (c.ids[2].span.line, c.ids[2].span.column) == (4, 17)


def test_types_declared_in_a_component_live_in_its_scope():
    d = parse_text("component c { struct pose { double x; }; ids { pose p; }; port out pose P; };")
    assert "c::pose" in d.types
    assert d.components[0].ids[0].type == NamedType("c::pose")
    assert d.components[0].ports[0].type == NamedType("c::pose")


def test_task_properties_and_durations():
    c = comp('''
        task a { doc "main loop"; period 50 ms; delay 5ms; priority 10; stack 2 M; scheduling real-time; };
        task b { period 0.5 s; stack 4096; };
        task c { period 200 us; };
        task d { period 2; };
        task e;
    ''', "const long P = 25;")
    a, b, c_, d, e = c.tasks
    assert a.doc == "main loop" and a.priority == 10 and a.scheduling == "real-time"
    assert a.period == Duration(0.05, "50 ms") and a.delay == Duration(0.005, "5ms")
    assert a.stack == 2 * 1024 * 1024 and b.stack == 4096
    assert b.period.seconds == 0.5 and c_.period.seconds == pytest.approx(200e-6)
    assert d.period == Duration(2.0, "2 s")
    assert e.period is None and e.codels == []
    assert (a.span.line, a.span.column) == (4, 14)


def test_period_from_a_constant_expression():
    c = comp("task t { period 2 * P ms; };", "const long P = 25;")
    assert c.tasks[0].period == Duration(0.05, "2 * P ms")


def test_task_codels_form_a_permanent_activity_with_pause_transitions():
    c = comp('''
        ids { long n; };
        task t {
          period 10 ms;
          codel <start> init(ids out n) yield main;
          codel <main> step(ids inout n) yield pause::main, stop;
          codel <stop> fini() yield ether;
          throws e;
        };
    ''', "exception e;")
    t = c.tasks[0]
    assert [(k.name, k.triggers, [str(y) for y in k.yields]) for k in t.codels] == [
        ("init", ["start"], ["main"]), ("step", ["main"], ["pause::main", "stop"]), ("fini", ["stop"], ["ether"])]
    assert t.codels[1].yields[0] == Yield("main", pause=True)
    assert t.throws == ["e"]
    assert t.ref_spans["throws:e"].line == 10


def test_ports():
    c = comp('''
        port out double Speed { doc "current speed"; };
        port in sequence<long> Scan;
        port multiple out long Many;
    ''')
    speed, scan, many = c.ports
    assert (speed.name, speed.direction, speed.type, speed.multiple, speed.doc) == (
        "Speed", "out", BaseType("double"), False, "current speed")
    assert (scan.direction, many.multiple, many.direction) == ("in", True, "out")
    assert (scan.span.line, scan.span.column) == (5, 32)


def test_attribute_parameters_name_ids_members():
    c = comp('''
        ids { double v; struct pos_s { double x, y; } pos; double arr[3]; };
        attribute Set(in v = 0.5 : "speed", out pos.x::px, inout arr[1], in pos::where, in ::all);
    ''')
    params = c.services[0].parameters
    got = [(p.direction, p.name, p.source, p.member, p.type, p.default, p.doc) for p in params]
    assert got == [
        ("in", "v", "ids", "v", None, 0.5, "speed"),
        ("out", "px", "ids", "pos.x", None, None, None),
        ("inout", "arr", "ids", "arr[1]", None, None, None),
        ("in", "where", "ids", "pos", None, None, None),
        ("in", "all", "ids", "", None, None, None),
    ]
    assert c.services[0].kind == "attribute"


def test_typed_service_parameters_with_defaults_and_docs():
    c = comp('''
        function f(in double x = 1 : "x (m)", in long n[2] = {3, 4}, out string<8> s,
                   in pose p = { .x = 1.5 : "abscissa", .y = 2 } : "a pose", in double d = : "doc only",
                   inout geo::path way = { [2] = { .x = 0 }, [0] = {} });
    ''', "struct pose { double x, y; }; module geo { typedef sequence<pose> path; };")
    x, n, s, p, d, way = c.services[0].parameters
    assert (x.source, x.type, x.default, x.doc) == ("local", BaseType("double"), 1.0, "x (m)")
    assert isinstance(x.default, float)
    assert (n.type, n.default) == (ArrayType(BaseType("long"), [2]), [3, 4])
    assert (s.direction, s.type, s.default) == ("out", StringType(8), None)
    assert (p.type, p.default, p.doc, p.member_docs) == (
        NamedType("pose"),
        {"x": 1.5, "y": 2},
        "a pose",
        {"x": "abscissa"},
    )
    assert (d.default, d.doc) == (None, "doc only")
    assert way.type == NamedType("geo::path")
    assert way.default == {2: {"x": 0}, 0: []}


def test_functions_and_activities_with_all_their_properties():
    c = comp('''
        ids { double speed; };
        task motion { period 10 ms; };
        function Stop() {
          doc "stop";
          codel stop_now(ids out speed);
          interrupts Move;
        };
        activity Move(in double target) {
          doc "move";
          task motion;
          validate check(in target) wcet 5 us;
          local double start, steps[4];
          codel <start> go(in target, local out start) yield main wcet 2 ms;
          async codel <main> run(local in start, ids inout speed) yields pause::main, ether wcet 0.001 s;
          codel <stop> halt() yield ether;
          interrupt Move;
          before Stop;
          after Stop, Move;
          throw e;
        };
    ''', "exception e;")
    stop, move = c.services
    assert (stop.kind, stop.doc, stop.interrupts, stop.task) == ("function", "stop", ["Move"], None)
    assert [(k.name, k.triggers, k.yields) for k in stop.codels] == [("stop_now", [], [])]
    assert move.kind == "activity" and move.task == "motion" and move.doc == "move"
    assert (move.validate.name, move.validate.wcet) == ("check", Duration(5e-06, "5 us"))
    assert move.locals == [Member("start", BaseType("double")), Member("steps", ArrayType(BaseType("double"), [4]))]
    go, run, halt = move.codels
    assert go.wcet == Duration(0.002, "2 ms") and run.wcet.seconds == 0.001 and halt.wcet is None
    assert run.is_async and not go.is_async
    assert [str(y) for y in run.yields] == ["pause::main", "ether"]
    assert move.states() == ["start", "main", "stop"]
    assert (move.interrupts, move.before, move.after, move.throws) == (["Move"], ["Stop"], ["Stop", "Move"], ["e"])
    assert move.ref_spans["task"].line == 13 and move.ref_spans["after:Move"].column == 23


def test_codel_parameters():
    c = comp('''
        task t { codel <start, resume> f(ids in a, local out b, port out P, remote in r, inout c,
                                         in a.b[2].c, in x::alias, ids out ::whole) yield ether; };
    ''')
    (k,) = c.tasks[0].codels
    assert k.triggers == ["start", "resume"]
    assert k.params == [
        CodelParam("a", "in", "ids"), CodelParam("b", "out", "local"), CodelParam("P", "out", "port"),
        CodelParam("r", "in", "remote"), CodelParam("c", "inout", None), CodelParam("a.b[2].c", "in", None),
        CodelParam("x", "in", None, "alias"), CodelParam("", "out", "ids", "whole"),
    ]
    assert (k.params[1].span.line, k.params[1].span.column) == (4, 52)


def test_genom_keywords_are_identifiers_where_not_ambiguous():
    c = comp("""
        ids { double period; long task; long port; long doc; long s; long ms; };
        task period {
          codel <start> stop(in period, in task) yield stop, wcet; codel <stop, wcet> yield() yield ether;
        };
        function task(in double delay) { codel codel(in delay); };
    """)
    assert [m.name for m in c.ids] == ["period", "task", "port", "doc", "s", "ms"]
    assert c.tasks[0].name == "period"
    assert [(k.name, k.triggers) for k in c.tasks[0].codels] == [("stop", ["start"]), ("yield", ["stop", "wcet"])]
    assert c.services[0].name == "task" and c.services[0].parameters[0].name == "delay"


def test_interface_provides_merges_ids_ports_services_and_throws():
    d = parse_text('''
        interface nav {
          exception blocked;
          throws blocked;
          ids { double goal; };
          port out double Goal;
          function SetGoal(in goal) { doc "from the interface"; throws blocked; };
          activity Go(in double x);
        };
        component robot {
          provides nav;
          uses other;
          ids { long mine; };
          port out long Mine;
          activity Go(in double x) { codel <start> go(in x) yield ether; };
        };
    ''', "t.gen")
    r = d.component("robot")
    assert r.provides == ["nav"] and r.uses == ["other"]
    assert [m.name for m in r.ids] == ["goal", "mine"]
    assert [p.name for p in r.ports] == ["Goal", "Mine"]
    assert [s.name for s in r.services] == ["SetGoal", "Go"]
    assert r.service("SetGoal").doc == "from the interface" and r.service("SetGoal").throws == ["nav::blocked"]
    assert [k.name for k in r.service("Go").codels] == ["go"]
    assert r.throws == ["nav::blocked"]
    assert d.interfaces["nav"].services[0].name == "SetGoal"
    assert r.service("SetGoal") is not d.interfaces["nav"].services[0]


def test_interface_extends_and_pragma_provides():
    d = parse_text('''
        #pragma provides child
        interface base { function Ping(); };
        interface child { extends base; function Pong(); };
        component a { };
        component b { provide child; };
    ''', "t.gen")
    assert [s.name for s in d.interfaces["child"].services] == ["Ping", "Pong"]
    assert [s.name for s in d.component("a").services] == ["Ping", "Pong"]
    assert d.component("b").provides == ["child"] and len(d.component("b").services) == 2
    assert [(p.name, p.arguments) for p in d.pragmas] == [("provides", "child")]


def test_pragma_requires_is_added_to_every_component():
    d = parse_text('#pragma requires "vision >= 2"\ncomponent a { require "x"; };\ncomponent b;', "t.gen")
    assert d.component("a").properties["require"] == ["x", "vision >= 2"]
    assert d.component("b").properties["require"] == ["vision >= 2"]


def test_several_files_share_one_description(tmp_path):
    from genom2bip.parser import parse_paths

    (tmp_path / "a.gen").write_text("component a;\n")
    (tmp_path / "b.gen").write_text("component b { task t; };\n")
    d = parse_paths([tmp_path])
    assert [c.name for c in d.components] == ["a", "b"]
    assert [f.rsplit("/", 1)[-1] for f in d.files] == ["a.gen", "b.gen"]


@pytest.mark.parametrize("body,message,column", [
    ("port out long P { period 5 ms; };", "'period' is not a property of a port", 27),
    ("task t { validate v(); };", "'validate' is not a property of a task", 18),
    ("function f() { task t; };", "'task' is not a property of a function", 24),
    ("attribute a() { codel <start> f() yield ether; };", "attribute 'a' cannot have state machine codels", 25),
    ("period 5 ms;", "'period' is not a property of a component", 9),
    ("activity a() { codel f(); };", "codel 'f' of activity 'a' has no state", 24),
    ("task t { codel f(); };", "codel 'f' of task 't' has no state", 18),
    ("task t { period 0 ms; };", "period must be positive", 25),
])
def test_properties_in_the_wrong_place(body, message, column):
    (e,) = errors(f"component c {{\n        {body}\n}};")
    assert e.message == message and (e.span.line, e.span.column) == (2, column)


@pytest.mark.parametrize("body,message", [
    ("task t; task t;", "duplicate task 't'"),
    ("port out long P; port in long P;", "duplicate port 'P'"),
    ("function f(); activity f();", "duplicate service 'f'"),
    ("function f(in long a, in double a);", "duplicate parameter 'a' in service 'f'"),
    ("ids { long a; }; ids { double a; };", "duplicate member 'a' in the ids of 'c'"),
    ("task t { codel <start> a() yield ether; codel <start> b() yield ether; };",
     "state 'start' of task 't' is already handled by codel 'a'"),
    ("task t { codel <start, start> a() yield ether; };", "state 'start' is listed twice for codel 'a'"),
    ("task t { codel <start> a() yield ether, ether; };", "codel 'a' yields 'ether' twice"),
    ("task t { codel <pause::start> a() yield ether; };", "codel 'a' cannot be triggered by 'pause::start'"),
    ("provides nowhere;", "component 'c' provides unknown interface 'nowhere'"),
    ("attribute a(in x::y::z);", "bad parameter 'x::y::z'"),
    ("function f(in double x = \"a\");", "parameter 'x' has type double but its value 'a' is not a number"),
])
def test_errors_the_parser_can_know(body, message):
    (e,) = errors(f"component c {{ {body} }};")
    assert e.message == message


def test_a_component_declared_twice_is_reopened():
    # genom3's comp_push reopens a component; the second body adds to the first
    d = parse_text("component c { task t; };\ncomponent c { function f(); };", "t.gen")
    (c,) = d.components
    assert [t.name for t in c.tasks] == ["t"] and [s.name for s in c.services] == ["f"]


def test_a_component_and_an_interface_cannot_share_a_name():
    (e,) = errors("interface c;\ncomponent c;")
    assert e.message == "conflicting declarations of 'c': already declared as interface"
    assert (e.span.line, e.span.column) == (2, 11) and e.hint == "first declared at t.gen:1:11"
