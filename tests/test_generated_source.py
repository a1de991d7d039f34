"""Generated step code shows its real lines in tracebacks, and GENOM2BIP_DUMP writes it to files."""
from __future__ import annotations

import traceback

import pytest

from runtime.bip2 import parse_text
from runtime.engine import Engine, ModelError
from runtime.engine.source import DUMP_ENV
from runtime.explore import StateSpace, explore

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
