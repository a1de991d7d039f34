"""Error columns stay exact when include directories cover the files (both dialects)."""
from __future__ import annotations

import pytest

from genom2bip.parser import parse_paths
from runtime.diagnostics import DiagnosticError

GENOM3 = """#include "types.idl"
component c {
  task t;
  activity a() { task t; codel <start> f() yield ether wcet; };
};
"""
GENOM2 = """#include "types.h"
module m { number: 1; internal_data: M_STR; };
request R { type: control; input: x::x; codel_control: c c; };
"""


def _first_error(tmp_path, name, text, include, include_text, include_dirs):
    (tmp_path / include).write_text(include_text)
    main = tmp_path / name
    main.write_text(text)
    with pytest.raises(DiagnosticError) as err:
        parse_paths([main], include_dirs=[str(d) for d in include_dirs])
    e = err.value.diagnostics[0]
    return e.span.line, e.span.column, e.message


@pytest.mark.parametrize("dirs", [[], ["."], ["abs"]], ids=["no -I", "-I relative", "-I absolute"])
def test_genom3_error_column_with_an_include(tmp_path, monkeypatch, dirs):
    monkeypatch.chdir(tmp_path)
    dirs = [tmp_path if d == "abs" else d for d in dirs]
    line, col, message = _first_error(tmp_path, "a.gen", GENOM3, "types.idl", "struct s { long v; };\n", dirs)
    assert (line, col, message) == (4, 60, "expected a value after 'wcet', found ';'")


@pytest.mark.parametrize("dirs", [[], ["."], ["abs"]], ids=["no -I", "-I relative", "-I absolute"])
def test_genom2_error_column_with_an_include(tmp_path, monkeypatch, dirs):
    monkeypatch.chdir(tmp_path)
    dirs = [tmp_path if d == "abs" else d for d in dirs]
    line, col, message = _first_error(tmp_path, "m.gen", GENOM2, "types.h",
                                      "typedef struct M_STR { double x; } M_STR;\n", dirs)
    assert (line, col) == (3, 58) and "unexpected name 'c'" in message


def test_error_inside_an_included_file_has_its_column(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "inc").mkdir()
    line, col, message = _first_error(tmp_path, "a.gen", '#include "bad.idl"\ncomponent c;\n', "inc/bad.idl",
                                      "struct s {\n  long v;\n  double x y;\n};\n", ["inc"])
    assert (line, col, message) == (3, 12, "expected ',', ';' or '[' after 'x', found 'y'")
