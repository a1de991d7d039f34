"""Every exit status of the one table (runtime/exits.py), for ``genom2bip`` and for ``python -m runtime``; the table
in both ``--help`` and in the README."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

import runtime.cli as runtime_cli
from genom2bip.cli import command
from genom2bip.cli.command import main as genom2bip
from runtime.cli import main as runtime
from runtime.exits import TABLE, epilog

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
MODEL, TIMED = str(EXAMPLES / "model.bip"), str(EXAMPLES / "timed.bip")
ERRORS = str(ROOT / "tests" / "fixtures" / "engine" / "Errors.bip")


def test_the_table_has_one_meaning_per_status():
    codes = [code for code, _ in TABLE]
    assert codes == sorted(set(codes)) == [0, 1, 2, 3, 4, 5, 130, 141]


@pytest.mark.parametrize("main, argv", [(genom2bip, ["--help"]), (genom2bip, ["check", "--help"]),
                                        (runtime, ["--help"]), (runtime, ["explore", "--help"])],
                         ids=["genom2bip", "genom2bip check", "runtime", "runtime explore"])
def test_help_ends_with_the_table(main, argv, capsys):
    assert main(argv) == 0
    assert capsys.readouterr().out.rstrip().endswith(epilog())


def test_the_readme_shows_the_same_table():
    readme = (ROOT / "README.md").read_text()
    rows = re.findall(r"^\| `(\d+)` \| (.+) \|$", readme, re.M)
    assert [(int(code), meaning) for code, meaning in rows] == list(TABLE)


# --------------------------------------------------------------------------- genom2bip


def test_genom2bip_0_done(capsys):
    assert genom2bip(["check", str(EXAMPLES / "thermo.gen"), "-I", str(EXAMPLES / "include")]) == 0


def test_genom2bip_1_errors_in_the_input(tmp_path, capsys):
    bad = tmp_path / "bad.gen"
    bad.write_text("component bad {\n  task t { period 10 parsecs; };\n};\n")
    assert genom2bip(["generate", str(bad), "-o", str(tmp_path / "out")]) == 1
    assert re.search(rf"{re.escape(str(bad))}:2:\d+: error", capsys.readouterr().err)
    assert not (tmp_path / "out").exists()


def test_genom2bip_2_usage(capsys):
    assert genom2bip(["verify", MODEL, "--no-such-option"]) == 2
    assert "unrecognized arguments: --no-such-option" in capsys.readouterr().err


def _raising(monkeypatch, exc: BaseException):
    def boom(args):
        raise exc
    monkeypatch.setattr(command.VERBS["check"], "run", boom)


def test_genom2bip_3_internal_error(monkeypatch, capsys):
    _raising(monkeypatch, RuntimeError("a bug"))
    assert genom2bip(["check", str(EXAMPLES / "thermo.gen")]) == 3
    err = capsys.readouterr().err
    assert "genom2bip: internal error: RuntimeError: a bug" in err and "Traceback" not in err


def test_genom2bip_4_found(capsys):
    assert genom2bip(["verify", MODEL, "--root", "System()"]) == 4
    assert "deadlock" in capsys.readouterr().out


def test_genom2bip_5_inconclusive(capsys):
    assert genom2bip(["verify", MODEL, "--root", "System()", "--max-states", "2", "--engine", "python"]) == 5


def test_genom2bip_130_interrupted(monkeypatch, capsys):
    _raising(monkeypatch, KeyboardInterrupt())
    assert genom2bip(["check", str(EXAMPLES / "thermo.gen")]) == 130
    assert "genom2bip: interrupted" in capsys.readouterr().err


# 141 (campaign | head): tests/reliability/test_closed_pipe.py, test_a_campaign_whose_output_is_closed_..._141,
# runs a campaign whose reader goes away.


# --------------------------------------------------------------------------- python -m runtime


def test_runtime_0_a_run_that_ends_as_asked(capsys):
    assert runtime(["run", MODEL, "--root", "System()", "--seed", "1", "--limit", "100"]) == 0
    assert capsys.readouterr().out.splitlines()[-1].endswith("deadlock (no enabled interaction)")  # a run, no check


def test_runtime_1_errors_in_the_input(tmp_path, capsys):
    bad = tmp_path / "bad.bip"
    bad.write_text("package bad\n  atom type A(\nend\n")
    assert runtime(["run", str(bad)]) == 1
    assert f"{bad}:3:1: error: expected a name" in capsys.readouterr().err


def test_runtime_2_usage(capsys):
    assert runtime(["run", MODEL, "--no-such-option"]) == 2
    assert "unrecognized arguments" in capsys.readouterr().err


def test_runtime_3_internal_error(monkeypatch, capsys):
    def boom(args, out=None, err=None):
        raise RuntimeError("a bug")
    monkeypatch.setattr(runtime_cli, "run_command", boom)
    assert runtime(["run", MODEL]) == 3
    err = capsys.readouterr().err
    assert err == "python -m runtime: internal error: RuntimeError: a bug\n"


@pytest.mark.parametrize("argv, said", [
    (["run", ERRORS, "--root", "OneSafe()", "--policy", "first"], "model error"),
    (["explore", TIMED, "--root", "Top()", "--tick", "1ms"], "deadlock at state"),
], ids=["run: model error", "explore: deadlock"])
def test_runtime_4_found(argv, said, capsys):
    assert runtime(argv) == 4
    captured = capsys.readouterr()
    assert said in captured.out + captured.err


def test_runtime_5_inconclusive(capsys):
    assert runtime(["explore", TIMED, "--root", "Top()", "--max-states", "5"]) == 5
    assert "(stopped at the state limit)" in capsys.readouterr().out


def test_runtime_130_interrupted(monkeypatch, capsys):
    def stop(args, out=None, err=None):
        raise KeyboardInterrupt
    monkeypatch.setattr(runtime_cli, "run_command", stop)
    assert runtime(["run", MODEL]) == 130
    assert capsys.readouterr().err == "interrupted\n"


@pytest.mark.parametrize("argv", [["-m", "gen.dala", "describe"],
                                  ["-m", "runtime", "run", MODEL, "--root", "System()", "--limit", "50"]],
                         ids=["gen.dala describe", "runtime run"])
def test_141_an_output_closed_by_its_reader_ends_quietly(argv):
    """``... | head``: the pipe's reader is gone before the first line (closed before the command starts)."""
    import os
    import subprocess
    import sys

    read, write = os.pipe()
    os.close(read)
    try:
        done = subprocess.run([sys.executable, *argv], cwd=ROOT, stdout=write, stderr=subprocess.PIPE, text=True,
                              env={**os.environ, "PYTHONPATH": f"{ROOT / 'gen'}{os.pathsep}{ROOT}"}, timeout=300)
    finally:
        os.close(write)
    assert done.returncode == 141, done.stderr
    assert "Traceback" not in done.stderr and "BrokenPipeError" not in done.stderr, done.stderr


def test_genom2bip_5_out_of_memory_is_a_limit_not_a_bug(tmp_path, capsys, monkeypatch):
    """The system refusing memory to the zone search (its first allocation made to fail, as under a ulimit): the
    command says so in one line with the way to stop earlier, and exits as at any other limit."""
    from runtime.zones.csearch import library

    lib = library()
    if lib is None:
        pytest.skip("the C zone search needs a C compiler (apt-get install gcc)")
    platform = tmp_path / "one.yaml"
    platform.write_text("cores: 1\n")
    anomaly = ROOT / "tests" / "fixtures" / "platform" / "Anomaly.gen"
    monkeypatch.chdir(tmp_path)  # where a verify writes its traces
    lib.zs_fail_allocation(0)
    try:
        code = genom2bip(["verify", str(anomaly), "--timed", "--platform", str(platform), "--response-times"])
    finally:
        lib.zs_fail_allocation(-1)
    err = capsys.readouterr().err
    assert code == 5, err
    assert "genom2bip: out of memory (zone search: no memory for its context); --max-memory MB stops a search " \
           "earlier and reports what it found" in err
    assert "internal error" not in err and "Traceback" not in err
    assert [p.name for p in tmp_path.iterdir()] == ["one.yaml"]  # nothing written: no verdict was reached
