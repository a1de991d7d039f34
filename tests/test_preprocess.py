"""The preprocessing layer: pcpp output, the map back to original positions, pragmas and cpp errors."""
from __future__ import annotations

from pathlib import Path

import pytest

from genom2bip.parser.preprocess import preprocess
from runtime.diagnostics import Reporter, Span


def run(text: str, tmp_path: Path | None = None, **kw):
    reporter = Reporter()
    if tmp_path is not None:
        main = tmp_path / "main.gen"
        main.write_text(text)
        out = preprocess(main, filename=str(main), reporter=reporter, **kw)
    else:
        out = preprocess(text, filename="t.gen", reporter=reporter, **kw)
    return out, reporter


def position_of(pre, needle: str, nth: int = 0) -> tuple[int, int]:
    """Output (line, column) of the nth occurrence of needle in the preprocessed text."""
    at = -1
    for _ in range(nth + 1):
        at = pre.text.index(needle, at + 1)
    line = pre.text.count("\n", 0, at) + 1
    column = at - (pre.text.rfind("\n", 0, at) + 1) + 1
    return line, column


def test_comments_are_removed_and_columns_still_map_to_the_source():
    pre, rep = run("/* head\n   comment */ long /* x */ a; // tail\n  double b;\n")
    assert "comment" not in pre.text and "tail" not in pre.text and "x */" not in pre.text
    assert not rep.diagnostics
    assert pre.span(*position_of(pre, "long")) == Span("t.gen", 2, 15)
    assert pre.span(*position_of(pre, "a;")) == Span("t.gen", 2, 28)
    assert pre.span(*position_of(pre, "double")) == Span("t.gen", 3, 3)


def test_defines_and_conditionals():
    src = "#define N 4\n#ifdef FAST\nconst long p = 1;\n#else\nconst long p = N;\n#endif\n"
    pre, _ = run(src)
    assert "const long p = 4;" in pre.text and "p = 1" not in pre.text
    pre, _ = run(src, defines={"FAST": "1"})
    assert "const long p = 1;" in pre.text


def test_macro_expansion_maps_to_the_macro_use():
    pre, _ = run("#define SIZE (2 * 8)\nstruct s { long a[SIZE]; };\n")
    assert "long a[(2 * 8)]" in pre.text
    span = pre.span(*position_of(pre, "8)"))
    assert (span.file, span.line, span.column) == ("t.gen", 2, 19)


def test_include_with_guard_and_positions_inside_the_included_file(tmp_path):
    (tmp_path / "types.idl").write_text("#ifndef T_IDL\n#define T_IDL\n\nstruct p { double x; };\n#endif\n")
    pre, rep = run('#include "types.idl"\n#include "types.idl"\ncomponent c;\n', tmp_path)
    assert not rep.diagnostics
    assert pre.text.count("struct p") == 1
    span = pre.span(*position_of(pre, "double"))
    assert span.file.endswith("types.idl") and (span.line, span.column) == (4, 12)
    span = pre.span(*position_of(pre, "component"))
    assert span.file.endswith("main.gen") and (span.line, span.column) == (3, 1)
    assert [Path(f).name for f in pre.files] == ["main.gen", "types.idl"]
    assert rep.sources.line(span.file, 3) == "component c;"


def test_angle_include_searches_include_dirs_then_the_including_directory(tmp_path):
    (tmp_path / "inc").mkdir()
    (tmp_path / "inc" / "a.idl").write_text("typedef long a_t;\n")
    (tmp_path / "b.idl").write_text("typedef long b_t;\n")
    pre, rep = run("#include <a.idl>\n#include <b.idl>\n", tmp_path, include_dirs=[str(tmp_path / "inc")])
    assert not rep.diagnostics
    assert "a_t" in pre.text and "b_t" in pre.text


def test_include_not_found_is_a_diagnostic_at_the_include_line(tmp_path):
    pre, rep = run('component c;\n  #include "missing.idl"\n', tmp_path, include_dirs=[str(tmp_path / "inc")])
    assert pre is not None
    (d,) = rep.diagnostics
    assert d.severity == "error"
    assert d.message.startswith("cannot find include file 'missing.idl' (searched: ")
    assert str(tmp_path) in d.message and str(tmp_path / "inc") in d.message
    assert d.span.file.endswith("main.gen") and (d.span.line, d.span.column) == (2, 12)


def test_include_not_found_inside_an_included_file_points_into_that_file(tmp_path):
    (tmp_path / "a.idl").write_text("\n\n#include <nowhere.idl>\n")
    _, rep = run('#include "a.idl"\n', tmp_path)
    (d,) = rep.diagnostics
    assert d.span.file.endswith("a.idl") and d.span.line == 3
    assert "cannot find include file 'nowhere.idl'" in d.message


def test_pragmas_are_collected_with_their_original_position(tmp_path):
    (tmp_path / "a.idl").write_text('#pragma requires "eigen3 >= 3.3"\n')
    pre, rep = run(
        '#include "a.idl"\n\n#pragma provides nav\n#pragma masquerade ros geo::p data\n#pragma once\n', tmp_path
    )
    assert not rep.diagnostics
    assert [(p.name, p.arguments) for p in pre.pragmas] == [
        ("requires", '"eigen3 >= 3.3"'),
        ("provides", "nav"),
        ("masquerade", "ros geo::p data"),
    ]
    assert pre.pragmas[0].span.file.endswith("a.idl") and pre.pragmas[0].span.line == 1
    assert pre.pragmas[1].span.file.endswith("main.gen") and pre.pragmas[1].span.line == 3
    assert "#pragma" not in pre.text


def test_pragma_in_a_disabled_region_is_ignored():
    pre, _ = run('#if 0\n#pragma requires "x"\n#endif\n')
    assert pre.pragmas == []


def test_error_directive_and_unterminated_conditional_are_reported():
    _, rep = run('#error "no robot"\n#ifndef A\nlong x;\n')
    msgs = [(d.severity, d.span.line, d.message) for d in rep.diagnostics]
    assert ("error", 1, '#error "no robot"') in msgs
    assert any(sev == "error" and line == 2 and "unterminated #ifndef" in m.lower() for sev, line, m in msgs)


def test_unknown_directive_is_a_warning_and_is_dropped():
    pre, rep = run("#ident \"x\"\nlong x;\n")
    (d,) = rep.diagnostics
    assert d.severity == "warning" and "#ident" in d.message
    assert "ident" not in pre.text


def test_missing_main_file(tmp_path):
    rep = Reporter()
    assert preprocess(tmp_path / "nope.gen", filename="nope.gen", reporter=rep) is None
    (d,) = rep.diagnostics
    assert d.span.file == "nope.gen" and "cannot read 'nope.gen'" in d.message


@pytest.mark.parametrize("line,column", [(1, 1), (99, 5), (2, 400)])
def test_span_outside_the_text_stays_in_the_file(line, column):
    pre, _ = run("long a;\n\n")
    assert pre.span(line, column).file == "t.gen"


def test_nothing_is_printed_by_pcpp(capsys, tmp_path):
    run('#error stop\n#warning careful\n#if\n#endif\n#include "nope.h"\n#include <nope.h>\n#endif\n#foo\n', tmp_path)
    out = capsys.readouterr()
    assert out.out == "" and out.err == ""
