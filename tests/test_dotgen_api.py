"""The parser package's public API: dialect detection and dispatch, parse_text/parse_paths contracts."""
from __future__ import annotations

import sys

import pytest

from genom2bip.ir import Description
from genom2bip.parser import detect_dialect, parse_paths, parse_text
from runtime.diagnostics import DiagnosticError

GENOM2 = """
/* a GenoM2 module */
module demo {
  number: 9000;
  internal_data: DEMO_STR;
};
request Stop { type: control; };
"""


@pytest.mark.parametrize("text,dialect", [
    ("component c { task t; };", "genom3"),
    ("interface i;", "genom3"),
    ("module m { struct s { long a; }; };", "genom3"),          # IDL modules are GenoM3
    ("typedef long t;", "genom3"),
    ("", "genom3"),
    (GENOM2, "genom2"),
    ("#include \"x.h\"\nexec_task Motion { period: 5; };", "genom2"),
    ("poster Pos { update: auto; };", "genom2"),
    ("module demo { number: 1; };", "genom2"),
    ("/* component c { } */\nrequest R { };", "genom2"),        # commented-out text does not count
    ("module m { };\ncomponent c;\n/* request R { } */", "genom3"),
])
def test_detect_dialect(text, dialect):
    assert detect_dialect(text) == dialect


def test_parse_text_returns_a_description():
    d = parse_text("component c;", "c.gen")
    assert isinstance(d, Description)
    assert d.components[0].file == "c.gen" and d.files == ["c.gen"]


def test_genom2_files_are_dispatched_to_the_genom2_front_end(monkeypatch):
    calls = []

    class FakeModule:
        @staticmethod
        def parse_genom2(source, reporter, description):
            calls.append(source.file)

    monkeypatch.setitem(sys.modules, "genom2bip.parser.genom2", FakeModule)
    parse_text(GENOM2, "old.gen")
    assert calls == ["old.gen"]


def test_missing_genom2_front_end_is_a_diagnostic(monkeypatch):
    monkeypatch.setitem(sys.modules, "genom2bip.parser.genom2", None)  # makes the import fail
    with pytest.raises(DiagnosticError) as info:
        parse_text(GENOM2, "old.gen")
    (d,) = info.value.diagnostics
    assert d.message == "GenoM2 support not available" and d.span.file == "old.gen"


def test_errors_of_all_files_are_collected(tmp_path):
    (tmp_path / "a.gen").write_text("component a {\n  task t\n};\n")
    (tmp_path / "b.gen").write_text("const long x = 1 / 0;\n")
    (tmp_path / "c.gen").write_text("component c;\n")
    with pytest.raises(DiagnosticError) as info:
        parse_paths([tmp_path])
    got = [(d.span.file.rsplit("/", 1)[-1], d.span.line) for d in info.value.diagnostics]
    assert got == [("a.gen", 3), ("b.gen", 1)]


def test_parse_paths_accepts_files_of_any_extension(tmp_path):
    (tmp_path / "types.idl").write_text("struct p { double x; };\n")
    d = parse_paths([str(tmp_path / "types.idl")])
    assert "p" in d.types


def test_include_dirs_apply_to_parse_text(tmp_path):
    (tmp_path / "t.idl").write_text("typedef long t;\n")
    d = parse_text("#include <t.idl>\n", "x.gen", include_dirs=[str(tmp_path)])
    assert "t" in d.types
