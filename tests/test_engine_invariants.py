"""Atom invariants of untimed models: ``at`` (exact marking) and ``from`` (places marked) read and written back,
checked after the initial transitions and every step by the run (exit 5) and by the explorer (an error with a
shortest trace); the compiled explorer leaves such models to the Python one."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from enginekit import FIXTURES
from genom2bip.back.bip2 import write_package
from genom2bip.cli import main
from runtime.bip2 import parse_file, parse_text
from runtime.diagnostics import DiagnosticError
from runtime.engine import Engine, first
from runtime.engine.invariants import InvariantViolation
from runtime.explore import StateSpace, explore
from runtime.native.compiled import compile_space

MODEL = FIXTURES / "Invariants.bip"
ROOT = Path(__file__).resolve().parents[1]


def engine(root: str) -> Engine:
    return Engine(parse_file(MODEL), root)


def cli(*args):
    return subprocess.run([sys.executable, "-m", "runtime", "run", str(MODEL), *args], capture_output=True,
                          text=True, cwd=ROOT, timeout=60)


def test_at_and_from_are_read_and_written_back():
    package = parse_file(MODEL)
    forms = {i.name: (i.places, i.exact) for i in package.atom_types[0].invariants}
    assert forms == {"positive": ([], True), "small": (["T"], False), "alone": (["T"], True),
                     "both": (["S", "T"], False)}
    text = write_package(package)
    assert "invariant small from T provided (n <= 3)" in text
    assert "invariant alone at T provided (false)" in text
    assert "invariant both from S, T provided (false)" in text
    assert parse_text(text, "Invariants.bip") == package


@pytest.mark.parametrize("line, column, message", [
    ("invariant small under T provided (n <= 3)", 21, "expected 'at', 'from' or 'provided', found the name 'under'"),
    ("invariant small from T, V provided (n <= 3)", 29, "unknown place 'V' in atom type A"),
])
def test_bad_place_lists_are_located(tmp_path, line, column, message):
    path = tmp_path / "Invariants.bip"
    path.write_text(MODEL.read_text().replace("invariant small from T provided (n <= 3)", line))
    with pytest.raises(DiagnosticError) as err:
        parse_file(path)
    assert f"{path}:14:{column}: error: {message}" in err.value.render()


def test_from_holds_beside_other_places_at_only_on_the_exact_marking():
    safe = engine("Safe()")
    summary = safe.run(first)
    # go three times then stop: T and U marked, n = 3; 'alone at T' and 'both from S, T' are not in force
    assert (summary.steps, summary.outcome) == (4, "deadlock")
    assert safe.describe_state(summary.state)["a"] == {"places": ["T", "U"], "data": {"n": 3}}


def test_a_step_that_breaks_an_invariant_is_an_invariant_violation():
    unsafe = engine("Unsafe()")
    s = unsafe.initial_state()
    for _ in range(4):
        s = unsafe.fire(s, unsafe.find(s, "a.go"))
    with pytest.raises(InvariantViolation) as err:
        unsafe.fire(s, unsafe.find(s, "a.stop"))
    assert (err.value.invariant, err.value.atom) == ("small", "a")
    assert str(err.value) == "the invariant small of component a has been violated! (after a.stop)"
    summary = unsafe.run(first)
    assert (summary.steps, summary.outcome) == (5, "invariant")
    assert summary.line() == ("5 steps, invariant violated: the invariant small of component a has been violated! "
                              "(after a.stop)")


def test_the_initial_state_is_checked():
    with pytest.raises(InvariantViolation, match="the invariant positive of component a has been violated!$"):
        engine("Born()").initial_state()


def test_run_exits_5_with_the_reference_wording():
    r = cli("--root", "Unsafe()", "--policy", "first", "--quiet")
    assert r.returncode == 4
    assert r.stdout.splitlines()[-1].startswith("5 steps, invariant violated: the invariant small of component a")
    assert r.stderr == (f"{MODEL}: ERROR: the invariant small of component a has been violated! (after a.stop)\n")
    born = cli("--root", "Born()", "--quiet")
    assert born.returncode == 4 and born.stdout.startswith("0 steps, invariant violated: the invariant positive")
    safe = cli("--root", "Safe()", "--policy", "first", "--quiet")
    assert (safe.returncode, safe.stdout) == (0, "4 steps, deadlock (no enabled interaction)\n")


def test_exploration_reports_the_violation_with_a_shortest_trace():
    space = StateSpace(parse_file(MODEL), "Unsafe()")
    result = explore(space)
    assert result.stopped_by == "error"
    assert result.error.message == "the invariant small of component a has been violated! (after a.stop)"
    assert [str(s) for s in result.error.trace] == ["a.go"] * 4
    clean = explore(StateSpace(parse_file(MODEL), "Safe()"))
    # n stays in the state after 'stop' (the invariant at T reads it): one deadlock per value 0..3
    assert clean.complete and clean.error is None and len(clean.deadlocks) == 4


LATE = """package Late
  port type P()
  atom type A()
    data int n = 0
    port P inc(), stop(), last()
    place S, T, V
    initial to S
    on inc from S to S provided (n < 3) do { n = n + 1; }
    on stop from S to T
    on last from T to V
    invariant low from V provided (n <= 1)
  end
  compound type System()
    component A a()
  end
end
"""


def test_a_variable_read_only_by_an_invariant_is_kept_by_the_reduction():
    # no transition reads n after 'stop': without the invariant, the reduction would reset it at T
    result = explore(StateSpace(parse_text(LATE, "Late.bip"), "System()"))
    assert result.error.message == "the invariant low of component a has been violated! (after a.last)"
    assert [str(s) for s in result.error.trace] == ["a.inc", "a.inc", "a.stop"]


def test_the_compiled_explorer_leaves_invariants_to_python(capsys):
    space = StateSpace(parse_file(MODEL), "Unsafe()")
    assert compile_space(space) == (None, "the compiled explorer does not check atom invariants: "
                                          "exploring with the Python step")
    code = main(["verify", str(MODEL), "--root", "Unsafe()"])
    out = capsys.readouterr().out.splitlines()
    assert code != 0
    assert out[1] == "note: the compiled explorer does not check atom invariants: exploring with the Python step"
    assert "model error in state 7: the invariant small of component a has been violated! (after a.stop)" in out


TIMED = """package Tm
  port type P()
  atom type A()
    clock x unit second
    port P go()
    place S, U
    initial to S, U do { x = 0; }
    on go from S to S provided (x >= 4) do { x = 0; }
    invariant alone at S provided (x <= 2)
    invariant beside from S provided (x <= 5)
  end
  compound type System()
    component A a()
  end
end
"""


def test_timed_invariants_use_the_same_at_and_from(tmp_path):
    # S and U are marked: 'alone at S' is not in force, 'beside from S' bounds time at 5 s
    path = tmp_path / "Tm.bip"
    path.write_text(TIMED)
    r = subprocess.run([sys.executable, "-m", "runtime", "run", str(path), "--policy", "first", "--limit", "1"],
                       capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert r.returncode == 0, r.stderr
    assert "  [0] a.go [ 4s, 5s ]" in r.stdout.splitlines()


def test_spin_refuses_a_model_with_invariants(capsys, tmp_path):
    # said whether SPIN is installed or not: installing it would not help
    code = main(["verify", str(MODEL), "--root", "Unsafe()", "--engine", "spin", "--spin-dir", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 1
    assert err == ("genom2bip: error: the Promela translation does not check atom invariants: verify with "
                   "--engine compiled or python\n")
    assert list(tmp_path.iterdir()) == []
