"""GenoM2 front end: each construct of the dialect, desugared into the IR as docs/genom2.md says."""
from pathlib import Path

import pytest

from genom2bip.ir import (
    ArrayType,
    BaseType,
    EnumType,
    EnumValue,
    NamedType,
    SequenceType,
    StringType,
    StructType,
    Typedef,
    UnionType,
)
from genom2bip.parser import parse_paths, parse_text

FIXTURES = Path(__file__).parent / "fixtures" / "genom2"

SDI = """
typedef struct SPEED { double v; double w; } SPEED;
typedef struct DEMO_STR { SPEED ref; SPEED odo; int count; char name[16]; } DEMO_STR;
module demo { number: 7; internal_data: DEMO_STR; };
exec_task Main { period: 10; };
"""


def parse(text: str, filename: str = "demo.gen"):
    return parse_text(text, filename)


def component(text: str):
    description = parse(text)
    assert len(description.components) == 1
    return description.components[0]


def fsm(service):
    """The codel FSM as {state: (codel, [yields])}."""
    out = {}
    for codel in service.codels:
        for state in codel.triggers:
            out[state] = (codel.name, [str(y) for y in codel.yields])
    return out


# --------------------------------------------------------------------------- module


def test_module_fields_go_to_properties_and_internal_data_to_ids():
    comp = component(SDI)
    assert comp.name == "demo"
    assert comp.dialect == "genom2"
    assert comp.properties["number"] == 7
    assert comp.properties["internal_data"] == "DEMO_STR"
    assert [m.name for m in comp.ids] == ["ref", "odo", "count", "name"]
    assert comp.ids[0].type == NamedType("SPEED")
    assert comp.ids[3].type == ArrayType(BaseType("char"), [16])
    assert comp.span.line == 4 and comp.span.column == 8


def test_module_descriptive_fields():
    comp = component("""
typedef struct S { int a; } S;
module m {
  number: 3; internal_data: S; version: "1.0"; email: "a@b.c"; lang: "c";
  codel_files: "a.c", "b.c"; requires: pocolibs, "genom"; iface_version: 1:2:3; clkrate: 50;
};
""")
    props = comp.properties
    assert props["version"] == "1.0"
    assert props["email"] == "a@b.c"
    assert props["lang"] == "c"
    assert props["codel_files"] == ["a.c", "b.c"]
    assert props["require"] == ["pocolibs", "genom"]
    assert props["iface_version"] == "1:2:3"
    assert comp.clock_rate.seconds == pytest.approx(0.02)


def test_default_clock_tick_is_10_ms():
    comp = component(SDI)
    assert comp.clock_rate.seconds == pytest.approx(0.01)
    assert comp.tasks[0].period.seconds == pytest.approx(0.1)
    assert comp.tasks[0].period.text == "10 ticks"


# --------------------------------------------------------------------------- exec_task


def test_exec_task_scheduling_fields_new_spelling():
    comp = component(SDI.replace("exec_task Main { period: 10; };", """
exec_task Main {
  period: 4; delay: 2; priority: 120; stack_size: 30000;
  codel_task_start: mainInit; codel_task_main: mainLoop; codel_task_end: mainEnd;
  fail_reports: HW_ERROR;
};"""))
    task = comp.task("Main")
    assert task.period.seconds == pytest.approx(0.04)
    assert task.delay.seconds == pytest.approx(0.02)
    assert (task.priority, task.stack) == (120, 30000)
    assert [(c.name, c.triggers, [str(y) for y in c.yields]) for c in task.codels] == [
        ("mainInit", ["start"], ["pause::main"]),
        ("mainLoop", ["main"], ["pause::main"]),
        ("mainEnd", ["stop"], ["ether"]),
    ]
    assert task.throws == ["HW_ERROR"]


def test_exec_task_old_spelling_gives_the_same_task():
    new = component(
        SDI.replace(
            "exec_task Main { period: 10; };",
            "exec_task Main { period: 3; codel_task_start: i; codel_task_main: m; codel_task_end: e; };",
        )
    )
    old = component(SDI.replace("exec_task Main { period: 10; };",
                                "exec_task Main { period: 3; c_init_func: i; c_func: m; c_end_func: e; };"))
    assert new.tasks == old.tasks


def test_exec_task_main_without_start_runs_from_start():
    comp = component(SDI.replace("exec_task Main { period: 10; };", "exec_task Main { c_func: loop; };"))
    task = comp.task("Main")
    assert task.period is None
    assert task.codels[0].triggers == ["start", "main"]


@pytest.mark.parametrize("period", ["0", "none"])
def test_period_zero_or_none_is_aperiodic(period):
    comp = component(SDI.replace("period: 10", f"period: {period}"))
    assert comp.tasks[0].period is None


def test_period_accepts_constant_expressions_and_defines():
    comp = component("#define BASE 3\n" + SDI.replace("period: 10", "period: BASE * 2 + 1"))
    assert comp.tasks[0].period.seconds == pytest.approx(0.07)


# --------------------------------------------------------------------------- requests


def test_control_request_is_a_function_with_validate_and_input():
    comp = component(SDI + """
request SetSpeed {
  doc: "set the reference";
  type: control;
  input: speed::ref;
  input_info: 0.1::"linear", 0.2::"angular";
  codel_control: checkSpeed;
  fail_reports: TOO_FAST;
};""")
    s = comp.service("SetSpeed")
    assert s.kind == "function"
    assert s.task is None
    assert s.doc == "set the reference"
    assert s.validate.name == "checkSpeed"
    assert s.codels == []
    [p] = s.parameters
    assert (p.direction, p.name, p.source, p.member) == ("in", "speed", "ids", "ref")
    assert p.type == NamedType("SPEED")
    assert p.default == {"v": 0.1, "w": 0.2}
    assert p.member_docs == {"v": "linear", "w": "angular"}
    assert s.throws == ["TOO_FAST"]


def test_control_request_old_spelling_and_output():
    comp = component(SDI + """
request GetOdo { type: control; output: odometry::odo; c_control_func: checkOdo; };""")
    s = comp.service("GetOdo")
    assert s.validate.name == "checkOdo"
    [p] = s.parameters
    assert (p.direction, p.name, p.member) == ("out", "odometry", "odo")


def test_scalar_input_info_gives_default_and_doc():
    comp = component(SDI + 'request SetCount { type: control; input: n::count; input_info: 3::"how many"; };')
    [p] = comp.service("SetCount").parameters
    assert (p.default, p.doc) == (3, "how many")


def test_exec_request_fsm_state_by_state():
    comp = component(SDI + """
request Track {
  type: exec; exec_task: Main;
  codel_start: trackStart; codel_main: trackMain; codel_end: trackEnd;
  codel_inter: trackInter; codel_fail: trackFail;
};""")
    s = comp.service("Track")
    assert (s.kind, s.task) == ("activity", "Main")
    assert fsm(s) == {
        "start": ("trackStart", ["pause::exec", "pause::end", "ether"]),
        "exec": ("trackMain", ["pause::exec", "pause::end", "ether"]),
        "end": ("trackEnd", ["ether"]),
        "stop": ("trackInter", ["ether"]),
        "fail": ("trackFail", ["ether"]),
    }
    assert s.states() == ["start", "exec", "end", "stop", "fail"]


def test_exec_request_old_spelling_gives_the_same_service():
    new = component(SDI + """request T { type: exec; exec_task: Main; codel_control: c; codel_start: s;
        codel_main: m; codel_end: e; codel_inter: i; codel_fail: f; interrupt_activity: T; fail_reports: E; };""")
    old = component(SDI + """request T { type: exec; exec_task: Main; c_control_func: c; c_exec_func_start: s;
        c_exec_func: m; c_exec_func_end: e; c_exec_func_inter: i; c_exec_func_fail: f; incompatible_with: T;
        fail_msg: E; };""")
    assert new.services == old.services


def test_exec_request_without_start_codel_starts_in_main():
    comp = component(SDI + "request Stop { type: exec; exec_task: Main; codel_main: stopMain; };")
    assert fsm(comp.service("Stop")) == {
        "start": ("stopMain", ["pause::exec", "ether"]),
        "exec": ("stopMain", ["pause::exec", "ether"]),
    }


def test_exec_request_with_only_a_start_codel_ends_at_once():
    comp = component(SDI + "request Once { type: exec; exec_task: Main; codel_start: once; };")
    assert fsm(comp.service("Once")) == {"start": ("once", ["ether"])}


def test_init_request_is_an_activity_marked_on_the_module():
    comp = component(SDI + "request Init { type: init; exec_task: Main; codel_start: initStart; };")
    assert comp.service("Init").kind == "activity"
    assert comp.properties["init_service"] == "Init"


def test_interrupt_activity_all_names_every_activity():
    comp = component(SDI + """
request A { type: exec; exec_task: Main; codel_start: a; };
request B { type: exec; exec_task: Main; codel_start: b; interrupt_activity: all; };
request C { type: control; interrupt_activity: none; };
request D { type: control; incompatible_with: A, B; };""")
    assert comp.service("B").interrupts == ["A", "B"]
    assert comp.service("C").interrupts == []
    assert comp.service("D").interrupts == ["A", "B"]


def test_fail_reports_are_declared_exceptions():
    description = parse(SDI + """
request A { type: exec; exec_task: Main; codel_start: a; fail_reports: E1, E2; };
request B { type: control; fail_msg: E2, E3; };""")
    comp = description.components[0]
    assert comp.service("A").throws == ["E1", "E2"]
    assert comp.service("B").throws == ["E2", "E3"]
    assert comp.throws == ["E1", "E2", "E3"]
    assert {"demo::E1", "demo::E2", "demo::E3"} <= set(description.exceptions)


def test_request_codels_receive_input_and_output_as_ids_params():
    comp = component(SDI + "request T { type: exec; exec_task: Main; input: s::ref; output: o::odo; codel_start: f; };")
    [codel] = comp.service("T").codels
    assert [(p.path, p.direction, p.source, p.alias) for p in codel.params] == [
        ("ref", "in", "ids", "s"), ("odo", "out", "ids", "o")]


def test_input_on_a_nested_sdi_field():
    comp = component(SDI + "request V { type: control; input: v::ref.v; };")
    [p] = comp.service("V").parameters
    assert (p.member, p.type) == ("ref.v", BaseType("double"))


def test_wcet_extension_on_codels():
    comp = component(SDI + "request T { type: exec; exec_task: Main; codel_start: f wcet 250 us; };")
    wcet = comp.service("T").codels[0].wcet
    assert wcet.seconds == pytest.approx(250e-6)
    assert wcet.text == "250 us"


# --------------------------------------------------------------------------- posters


def test_auto_poster_is_an_out_port_with_a_struct_of_its_data():
    description = parse(SDI + "poster Robot { update: auto; data: speed::ref, odometry::odo; exec_task: Main; };")
    comp = description.components[0]
    port = comp.port("Robot")
    assert (port.direction, port.type) == ("out", NamedType("demo_Robot_poster"))
    struct = description.types["demo_Robot_poster"]
    assert isinstance(struct, StructType)
    assert [(m.name, m.type) for m in struct.members] == [
        ("speed", NamedType("SPEED")),
        ("odometry", NamedType("SPEED")),
    ]
    assert comp.properties["posters"]["Robot"] == {"update": "auto", "exec_task": "Main"}


def test_user_poster_takes_its_type_and_create_function():
    comp = component(SDI + "poster Raw { update: user; type: SPEED; exec_task: Main; c_create_func: mkRaw; };")
    assert comp.port("Raw").type == NamedType("SPEED")
    assert comp.properties["posters"]["Raw"]["create"] == "mkRaw"


def test_poster_client_from_is_an_in_port():
    comp = component(SDI.replace("exec_task Main { period: 10; };",
                                 "exec_task Main { period: 10; poster_client_from: pom::Pos; };"))
    port = comp.port("pom_Pos")
    assert (port.direction, port.type) == ("in", NamedType("pom::Pos"))


# --------------------------------------------------------------------------- C declarations


def test_c_declarations_become_ir_types():
    description = parse("""
#define N 4
typedef unsigned char BYTE;
typedef struct POINT { double x, y; } POINT;
struct tagged { long a; unsigned short b; };
typedef struct { struct tagged t; POINT pts[N][2]; char *label; int *values; } SHAPE;
typedef union { int i; float f; } NUM;
enum color { RED, GREEN = 5, BLUE };
const int LIMIT = 2 * N;
module m { internal_data: SHAPE; };
""")
    types = description.types
    assert types["BYTE"] == Typedef("BYTE", BaseType("octet"))
    assert [m.name for m in types["POINT"].members] == ["x", "y"]
    assert [m.type for m in types["tagged"].members] == [BaseType("long"), BaseType("unsigned short")]
    shape = types["SHAPE"]
    assert [m.type for m in shape.members] == [
        NamedType("tagged"),
        ArrayType(NamedType("POINT"), [4, 2]),
        StringType(),
        SequenceType(BaseType("long")),
    ]
    assert isinstance(types["NUM"], UnionType)
    assert types["color"] == EnumType("color", ["RED", "GREEN", "BLUE"])
    assert description.constants["BLUE"].value == EnumValue(6, "BLUE")
    assert description.constants["LIMIT"].value == 8


def test_defines_become_constants():
    description = parse('#define MAX_SPEED 1.5\n#define NAME "rflex"\n#define TWICE (2 * 21)\n' + SDI)
    consts = description.constants
    assert consts["MAX_SPEED"].value == 1.5
    assert consts["NAME"].value == "rflex"
    assert consts["TWICE"].value == 42
    assert consts["MAX_SPEED"].span.line == 1


def test_import_from_declares_types():
    description = parse("""
import from pom { typedef struct POM_POS { double x, y; } POM_POS; };
typedef struct S { POM_POS where; } S;
module m { internal_data: S; };
""")
    assert "POM_POS" in description.types
    assert description.components[0].ids[0].type == NamedType("POM_POS")


def test_same_header_in_two_modules_is_not_a_duplicate(tmp_path):
    (tmp_path / "common.h").write_text("typedef struct POS { double x; } POS;\n")
    for name in ("a", "b"):
        (tmp_path / f"{name}.gen").write_text(f'#include "common.h"\nmodule {name} {{ internal_data: POS; }};\n')
    description = parse_paths([str(tmp_path / "a.gen"), str(tmp_path / "b.gen")])
    assert [c.name for c in description.components] == ["a", "b"]


# --------------------------------------------------------------------------- the fixture, both spellings


def test_rflex_fixture_with_both_spellings():
    description = parse_paths([str(FIXTURES / "rflex.gen")])
    [comp] = description.components
    assert comp.name == "rflex"
    assert [s.name for s in comp.services] == ["Init", "SetSpeed", "GetOdo", "TrackSpeed", "Stop"]
    assert [(s.kind, s.task) for s in comp.services] == [
        ("activity", "MotorsTask"), ("function", None), ("function", None),
        ("activity", "MotorsTask"), ("activity", "MotorsTask")]
    init, set_speed, _get, track, stop = comp.services
    assert init.validate.name == "rflexInitCheck"           # c_control_func
    assert fsm(init) == {"start": ("rflexInitStart", ["ether"])}  # c_exec_func_start
    assert set_speed.validate.name == "rflexSetSpeedCheck"  # codel_control
    assert fsm(track)["exec"] == ("rflexTrackMain", ["pause::exec", "pause::end", "ether"])
    assert track.codels[1].wcet.seconds == pytest.approx(0.002)
    assert fsm(stop) == {"start": ("rflexStopMain", ["pause::exec", "ether"]),
                         "exec": ("rflexStopMain", ["pause::exec", "ether"]),
                         "stop": ("rflexStopInter", ["ether"])}  # c_exec_func, c_exec_func_inter
    assert stop.interrupts == ["TrackSpeed"]                # incompatible_with
    assert stop.throws == ["MOTOR_ERROR"]                   # fail_msg
    motors, sonars = comp.tasks
    assert motors.period.seconds == pytest.approx(0.05)
    assert [c.name for c in motors.codels] == ["rflexMotorsInit", "rflexMotorsMain", "rflexMotorsEnd"]
    assert sonars.period.seconds == pytest.approx(0.2)
    assert [p.name for p in comp.ports] == ["pom_Pos", "Robot", "Sonars"]
    assert description.constants["RFLEX_NB_SONARS"].value == 16
    sonars_member = next(m for m in comp.ids if m.name == "sonars")
    assert sonars_member.type == ArrayType(BaseType("short"), [16])
    # the header's types are known, with spans inside the header
    assert description.types["RFLEX_ODO"].span.file.endswith("rflexStruct.h")


def test_pragmas_are_kept_and_requires_applies_to_the_module():
    description = parse('#pragma requires "pocolibs >= 2.0"\n' + SDI)
    assert [(p.name, p.arguments) for p in description.pragmas] == [("requires", '"pocolibs >= 2.0"')]
    assert description.components[0].properties["require"] == ["pocolibs >= 2.0"]
