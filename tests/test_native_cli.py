"""``genom2bip verify --engine compiled|python``: the same report, notes when falling back, progress and Ctrl-C."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from genom2bip.cli import main
from tests.nativekit import needs_cc
from tests.verifykit import FIXTURES, ROOT

DINING = str(FIXTURES / "Dining.bip")


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out.splitlines(), err


def without_summary(lines: list[str]) -> list[str]:
    """The report without the line of figures (time, rate, bytes), which differ between engines."""
    return [line for line in lines if not line.startswith("explored: ")]


@needs_cc
@pytest.mark.parametrize("path, root", [(DINING, "Table3()"), (str(FIXTURES / "Codel.bip"), "Main()"),
                                        (str(FIXTURES / "Counters.bip"), "Pair()")])
def test_compiled_and_python_print_the_same_report(capsys, path, root):
    code_c, out_c, _ = run(capsys, "verify", path, "--root", root, "--engine", "compiled")
    code_p, out_p, _ = run(capsys, "verify", path, "--root", root, "--engine", "python")
    assert code_c == code_p
    assert without_summary(out_c) == without_summary(out_p)
    summary = next(line for line in out_c if line.startswith("explored: "))
    assert summary.split(";")[0] == next(line for line in out_p if line.startswith("explored: ")).split(";")[0]
    assert not any(line.startswith("note:") for line in out_c)


def test_without_a_compiler_one_note_and_the_same_answers(capsys, monkeypatch):
    _, expected, _ = run(capsys, "verify", DINING, "--root", "Table2()", "--engine", "python")
    monkeypatch.setenv("PATH", "")
    monkeypatch.delenv("CC", raising=False)
    code, out, _ = run(capsys, "verify", DINING, "--root", "Table2()")
    assert code == 4
    assert out[1] == "note: no C compiler on PATH (gcc or $CC): exploring with the Python step"
    assert without_summary(out[:1] + out[2:]) == without_summary(expected)


@needs_cc
def test_a_model_the_c_step_does_not_take_is_explored_in_python(capsys, tmp_path):
    model = tmp_path / "Halves.bip"
    model.write_text("""package Halves
  port type Port()
  atom type A()
    data float h
    port Port p()
    place s, t
    initial to s
    on p from s to t do { h = 7; h = h / 2; }
  end
  compound type Main()
    component A a()
  end
end
""")
    code, out, _ = run(capsys, "verify", str(model))
    assert out[1] == (f"note: compiled exploration does not take this model (atom a (A), transition on p from s to t "
                      f"({model}:8:8): an int value assigned to a float variable (the Python step keeps it an int, "
                      "with int arithmetic; write a float constant such as 1.0)): exploring with the Python step")
    assert out[2].startswith("explored: 2 states") and code == 4


@needs_cc
def test_lts_exports_say_they_use_the_python_step(capsys, tmp_path):
    _, out, _ = run(capsys, "verify", DINING, "--root", "Table2()", "--aut", str(tmp_path / "d.aut"))
    assert "note: LTS exports need every successor list: exploring with the Python step" in out
    assert (tmp_path / "d.aut").read_text().startswith("des (0, 8, 6)")


@needs_cc
def test_safety_properties_run_compiled_and_the_others_say_they_run_in_python(capsys, tmp_path):
    props = tmp_path / "p.mcl"
    props.write_text('ok: "S.req" precedes "S.work";\nbad: never "S.reply";\nreach: <true* . "S.reply"> true\n')
    code_c, out_c, _ = run(capsys, "verify", str(FIXTURES / "Server.bip"), "--property", str(props))
    code_p, out_p, _ = run(capsys, "verify", str(FIXTURES / "Server.bip"), "--property", str(props),
                           "--engine", "python")
    assert code_c == code_p == 4
    assert out_c[1] == "property ok: \"S.req\" precedes \"S.work\""
    assert out_c[3].startswith("  holds (compiled observer search, ")
    assert any(line.startswith("  violated (compiled observer search") for line in out_c)
    assert "note: property reach is checked with the Python step" in " ".join(out_c)
    traces = [line for line in out_c if line.startswith("       ")]
    assert traces == [line for line in out_p if line.startswith("       ")]


def test_max_memory_must_be_positive(capsys):
    code, _, err = run(capsys, "verify", DINING, "--max-memory", "-1")
    assert code == 2 and "--max-memory must be >= 0" in err


def big_dining(tmp_path: Path, n: int = 22) -> str:
    sys.path.insert(0, str(ROOT / "bench"))
    from verify_bench import dining

    path = tmp_path / f"Dining{n}.bip"
    path.write_text(dining(n), encoding="utf-8")
    return str(path)


#: Runs genom2bip with Ctrl-C's default meaning: a shell starts a background job (CI's tests, a run under
#: nohup) with SIGINT ignored, and a process keeps that, so SIGINT would not stop it.
WITH_CTRL_C = ("import runpy, signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
               "sys.argv[0] = 'genom2bip'; runpy.run_module('genom2bip', run_name='__main__')")


@pytest.mark.parametrize("engine", [pytest.param("compiled", marks=needs_cc), "python"])
def test_ctrl_c_prints_a_summary_of_what_was_explored(tmp_path, engine):
    """Ctrl-C once the first progress line is out: the summary says interrupted (exit 5).

    The memory bound (2 GB) is only a safety net: the signal comes about a second into the search, when
    either engine holds a few MB; a search that ignored it would be killed 120 s later, not wait for it.
    """
    model = big_dining(tmp_path)
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen([sys.executable, "-c", WITH_CTRL_C, "verify", model, "--engine", engine, "--progress",
                             "--max-memory", "2000"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env, cwd=tmp_path)
    seen: list[str] = []
    out: list[str] = []
    progressed = threading.Event()

    def read_err():
        for line in proc.stderr:
            seen.append(line)
            if "states/s" in line:
                progressed.set()
        progressed.set()  # the process ended without one: the assertions below say so

    readers = [threading.Thread(target=read_err, daemon=True),
               threading.Thread(target=lambda: out.extend(proc.stdout), daemon=True)]
    for reader in readers:
        reader.start()
    try:
        progressed.wait(timeout=600)  # an event: the first line comes about a second into the search
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=120)
        for reader in readers:
            reader.join(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    err = "".join(seen)
    assert proc.returncode == 5, err
    assert "states/s" in err and "depth" in err  # the progress line appeared after a second
    assert "until complete or 2.0 GB (--max-memory); Ctrl-C stops and reports what was explored" in err
    summary = next(line for line in out if line.startswith("explored: "))
    assert "stopped at interrupted" in summary
    assert "deadlocks: none reachable in the explored part" in "".join(out)


def test_the_python_search_stops_at_its_memory_bound_and_reports_what_it_explored(tmp_path, capsys):
    model = big_dining(tmp_path, 12)
    code, out, err = run(capsys, "verify", model, "--engine", "python", "--max-memory", "2", "--progress")
    assert code == 5, (out, err)
    assert "until complete or 2 MB (--max-memory); Ctrl-C stops and reports what was explored" in err
    summary = next(line for line in out if line.startswith("explored: "))
    assert "stopped at max-memory" in summary
    assert "note: the Python search stopped past 2 MB (--max-memory MB sets the bound)" in out
