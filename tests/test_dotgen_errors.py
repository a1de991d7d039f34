"""Syntax errors: their wording and their position in the original file, several per file."""
from __future__ import annotations

from pathlib import Path

import pytest

from genom2bip.parser import parse_paths, parse_text
from runtime.diagnostics import DiagnosticError

ERRORS = Path(__file__).parent / "fixtures" / "genom3" / "errors"


def diagnostics(text: str) -> list:
    with pytest.raises(DiagnosticError) as info:
        parse_text(text, "t.gen")
    return info.value.diagnostics


def one(text: str):
    (d,) = diagnostics(text)
    return d


def where(d) -> tuple[str, int, int]:
    return (d.span.file, d.span.line, d.span.column)


def test_codel_without_yield_names_what_was_expected_and_found():
    d = one("component c {\n  task t {\n    codel <start> f(in a) task;\n  };\n};\n")
    assert d.message == "expected 'yield' after codel parameters, found 'task'"
    assert where(d) == ("t.gen", 3, 27)
    assert (d.span.end_line, d.span.end_column) == (3, 31)


def test_simple_codel_followed_by_junk():
    d = one("component c { function f() { codel g(in x) yield; }; };")
    assert d.message == "expected ';' or 'wcet' after codel parameters, found 'yield'"
    assert where(d) == ("t.gen", 1, 44)


def test_missing_semicolon_points_at_the_next_token_and_hints_at_the_line_before():
    d = one("component c {\n  port out long P\n  task t;\n};\n")
    assert d.message == "expected ';' or '{' after 'P', found 'task'"
    assert where(d) == ("t.gen", 3, 3)
    assert d.hint == "is a ';' missing after 'P'? (line 2)"


def test_unknown_character():
    d = one("component c { ids { long $a; }; };")
    assert d.message.startswith("unexpected character '$'; expected ")
    assert where(d) == ("t.gen", 1, 26)


def test_unterminated_string():
    d = one('component c {\n  doc "no end;\n};\n')
    assert d.message == "unterminated string; expected string after 'doc'"
    assert where(d) == ("t.gen", 2, 7)


def test_end_of_file_inside_a_component():
    d = one("component c {\n  task t;\n")
    assert d.message.startswith("expected '}' or a declaration (ids, task, port")
    assert d.message.endswith("after ';', found end of file")
    assert where(d) == ("t.gen", 2, 10)


def test_wrong_top_level_statement():
    d = one("\n\nlong x;\n")
    assert d.message == (
        "expected end of file or a declaration (component, interface, module, const, typedef, struct, enum, ...), "
        "found 'long'")
    assert where(d) == ("t.gen", 3, 1)


def test_missing_value():
    d = one("component c { task t { priority ; }; };")
    assert d.message == "expected a value after 'priority', found ';'"


def test_double_angle_gets_a_hint_where_it_is_read_as_a_shift():
    d = one("typedef sequence<sequence<long, 4>> s;")
    assert d.hint == "'>>' is a shift operator here: write '> >' to close two template argument lists"


def test_error_inside_an_included_file_points_into_that_file():
    with pytest.raises(DiagnosticError) as info:
        parse_paths([ERRORS / "uses_bad_include.gen"])
    (d,) = info.value.diagnostics
    assert Path(d.span.file).name == "bad_types.idl"
    assert (d.span.line, d.span.column) == (6, 5)
    assert d.message == "expected ',', ';' or '[' after 'x', found 'double'"
    rendered = info.value.render()
    assert "bad_types.idl:6:5: error:" in rendered and "        double y;\n        ^^^^^^" in rendered


def test_several_syntax_errors_are_reported_together_in_order():
    with pytest.raises(DiagnosticError) as info:
        parse_paths([ERRORS / "several.gen"])
    got = [(d.span.line, d.span.column, d.message) for d in info.value.diagnostics]
    assert got == [
        (6, 5, "expected ';' after 'ms', found 'codel'"),
        (12, 19, "expected ';' or 'wcet' after codel parameters, found 'task'"),
        (17, 12, "unexpected character '@'; expected '::' or identifier after 'throws'"),
    ]
    assert info.value.render().endswith("3 errors")


def test_syntax_and_constant_errors_come_together():
    got = [
        (d.span.line, d.message) for d in diagnostics("const long a = 1 / 0;\ncomponent c { task t { period ; }; };\n")
    ]
    assert got == [(1, "division by zero in constant expression"), (2, "expected a value after 'period', found ';'")]


def test_missing_include_is_reported_with_the_directories_searched(tmp_path):
    with pytest.raises(DiagnosticError) as info:
        parse_paths([ERRORS / "missing_include.gen"], include_dirs=[str(tmp_path)])
    (d,) = info.value.diagnostics
    assert (Path(d.span.file).name, d.span.line, d.span.column) == ("missing_include.gen", 1, 10)
    assert d.message.startswith("cannot find include file 'geometry.idl' (searched: ")
    assert "errors" in d.message and str(tmp_path) in d.message


def test_missing_path_and_empty_directory(tmp_path):
    with pytest.raises(DiagnosticError) as info:
        parse_paths([tmp_path / "nope.gen", tmp_path])
    msgs = sorted(d.message for d in info.value.diagnostics)
    assert msgs == [f"no .gen file in directory '{tmp_path}'", f"no such file or directory: '{tmp_path / 'nope.gen'}'"]


def test_errors_never_escape_as_tracebacks():
    nasty = ["component", "component c {", "}", "component c { task t { codel <> f() yield; }; };",
             "const long x = ;", "struct s {};", "component c { attribute a(in); };", "#if\n", "\"",
             "component c { function f(in double x = { .a = }); };", "module m { };;", "interface i { extends; };"]
    for text in nasty:
        with pytest.raises(DiagnosticError) as info:
            parse_text(text, "n.gen")
        assert all(d.span.file == "n.gen" and d.span.line >= 1 for d in info.value.diagnostics), text


def test_keywords_are_never_read_as_prefixes_of_longer_words():
    d = one("component c {\n  task t { periods 5 ms; };\n};\n")
    assert d.message.endswith("found 'periods'") and (d.span.line, d.span.column) == (2, 12)
    d = one("component c { codels \"x\"; };")
    assert d.message.endswith("found 'codels'")


def test_mutated_descriptions_give_diagnostics_not_tracebacks():
    import random
    import re

    src = (Path(__file__).parent / "fixtures" / "genom3" / "demo.gen").read_text()
    words = list(re.finditer(r"\w+|::|[^\s\w]", src))
    pieces = [";", "{", "}", "(", ")", "<", ">", "::", ",", "=", ":", "task", "yield", '"', "0", "#if", "[", "@"]
    rnd = random.Random(2024)
    for _ in range(60):
        m = rnd.choice(words)
        text = src[:m.start()] + (rnd.choice(pieces) + " " if rnd.random() < 0.6 else "") + src[m.end():]
        try:
            parse_text(text, "m.gen")
        except DiagnosticError as e:
            assert e.diagnostics and all(d.span.file == "m.gen" and d.span.line >= 1 for d in e.diagnostics)
            e.render()
