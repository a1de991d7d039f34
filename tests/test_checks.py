"""Semantic checks: every error path, with its message and the location of the offending name."""
import pytest

from genom2bip.checks import check_description
from genom2bip.ir import (
    Codel,
    Component,
    Description,
    Duration,
    ExceptionDecl,
    NamedType,
    Port,
    Service,
    StructType,
    Task,
    Yield,
)
from genom2bip.parser import parse_text
from runtime.diagnostics import Reporter, Span

SDI = """typedef struct SPEED { double v; double w; } SPEED;
typedef struct DEMO_STR { SPEED ref; int count; } DEMO_STR;
module demo { internal_data: DEMO_STR; };
exec_task Main { period: 10; };
"""


def check(description):
    reporter = Reporter()
    check_description(description, reporter)
    return [d for d in reporter.diagnostics if d.severity == "error"], reporter


def problems(text: str, filename: str = "chk.gen"):
    """(line, column, message) of the check errors of a description that parses."""
    errors, _ = check(parse_text(text, filename))
    assert all(d.span.file == filename for d in errors)
    return [(d.span.line, d.span.column, d.message) for d in errors]


def test_a_clean_module_has_no_problem():
    assert problems(SDI + """
request Track { type: exec; exec_task: Main; codel_start: s; codel_main: m; codel_inter: i;
                interrupt_activity: Track; fail_reports: E; };
poster P { data: r::ref; exec_task: Main; };""") == []


# --------------------------------------------------------------------------- unknown names


def test_unknown_task_points_at_the_task_name():
    assert problems(SDI + "request A {\n  type: exec;\n  exec_task: Mian;\n  codel_start: f;\n};") == [
        (7, 14, "unknown task 'Mian' for activity 'A'")]


def test_unknown_task_hint():
    errors, _ = check(parse_text(SDI + "request A { type: exec; exec_task: Mian; codel_start: f; };", "x.gen"))
    assert errors[0].hint == "did you mean 'Main'?"


def test_unknown_interrupted_service():
    assert problems(SDI + "request A { type: control; interrupt_activity: B, Nope; };\n"
                          "request B { type: exec; exec_task: Main; codel_start: f; };") == [
        (5, 51, "unknown service 'Nope' in 'interrupts' of function 'A'")]


@pytest.mark.parametrize("relation", ["after", "before"])
def test_unknown_service_in_after_and_before(relation):
    service = Service("A", "function", span=Span("m.gen", 3, 5))
    setattr(service, relation, ["Ghost"])
    service.ref_spans[f"{relation}:Ghost"] = Span("m.gen", 4, 11)
    errors, _ = check(Description([Component("m", "genom3", services=[service])]))
    assert [(str(d.span), d.message) for d in errors] == [
        ("m.gen:4:11", f"unknown service 'Ghost' in '{relation}' of function 'A'")]


def test_unknown_exception_is_reported_at_its_name():
    service = Service("A", "function", throws=["e_unknown"], span=Span("m.gen", 3, 5))
    service.ref_spans["throws:e_unknown"] = Span("m.gen", 6, 9)
    description = Description([Component("m", "genom3", services=[service])],
                              exceptions={"m::e_known": ExceptionDecl("e_known")})
    errors, _ = check(description)
    assert [(str(d.span), d.message, d.hint) for d in errors] == [
        ("m.gen:6:9", "unknown exception 'e_unknown' in component 'm'", "did you mean 'e_known'?")]


def test_genom2_fail_reports_are_known_exceptions():
    assert problems(SDI + "request A { type: control; fail_reports: E1; };") == []


def test_unknown_type_in_a_struct_member():
    assert problems("typedef struct S { Ghost g; int n; } S;\nmodule m { internal_data: S; };\n") == [
        (1, 20, "unknown type 'Ghost'")]


def test_unknown_type_of_a_port():
    comp = Component("m", "genom3", ports=[Port("P", "out", NamedType("nope::pose", span=Span("m.gen", 9, 12)))])
    description = Description([comp], types={"dala::pose": StructType("pose")})
    errors, _ = check(description)
    assert [(str(d.span), d.message) for d in errors] == [("m.gen:9:12", "unknown type 'nope::pose'")]


def test_scoped_type_names_resolve():
    comp = Component("m", "genom3", ports=[Port("P", "out", NamedType("::dala::pose")),
                                           Port("Q", "out", NamedType("pose"))])
    description = Description([comp], types={"dala::pose": StructType("pose")})
    assert check(description)[0] == []


def test_unknown_port_in_a_codel_parameter():
    from genom2bip.ir import CodelParam
    codel = Codel("f", ["start"], [Yield("ether")], [CodelParam("Spede", "out", "port", span=Span("m.gen", 7, 30))],
                  span=Span("m.gen", 7, 20))
    comp = Component("m", "genom3", tasks=[Task("t", Duration(0.1))], ports=[Port("Speed", "out", NamedType("x"))],
                     services=[Service("A", "activity", task="t", codels=[codel], span=Span("m.gen", 6, 1))])
    errors, _ = check(Description([comp], types={"x": StructType("x")}))
    assert [(str(d.span), d.message, d.hint) for d in errors] == [
        ("m.gen:7:30", "unknown port 'Spede' in codel 'f'", "did you mean 'Speed'?")]


def test_unknown_ids_member_in_a_codel_parameter():
    from genom2bip.ir import BaseType, CodelParam, Member
    codel = Codel("f", ["start"], [Yield("ether")], [CodelParam("sped.v", "in", "ids", span=Span("m.gen", 8, 25))])
    comp = Component("m", "genom3", ids=[Member("speed", BaseType("double"))], tasks=[Task("t", Duration(0.1))],
                     services=[Service("A", "activity", task="t", codels=[codel])])
    errors, _ = check(Description([comp]))
    assert [(str(d.span), d.message, d.hint) for d in errors] == [
        ("m.gen:8:25", "unknown ids member 'sped' in codel 'f'", "did you mean 'speed'?")]


def test_poster_of_a_module_checked_alone_is_a_warning():
    text = SDI.replace(
        "exec_task Main { period: 10; };", "exec_task Main { period: 10; poster_client_from: pom::Pos; };"
    )
    errors, reporter = check(parse_text(text, "w.gen"))
    assert errors == []
    [warning] = [d for d in reporter.diagnostics if d.severity == "warning"]
    assert warning.message == "type of poster 'pom::Pos' unchecked: module 'pom' is not in the description"
    assert (warning.span.line, warning.span.column) == (4, 50)


def test_poster_read_from_a_module_that_lacks_it():
    pom = parse_text("typedef struct S { int a; } S;\nmodule pom { internal_data: S; };\n"
                     "exec_task T { period: 1; };\nposter Pos { data: a::a; exec_task: T; };\n", "pom.gen")
    text = SDI.replace(
        "exec_task Main { period: 10; };", "exec_task Main { period: 10; poster_client_from: pom::Poz; };"
    )
    rflex = parse_text(text, "r.gen")
    both = Description(pom.components + rflex.components, types={**pom.types, **rflex.types})
    errors, _ = check(both)
    assert [(d.span.file, d.message) for d in errors] == [("r.gen", "unknown type 'pom::Poz'")]


# --------------------------------------------------------------------------- duplicates


def test_duplicate_requests_tasks_and_posters():
    found = problems(SDI + """exec_task Main { period: 5; };
request A { type: control; };
request A { type: control; };
poster P { data: r::ref; exec_task: Main; };
poster P { data: c::count; exec_task: Main; };
""")
    assert (5, 11, "duplicate task 'Main' in component 'demo'") in found
    assert (7, 9, "duplicate service 'A' in component 'demo'") in found
    assert (9, 8, "duplicate port 'P' in component 'demo'") in found


def test_duplicate_hint_names_the_first():
    errors, _ = check(parse_text(SDI + "request A { type: control; };\nrequest A { type: control; };", "d.gen"))
    assert errors[0].hint == "first declared at d.gen:5:9"


def test_duplicate_ids_members_and_components():
    from genom2bip.ir import BaseType, Member

    ids = [
        Member("x", BaseType("double"), span=Span("a.gen", 2, 3)),
        Member("x", BaseType("long"), span=Span("a.gen", 3, 3)),
    ]
    description = Description([Component("a", "genom3", ids=ids, span=Span("a.gen", 1, 11)),
                               Component("a", "genom3", span=Span("b.gen", 1, 11))])
    errors, _ = check(description)
    assert sorted((str(d.span), d.message) for d in errors) == [
        ("a.gen:3:3", "duplicate ids member 'x' in component 'a'"),
        ("b.gen:1:11", "duplicate component 'a' in the description"),
    ]


# --------------------------------------------------------------------------- FSMs


def _activity(codels, **kw):
    service = Service("A", "activity", task="t", codels=codels, span=Span("m.gen", 10, 10), **kw)
    comp = Component("m", "genom3", tasks=[Task("t", Duration(0.1))], services=[service])
    return Description([comp])


def test_yield_to_undeclared_state():
    codels = [
        Codel("s", ["start"], [Yield("main", span=Span("m.gen", 11, 40)), Yield("ether")], span=Span("m.gen", 11, 20)),
        Codel("m", ["mian"], [Yield("ether")], span=Span("m.gen", 12, 20)),
    ]
    errors, _ = check(_activity(codels))
    assert [(str(d.span), d.message) for d in errors] == [
        ("m.gen:11:40", "yield to undeclared state 'main' in codel 's' of activity 'A'")]
    assert errors[0].hint == "did you mean 'mian'?"


def test_an_activity_that_ends_only_through_its_stop_codel_is_accepted():
    # genom3 (codel.c, codel_fsmcreate) only asks codel<stop> to lead to ether: a tracking loop ends when interrupted
    codels = [Codel("s", ["start"], [Yield("loop")]), Codel("l", ["loop"], [Yield("loop", pause=True)]),
              Codel("st", ["stop"], [Yield("ether")])]
    assert check(_activity(codels))[0] == []
    assert check(_activity(codels[:2]))[0] == []


def test_a_codel_reached_neither_from_start_nor_from_stop():
    codels = [
        Codel("s", ["start"], [Yield("ether")]),
        Codel("l", ["lost"], [Yield("ether")], span=Span("m.gen", 12, 5)),
    ]
    errors, _ = check(_activity(codels))
    assert [(str(d.span), d.message) for d in errors] == [
        ("m.gen:12:5", "codel<lost> 'l' of activity 'A' is never reached")]


def test_no_path_from_stop_to_ether():
    codels = [Codel("s", ["start"], [Yield("ether")]), Codel("st", ["stop"], [Yield("stop", pause=True)])]
    errors, _ = check(_activity(codels))
    assert [d.message for d in errors] == ["no path from stop to ether in activity 'A': an interruption can never end"]


def test_activity_without_start_codel():
    codels = [Codel("m", ["main"], [Yield("ether")])]
    errors, _ = check(_activity(codels))
    assert [(str(d.span), d.message) for d in errors] == [
        ("m.gen:10:10", "activity 'A' has no codel for state 'start'")
    ]


def test_genom2_activity_without_any_codel():
    assert problems(SDI + "request A { type: exec; exec_task: Main; };") == [
        (5, 9, "activity 'A' has no codel for state 'start'")]


def test_activity_without_task():
    assert problems(SDI + "request A { type: exec; codel_start: f; };") == [(5, 9, "activity 'A' has no task")]


def test_control_request_with_exec_codels():
    assert problems(SDI + "request A {\n  type: control;\n  codel_main: f;\n};") == [
        (7, 15, "control request 'A' has FSM codel 'f' (state start, exec); it runs in the control task and "
                "takes only a validate codel (codel_control)")]


def test_attribute_with_fsm_codels():
    service = Service("A", "attribute", codels=[Codel("f", ["start"], [Yield("ether")], span=Span("m.gen", 4, 19))],
                      span=Span("m.gen", 3, 13))
    errors, _ = check(Description([Component("m", "genom3", services=[service])]))
    assert [(str(d.span), d.message) for d in errors] == [
        ("m.gen:4:19", "attribute 'A' has FSM codel 'f' (state start); it runs in the control task and takes only "
                       "a validate codel")]


def test_genom3_function_codels_are_checked_like_an_activity():
    service = Service("F", "function", codels=[Codel("f", ["start"], [Yield("nowhere", span=Span("m.gen", 5, 40))])],
                      span=Span("m.gen", 4, 12))
    errors, _ = check(Description([Component("m", "genom3", services=[service])]))
    assert [d.message for d in errors] == ["yield to undeclared state 'nowhere' in codel 'f' of function 'F'"]


def test_task_codels_are_checked():
    task = Task(
        "t",
        Duration(0.1),
        codels=[Codel("m", ["main"], [Yield("mian", pause=True, span=Span("m.gen", 3, 30))])],
        span=Span("m.gen", 2, 8),
    )
    errors, _ = check(Description([Component("m", "genom3", tasks=[task])]))
    assert [(str(d.span), d.message) for d in errors] == [
        ("m.gen:3:30", "yield to undeclared state 'mian' in codel 'm' of task 't'"),
    ]
    # without a start state, the codels are reported as never reached (genom3's rule), not the missing start
    task.codels[0].yields = [Yield("main", pause=True)]
    task.codels[0].span = Span("m.gen", 3, 5)
    errors, _ = check(Description([Component("m", "genom3", tasks=[task])]))
    assert [(str(d.span), d.message) for d in errors] == [("m.gen:3:5", "codel<main> 'm' of task 't' is never reached")]
    task.codels.append(Codel("st", ["stop"], [Yield("ether")]))
    task.codels[0].triggers = ["start", "main"]
    assert check(Description([Component("m", "genom3", tasks=[task])]))[0] == []


# --------------------------------------------------------------------------- tasks


def test_negative_period_is_reported_at_the_period():
    assert problems(SDI.replace("period: 10", "period: -3")) == [
        (4, 26, "task 'Main' has a non-positive period (-3 ticks)")]


def test_zero_period_in_the_ir_is_reported():
    task = Task("t", Duration(0.0, "0 ms"), span=Span("m.gen", 2, 8))
    task.ref_spans["period"] = Span("m.gen", 3, 12)
    errors, _ = check(Description([Component("m", "genom3", tasks=[task])]))
    assert [(str(d.span), d.message) for d in errors] == [("m.gen:3:12", "task 't' has a non-positive period (0 ms)")]


# --------------------------------------------------------------------------- several at once


def test_several_errors_are_all_reported_in_location_order():
    text = SDI + """request A { type: exec; exec_task: Nowhere; codel_start: f; };
request B { type: control; interrupt_activity: Ghost; };
request A { type: control; };
"""
    found = problems(text)
    assert sorted(found) == found or True  # the reporter sorts when raising; check the set here
    assert {m for _, _, m in found} == {
        "unknown task 'Nowhere' for activity 'A'",
        "unknown service 'Ghost' in 'interrupts' of function 'B'",
        "duplicate service 'A' in component 'demo'",
    }
    reporter = Reporter()
    check_description(parse_text(text, "s.gen"), reporter)
    with pytest.raises(Exception) as info:
        reporter.raise_if_errors()
    lines = [d.span.line for d in info.value.diagnostics]
    assert lines == sorted(lines) == [5, 6, 7]
