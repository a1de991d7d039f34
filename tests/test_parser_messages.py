"""Messages for broken files: unclosed comments, NUL bytes, files that cannot be read."""
from __future__ import annotations

import pytest

from genom2bip.cli import main
from genom2bip.parser import parse_text
from runtime.diagnostics import Diagnostic, DiagnosticError, Span


def _errors(text: str, name: str = "m.gen"):
    with pytest.raises(DiagnosticError) as err:
        parse_text(text, name)
    return [(d.span.line, d.span.column, d.message) for d in err.value.diagnostics if d.severity == "error"]


@pytest.mark.parametrize(
    "text,where",
    [
        ("/* a header cut short\ncomponent c;\n", (1, 1)),
        ("component c {\n  task t; /* open\n};\n", (2, 11)),
        (
            "typedef struct S { double v; } S;\nmodule m { number: 1; internal_data: S; };\n"
            "/* cut\nrequest R { type: control; };\n",
            (3, 1),
        ),
        ("typedef struct S { double v; } S;\nmodule m { number: 1; /* x\n internal_data: S; };\n", (2, 23)),
    ],
    ids=["genom3 leading", "genom3 inside", "genom2 leading", "genom2 inside"],
)
def test_an_unclosed_comment_is_named(text, where):
    assert _errors(text) == [(*where, "unterminated comment")]


def test_a_nul_byte_is_shown_escaped_never_raw(tmp_path, capsys):
    bad = tmp_path / "nul.gen"
    bad.write_bytes(b"component c {\x00 task t; };\n")
    assert main(["check", str(bad)]) == 1
    err = capsys.readouterr().err
    assert "\x00" not in err
    assert f"{bad}:1:14: error: unexpected character '\\x00'" in err
    assert "    component c {? task t; };" in err


def test_a_file_level_problem_is_reported_by_name_not_at_line_zero():
    d = Diagnostic(Span("props.mcl", 0, 0), "cannot read the property file: No such file or directory")
    assert d.render() == "props.mcl: error: cannot read the property file: No such file or directory"


def test_a_missing_property_file_is_named(tmp_path, capsys):
    gen = tmp_path / "c.gen"
    gen.write_text("component c { task t { period 10 ms; }; };\n")
    assert main(["verify", str(gen), "--property", str(tmp_path / "none.mcl")]) == 1
    err = capsys.readouterr().err
    assert f"{tmp_path / 'none.mcl'}: error: cannot read the property file" in err and ":0:0" not in err


def test_a_missing_description_is_named(tmp_path, capsys):
    assert main(["check", str(tmp_path / "none.gen")]) == 1
    assert f"{tmp_path / 'none.gen'}: no such file or directory" in capsys.readouterr().err
