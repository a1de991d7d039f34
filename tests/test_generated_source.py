"""Generated code shows its real lines in tracebacks and debuggers; GENOM2BIP_DUMP writes it to files.

Each generator is covered: the engine's step, the explorer's successor function and codec, the C step.
"""
from __future__ import annotations

import re
import shutil
import subprocess
import traceback
from pathlib import Path

import pytest

from runtime.bip2 import parse_text
from runtime.engine import Engine, ModelError
from runtime.engine.source import DUMP_ENV
from runtime.explore import StateSpace, explore
from tests import test_explore
from tests.nativekit import compiled, needs_cc

DIV = """package Div
  port type P()
  atom type A()
    data int x
    data int y
    port P go()
    place S
    initial to S do { x = 1; y = 0; }
    on go from S to S do { x = x / y; }
  end
  compound type Main()
    component A a()
  end
end
"""


def _failure(engine: Engine) -> str:
    state = engine.initial_state()
    with pytest.raises(ModelError) as info:
        engine.fire(state, engine.enabled(state)[0])
    return "".join(traceback.format_exception(info.value.__cause__))


def test_a_traceback_through_the_generated_step_quotes_its_line(monkeypatch):
    monkeypatch.delenv(DUMP_ENV, raising=False)
    text = _failure(Engine(parse_text(DIV, "Div.bip"), "Main()"))
    assert 'File "<bip step: Div Main() #' in text
    assert "v_x = _idiv(v_x, v_y)" in text


def test_the_dump_switch_writes_the_generated_sources_and_tracebacks_name_them(tmp_path, monkeypatch):
    monkeypatch.setenv(DUMP_ENV, str(tmp_path / "dump"))
    text = _failure(Engine(parse_text(DIV, "Div.bip"), "Main()"))
    dumped = sorted((tmp_path / "dump").glob("bip-step-div-main-*.py"))
    assert len(dumped) == 1
    assert f'File "{dumped[0]}", line ' in text
    line = int(text.split(f'File "{dumped[0]}", line ')[-1].split(",")[0])
    assert "_idiv(v_x, v_y)" in dumped[0].read_text().splitlines()[line - 1]
    StateSpace(parse_text(DIV.replace("x / y", "x + y"), "Div.bip"), "Main()")
    names = {p.name.rsplit("-", 1)[0] for p in (tmp_path / "dump").iterdir()}
    assert {"bip-step-div-main", "explorer-codec", "explorer-successors"} <= names


def test_exploration_reports_the_model_error_with_the_generated_line(monkeypatch):
    monkeypatch.delenv(DUMP_ENV, raising=False)
    result = explore(StateSpace(parse_text(DIV, "Div.bip"), "Main()"))
    assert result.error is not None
    assert "integer division by zero" in result.error.message and "x = _idiv" in result.error.message


COUNTER = test_explore.COUNTER.replace("    data int n", '    @domain(range="0..30")\n    data int n')


def _successors_failure(text: str) -> str:
    """The traceback of the first error met while numbering the states of a model, breadth-first."""
    space = StateSpace(parse_text(text, "M.bip"), "Main()")
    with pytest.raises(Exception) as info:
        for sid in range(100):
            space.successors(sid)
    return "".join(traceback.format_exception(info.value))


def _dumped_line(text: str, path) -> str:
    """The line of the dumped file ``path`` that the traceback ``text`` names last."""
    line = int(text.split(f'File "{path}", line ')[-1].split(",")[0])
    return path.read_text().splitlines()[line - 1]


def test_a_traceback_through_the_successor_function_quotes_its_line(monkeypatch):
    monkeypatch.delenv(DUMP_ENV, raising=False)
    text = _successors_failure(DIV)
    assert 'File "<explorer successors #' in text
    assert "t = _FIRE[I.source](base, I.mask, None)" in text


def test_a_traceback_through_the_codec_quotes_its_line(monkeypatch):
    monkeypatch.delenv(DUMP_ENV, raising=False)
    text = _successors_failure(COUNTER)
    assert "left its declared domain 0..30: value 33" in text
    assert 'File "<explorer codec #' in text
    assert re.search(r"\n +_domain\(\d+, x\d+\)\n", text)


def test_the_dump_switch_names_the_successor_and_codec_files_in_tracebacks(tmp_path, monkeypatch):
    monkeypatch.setenv(DUMP_ENV, str(tmp_path))
    text = _successors_failure(DIV)
    (expand,) = tmp_path.glob("explorer-successors-*.py")
    assert _dumped_line(text, expand).strip() == "t = _FIRE[I.source](base, I.mask, None)"
    text = _successors_failure(COUNTER)
    codecs = [p for p in tmp_path.glob("explorer-codec-*.py") if str(p) in text]
    assert len(codecs) == 1
    assert re.fullmatch(r" +_domain\(\d+, x\d+\)", _dumped_line(text, codecs[0]))


@needs_cc
def test_the_compiled_step_keeps_its_c_text_beside_the_library(tmp_path, monkeypatch):
    monkeypatch.delenv(DUMP_ENV, raising=False)
    monkeypatch.setenv("GENOM2BIP_CACHE", str(tmp_path))
    cs = compiled(StateSpace(parse_text(COUNTER, "C.bip"), "Main()"))
    library = Path(cs.lib._name)
    assert library.parent == tmp_path
    assert library.with_suffix(".c").read_text() == cs.source


@needs_cc
def test_the_dump_switch_compiles_the_c_step_from_the_dumped_file_with_line_tables(tmp_path, monkeypatch):
    monkeypatch.setenv(DUMP_ENV, str(tmp_path / "dump"))
    monkeypatch.setenv("GENOM2BIP_CACHE", str(tmp_path / "cache"))
    cs = compiled(StateSpace(parse_text(COUNTER, "C.bip"), "Main()"))
    (dumped,) = (tmp_path / "dump").glob("compiled-step-c-main-*.c")
    assert dumped.read_text() == cs.source
    library = Path(cs.lib._name)
    assert library.parent == tmp_path / "cache" and not library.with_suffix(".c").exists()
    assert str(dumped).encode() in library.read_bytes()  # the debug information names the dumped file
    if shutil.which("gdb") is None:
        return
    out = subprocess.run(["gdb", "-nx", "-batch", "-ex", "info line f0", "-ex", "list f0", str(library)],
                         capture_output=True, text=True, timeout=60).stdout
    found = re.search(r'Line \d+ of "([^"]+)"', out)
    assert found and Path(found.group(1)) == dumped, out
    listed = re.findall(r"^(\d+)\t(.*)$", out, re.M)  # gdb's listing of f0: the dumped file's own lines
    lines = dumped.read_text().splitlines()
    assert len(listed) >= 5 and all(lines[int(n) - 1] == text for n, text in listed), out
