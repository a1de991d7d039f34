"""GenoM2 front end: bad input gives diagnostics at file:line:column, every one of a file, never a traceback."""
import pytest

from genom2bip.ir import Description
from genom2bip.parser.genom2 import parse_genom2
from genom2bip.parser.preprocess import preprocess
from runtime.diagnostics import Reporter

from genom2bip.parser import parse_paths, parse_text
from runtime.diagnostics import DiagnosticError

SDI = """typedef struct SPEED { double v; double w; } SPEED;
typedef struct DEMO_STR { SPEED ref; int count; } DEMO_STR;
module demo { internal_data: DEMO_STR; };
exec_task Main { period: 10; };
"""


def errors(text: str, filename: str = "bad.gen"):
    """The diagnostics of a text that must not parse, as (line, column, message)."""
    with pytest.raises(DiagnosticError) as info:
        parse_text(text, filename)
    diags = info.value.diagnostics
    assert all(d.span.file == filename for d in diags), [str(d.span) for d in diags]
    return [(d.span.line, d.span.column, d.message) for d in diags if d.severity == "error"], info.value


def only_error(text: str):
    found, _ = errors(text)
    assert len(found) == 1, found
    return found[0]


def test_unknown_request_field_lists_the_accepted_ones():
    line, col, message = only_error(SDI + "request A {\n  type: exec;\n  codel_mian: f;\n};\n")
    assert (line, col) == (7, 3)
    assert "unknown field 'codel_mian' in request 'A'" in message
    for accepted in ("codel_main", "c_exec_func", "c_exec_func_start", "interrupt_activity", "fail_reports"):
        assert accepted in message


def test_unknown_field_hint_suggests_the_closest():
    _, err = errors(SDI + "request A { type: exec; exec_tsk: Main; };")
    assert err.diagnostics[0].hint == "did you mean 'exec_task'?"


@pytest.mark.parametrize("kind, fields, wrong", [
    ("module", "", "numbr"),
    ("exec_task", "", "perod"),
    ("poster", "data: r::ref;", "updte"),
])
def test_unknown_field_in_every_block(kind, fields, wrong):
    body = f"{kind} X {{ {fields} {wrong}: 1; }};"
    text = (
        SDI.replace("module demo { internal_data: DEMO_STR; };", "module demo { internal_data: DEMO_STR; };\n" + body)
        if kind != "module"
        else SDI.replace("module demo {", "module demo { " + wrong + ": 1;")
    )
    found, _ = errors(text)
    assert any(f"unknown field '{wrong}' in {kind}" in m and "accepted fields:" in m for _, _, m in found), found


def test_same_field_under_both_spellings_is_an_error():
    line, col, message = only_error(
        SDI + "request A { type: exec; exec_task: Main;\n codel_main: f; c_exec_func: g; };"
    )
    assert (line, col) == (6, 17)
    assert "field 'c_exec_func' given twice in request 'A': first (as 'codel_main') at bad.gen:6:2" == message


def test_every_syntax_error_of_a_file_is_reported_in_order():
    text = SDI + """request A {
  type: exec
  exec_task: Main;
};
request B { type: control; input: x::; };
request C { type: control };
"""
    found, err = errors(text)
    assert [(line, c) for line, c, _ in found] == [(7, 3), (9, 38), (10, 27)]
    assert found[0][2] == "syntax error: unexpected name 'exec_task'; expected ';', ',', '::' or 'wcet'"
    assert err.diagnostics[0].hint == "is a ';' missing before it?"
    rendered = err.render()
    assert "bad.gen:7:3: error: syntax error" in rendered
    assert "      exec_task: Main;\n      ^^^^^^^^^" in rendered
    assert rendered.endswith("3 errors")


def test_unterminated_block_is_reported_at_its_end():
    line, col, message = only_error(SDI + "request A { type: control;\n")
    assert line == 5
    assert message.startswith("syntax error: unexpected end of declaration; expected '}'")


def test_stray_character():
    line, col, message = only_error(SDI + "request A { type: control; rqst_num: @; };")
    assert (line, col) == (5, 38)
    assert message.startswith("syntax error: unexpected character '@'")


def test_an_unquoted_string_field_is_one_error_without_cascade():
    # the module's syntax error must not make every request "outside a module"
    found, _ = errors("typedef struct S { double v; } S;\nmodule m {\n  email: a@b.org;\n  internal_data: S; };\n"
                      "request SetSpeed { type: control; };\n")
    assert found == [(3, 11, "'email' needs a quoted string: write email: \"...\";")]


def test_unknown_declaration_kind():
    line, col, message = only_error(SDI + "reqest A { type: control; };")
    assert (line, col) == (5, 1)
    assert message.startswith("unknown declaration 'reqest'")


@pytest.mark.parametrize("field, message", [
    ("type: sometimes;", "request type must be control, exec or init, not 'sometimes'"),
    ("type: control; doc: 3;", "field 'doc' expects a quoted string"),
    ("type: exec; exec_task: \"Main\";", "field 'exec_task' expects a name here"),
    ("type: control; input: ref;", "field 'input' expects 'name::sdi_field'"),
    ("type: control; input: r::nope;", "'nope' is not a field of DEMO_STR"),
    ("type: control; input: r::ref.z;", "'z' is not a field of SPEED"),
    ("type: control; input: r::count.z;", "'count.z': 'count' is not a struct"),
    ("type: control; input_info: 1::\"x\";", "input_info without an input"),
    ("type: exec; exec_task: Main; codel_start: f wcet 3;", "wcet of codel 'f' needs a unit: s, ms, us, ns"),
    ("doc: \"no type\";", "request 'A' has no 'type:' (control, exec or init)"),
])
def test_bad_request_values(field, message):
    found, _ = errors(SDI + f"request A {{ {field} }};")
    assert any(message in m for _, _, m in found), found


def test_bad_value_is_reported_at_the_value():
    line, col, _ = only_error(SDI + "request A {\n  type: control;\n  input: r::nope;\n};")
    assert (line, col) == (7, 13)


@pytest.mark.parametrize("field, message", [
    ("period: 2.5;", "field 'period' counts clock ticks: an integer, not 2.5"),
    ("period: UNKNOWN;", "unknown constant 'UNKNOWN'"),
    ("period: 1/0;", "division by zero in a constant expression"),
    ("priority: \"high\";", "field 'priority' expects a number"),
    ("stack_size: 1, 2;", "field 'stack_size' takes one number, not a list"),
])
def test_bad_exec_task_values(field, message):
    found, _ = errors(SDI.replace("exec_task Main { period: 10; };", f"exec_task Main {{ {field} }};"))
    assert any(message in m for _, _, m in found), found


def test_poster_errors():
    found, _ = errors(SDI + """poster P { update: sometimes; data: r::ref; };
poster Q { exec_task: Nowhere; data: r::ref; };
poster R { update: user; };
poster S { data: r::ref; type: SPEED; };
""")
    messages = [m for _, _, m in found]
    assert "poster update must be 'auto' or 'user', not 'sometimes'" in messages
    assert "poster 'Q': unknown exec_task 'Nowhere'" in messages
    assert any(m.startswith("poster 'R' needs 'data: name::sdi_field, ...;'") for m in messages)
    assert any(m.startswith("poster 'S' has both 'data' and 'type'") for m in messages)


def test_module_problems():
    found, _ = errors("typedef struct S { int a; } S;\nmodule m { internal_data: T; };\nmodule n { };\n")
    assert (2, 27, "internal_data 'T' is not a known struct type") in found
    assert any(line == 3 and m.startswith("second module 'n' in one file") for line, _, m in found)


def test_request_outside_a_module():
    line, col, message = only_error("request A { type: control; };")
    assert (line, col) == (1, 1)
    assert message.startswith("request 'A' outside a module")


def test_second_init_request_is_a_warning_as_genom2_has_no_such_check():
    reporter = Reporter()
    parse_genom2(preprocess(SDI + "request I { type: init; exec_task: Main; codel_start: a; };\n"
                                  "request J { type: init; exec_task: Main; codel_start: b; };\n",
                            filename="w.gen", reporter=reporter), reporter, Description())
    assert [(d.severity, d.span.line, d.span.column, d.message) for d in reporter.diagnostics] == [
        ("warning", 6, 19, "second init request 'J' (the first is 'I')")]


def test_init_requests_are_made_incompatible_with_all_requests():
    reporter = Reporter()
    d = Description()
    parse_genom2(preprocess(SDI + "request I { type: init; exec_task: Main; codel_start: a;\n"
                                  "  interrupt_activity: T; };\n"
                                  "request T { type: exec; exec_task: Main; codel_start: t; };\n",
                            filename="w.gen", reporter=reporter), reporter, d)
    assert [(d.severity, d.span.line, d.span.column, d.message) for d in reporter.diagnostics] == [
        ("warning", 6, 23, "init request 'I' is made incompatible with all requests")]
    assert d.components[0].service("I").interrupts == ["I", "T"]


def test_c_declaration_errors():
    found, _ = errors("typedef struct S { int a; int a; } S;\ntypedef float int X;\ntypedef char B[-1];\n"
                      "typedef struct S { double a; } S;\nmodule m { internal_data: S; };\n")
    messages = {(line, m.split(" (")[0]) for line, _, m in found}
    assert (1, "duplicate member 'a' in struct S") in messages
    assert (2, "invalid C type 'float int'") in messages
    assert (3, "array size must be a positive integer, not -1") in messages
    assert (4, "duplicate type 'S': already defined differently") in messages


def test_error_inside_an_included_header_points_into_the_header(tmp_path):
    (tmp_path / "bad.h").write_text("typedef struct S {\n  int a\n} S;\n")
    (tmp_path / "m.gen").write_text('#include "bad.h"\nmodule m { internal_data: S; };\n')
    with pytest.raises(DiagnosticError) as info:
        parse_paths([str(tmp_path / "m.gen")])
    first = info.value.diagnostics[0]
    assert first.span.file.endswith("bad.h")
    assert (first.span.line, first.span.column) == (3, 1)


def test_deeply_nested_expression_is_an_error_not_a_crash():
    deep = "- " * 5000 + "1"
    with pytest.raises(DiagnosticError) as info:
        parse_text(SDI.replace("period: 10", f"period: {deep}"), "deep.gen")
    assert "nested too deeply" in info.value.diagnostics[0].message
