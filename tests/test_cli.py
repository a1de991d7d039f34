"""The genom2bip command: the check verb's output, exit codes, errors on stderr, never a traceback."""
import json
import subprocess
import sys
from pathlib import Path

import pytest

from genom2bip import cli

ROOT = Path(__file__).resolve().parents[1]
RFLEX = ROOT / "tests" / "fixtures" / "genom2" / "rflex.gen"
DALA = ROOT / "descriptions" / "dala"
BAD = """typedef struct S { int a; } S;
module m { internal_data: S; };
request A { type: exec; exec_task: Nowhere; codel_start: f; };
request B { type: control; interrupt_activity: Ghost; };
"""


def run(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_check_prints_a_summary_of_a_genom2_module(capsys):
    code, out, err = run(capsys, "check", RFLEX)
    assert code == 0
    assert out.startswith("module rflex (genom2)")
    for line in (
        "  clock tick 10 ms (100 Hz)",
        "  MotorsTask: period 50 ms (5 ticks)  priority 100  stack 20000",
        "  SonarTask: period 200 ms (20 ticks)  delay 10 ms (1 tick)  priority 110  stack 10000",
        "  function SetSpeed(in speed::ref: RFLEX_SPEED)",
        "  activity TrackSpeed()  in task MotorsTask",
        "      states: start, exec, end, stop, fail",
        "      exec: rflexTrackMain -> pause::exec, pause::end, ether  wcet 2 ms",
        "      start/exec: rflexStopMain -> pause::exec, ether",
        "      interrupts TrackSpeed, Stop",
        "      throws MOTOR_ERROR, SPEED_TOO_HIGH",
        "  out Robot: rflex_Robot_poster  written by MotorsTask",
        "  in  pom_Pos: pom::Pos",
    ):
        assert line + "\n" in out, line
    # services are listed by kind: functions before activities
    assert out.index("function SetSpeed") < out.index("activity Init")
    # the poster read from a module that is not checked with this one is a warning, not an error
    assert "warning: type of poster 'pom::Pos' unchecked" in err
    assert "error" not in err


def test_check_the_dala_directory(capsys):
    code, out, err = run(capsys, "check", DALA)
    assert code == 0, err
    for name in ("LaserRF", "Aspect", "NDD", "RFLEX", "POM", "Planner"):
        assert f"component {name} (genom3)" in out
    assert "after SetParams, SetSpeed, SetDataSource" in out
    assert "motion: period 100 ms" in out
    rules = sum(1 for line in (DALA / "rules.yaml").read_text().splitlines() if line.startswith("  - id:"))
    assert f"rules: {rules} from {DALA / 'rules.yaml'}, " in out


def test_check_reads_the_rule_file_of_a_directory_and_locates_its_errors(tmp_path, capsys):
    for name in ("NDD.gen", "POM.gen", "dala.idl"):
        (tmp_path / name).write_text((DALA / name).read_text())
    rules = tmp_path / "rules.yaml"
    rules.write_text("rules:\n  - id: r\n    service: NDD.GoTo\n    requires: [POM.Fly]\n")
    code, out, err = run(capsys, "check", tmp_path)
    assert code == 1 and out == ""
    assert err.startswith(f"{rules}:4:16: error: "), err
    assert "POM.Fly" in err
    code, out, err = run(capsys, "check", tmp_path, "--no-rules")
    assert code == 0, err
    assert "rules:" not in out


def test_check_json_is_the_ir(capsys):
    code, out, _ = run(capsys, "check", "--json", RFLEX)
    assert code == 0
    data = json.loads(out)
    assert data["node"] == "Description"
    [comp] = data["components"]
    assert (comp["name"], comp["dialect"]) == ("rflex", "genom2")
    assert [s["name"] for s in comp["services"]] == ["Init", "SetSpeed", "GetOdo", "TrackSpeed", "Stop"]
    assert comp["services"][3]["ref_spans"]["task"].endswith("rflex.gen:54:19")
    assert comp["tasks"][0]["period"] == {"node": "Duration", "seconds": 0.05, "text": "5 ticks"}


def test_errors_go_to_stderr_with_location_and_caret(capsys, tmp_path):
    bad = tmp_path / "bad.gen"
    bad.write_text(BAD)
    code, out, err = run(capsys, "check", bad)
    assert code == 1
    assert out == ""
    lines = err.splitlines()
    assert lines[0] == f"{bad}:3:36: error: unknown task 'Nowhere' for activity 'A'"
    assert lines[1] == "    request A { type: exec; exec_task: Nowhere; codel_start: f; };"
    assert lines[2] == "                                       ^^^^^^^"
    assert f"{bad}:4:48: error: unknown service 'Ghost' in 'interrupts' of function 'B'" in err
    assert lines[-1] == "2 errors"


def test_syntax_errors_fail_before_the_checks(capsys, tmp_path):
    bad = tmp_path / "syntax.gen"
    bad.write_text(BAD.replace("request B { type: control;", "request B { type: control"))
    code, out, err = run(capsys, "check", "--json", bad)
    assert code == 1 and out == ""
    assert "syntax.gen:4:27: error: syntax error" in err
    assert "unknown task" not in err  # the checks run on descriptions that parse


def test_missing_file(capsys):
    code, out, err = run(capsys, "check", "/no/such/file.gen")
    assert code == 1
    assert err == "genom2bip: error: /no/such/file.gen: no such file or directory\n"


def test_empty_directory(capsys, tmp_path):
    code, _, err = run(capsys, "check", tmp_path)
    assert code == 1
    assert "no .gen file in this directory" in err


def test_include_dirs_and_defines(capsys, tmp_path):
    inc = tmp_path / "inc"
    inc.mkdir()
    (inc / "types.h").write_text("typedef struct S { int a; } S;\n")
    (tmp_path / "m.gen").write_text('#include "types.h"\nmodule m { internal_data: S; };\n'
                                    "exec_task T {\n#ifdef FAST\n  period: 1;\n#else\n  period: PERIOD;\n#endif\n};\n")
    code, out, err = run(capsys, "check", tmp_path / "m.gen", "-I", inc, "-D", "FAST")
    assert code == 0, err
    assert "T: period 10 ms (1 tick)" in out
    code, out, err = run(capsys, "check", tmp_path / "m.gen", "-I", inc, "-DPERIOD=7")
    assert code == 0, err
    assert "T: period 70 ms (7 ticks)" in out
    code, _, err = run(capsys, "check", tmp_path / "m.gen")
    assert code == 1 and "types.h" in err


def test_bad_define(capsys):
    code, _, err = run(capsys, "check", RFLEX, "-D", "1X=2")
    assert code == 2
    assert "'1X' is not a macro name" in err


def test_version(capsys):
    code, out, _ = run(capsys, "--version")
    assert code == 0
    assert out.startswith("genom2bip ")


@pytest.mark.parametrize("argv", [[], ["frobnicate"], ["check"], ["check", "--nope", "x.gen"]])
def test_usage_errors_exit_2(capsys, argv):
    code, _, err = run(capsys, *argv)
    assert code == 2
    assert "usage: genom2bip" in err


def test_unexpected_exception_is_one_line(capsys, monkeypatch):
    import genom2bip.checks

    def boom(description, reporter):
        raise RuntimeError("kaboom")

    monkeypatch.setattr(genom2bip.checks, "check_description", boom)
    monkeypatch.delenv("GENOM2BIP_TRACEBACK", raising=False)
    code, out, err = run(capsys, "check", RFLEX)
    assert code == 3
    assert err.strip().splitlines() == ["genom2bip: internal error: RuntimeError: kaboom",
                                        "genom2bip: run again with --traceback (or GENOM2BIP_TRACEBACK=1) to see where"]


@pytest.mark.parametrize("how", ["option", "environment"])
def test_traceback_on_request_shows_where_an_unexpected_exception_came_from(capsys, monkeypatch, how):
    import genom2bip.checks

    def boom(description, reporter):
        raise RuntimeError("kaboom")

    monkeypatch.setattr(genom2bip.checks, "check_description", boom)
    if how == "option":
        monkeypatch.delenv("GENOM2BIP_TRACEBACK", raising=False)
        code, out, err = run(capsys, "--traceback", "check", RFLEX)
    else:
        monkeypatch.setenv("GENOM2BIP_TRACEBACK", "1")
        code, out, err = run(capsys, "check", RFLEX)
    assert code == 3
    assert err.startswith("Traceback (most recent call last):")
    assert 'in boom\n    raise RuntimeError("kaboom")' in err
    assert err.strip().splitlines()[-1] == "genom2bip: internal error: RuntimeError: kaboom"


def test_verbs_are_one_function_each_listed_by_the_command():
    from genom2bip.cli import check, command

    assert list(command.VERBS) == ["check", "generate", "call", "verify", "graph", "mission", "campaign"]
    assert command.VERBS["check"].run is check.verb_check


def test_the_installed_command_never_prints_a_traceback(tmp_path):
    bad = tmp_path / "bad.gen"
    bad.write_text(BAD + "request {{{ ;;; \x00 @@ \n")
    proc = subprocess.run([sys.executable, "-m", "genom2bip", "check", str(bad)],
                          capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert proc.returncode == 1
    assert "Traceback" not in proc.stderr
    assert "bad.gen:5:" in proc.stderr


@pytest.mark.parametrize("option", ["--property", "--rules", None])
def test_binary_input_files_are_input_errors_not_internal_ones(tmp_path, capsys, option):
    binary = b"\x7fELF\x02\x01\x01\x00\xff\xfe\n"
    if option is None:
        path = tmp_path / "M.bip"
        argv = ["verify", path]
    else:
        path = tmp_path / ("p.mcl" if option == "--property" else "rules.yaml")
        argv = ["verify", DALA / "NDD.gen", option, path, "--max-states", "10"]
    path.write_bytes(binary)
    code, _, err = run(capsys, *argv)
    assert code == 1, err
    assert err.startswith(f"{path}:1:9: error: not a UTF-8 text file: byte 0xff cannot be read\n"), err
    assert "internal error" not in err and "Traceback" not in err
    assert path.read_bytes() == binary


@pytest.mark.parametrize("text,held", [
    ("struct s { long a; };\nconst long N = 3;\n", "1 type, 1 constant only"),  # GenoM3 IDL
    ("#define MAX 3\ntypedef struct S { long a[MAX]; } S_t;\n", "2 types only"),  # typedef, preprocessor
    ("/* a description still to be written */\n", "the file is empty"),
    ("", "the file is empty"),
])
def test_a_file_without_component_is_accepted_by_check_and_refused_by_generate(tmp_path, capsys, text, held):
    gen = tmp_path / "types.gen"
    gen.write_text(text)
    code, out, err = run(capsys, "check", gen)
    assert (code, out, err) == (0, f"no component in {gen}: {held} (nothing to generate, run or verify)\n", "")
    out_dir = tmp_path / "out"
    for argv in ([gen, "-o", out_dir], ["verify", gen]):
        code, out, err = run(capsys, *argv)
        assert code == 1
        assert err == (f"genom2bip: error: no component in {gen}: {held}; a model needs at least one component "
                       f"(or module)\n")
        assert "generator bug" not in err
    assert not out_dir.exists()


def test_a_file_name_the_terminal_cannot_show_is_escaped_not_an_internal_error(tmp_path):
    import os

    source = tmp_path / "robot é" / os.fsdecode(b"arm\xff.gen")
    source.parent.mkdir()
    source.write_bytes((ROOT / "tests/fixtures/genom3/counter.gen").read_bytes())
    env = {**os.environ, "PYTHONIOENCODING": "ascii"}
    for argv, shown in ((["check", source], b"robot \\xe9/arm\\udcff.gen:2:11"),
                        ([source, "-o", tmp_path / "out \u00e9"], b"out \\xe9/arm_/ (5 files)")):
        result = subprocess.run([sys.executable, "-m", "genom2bip", *map(str, argv)], capture_output=True,
                                env=env, cwd=ROOT, timeout=60, check=False)
        assert result.returncode == 0, result.stderr
        assert shown in result.stdout
