"""``genom2bip verify``'s answer: a summary line per check first, the details and the traces in a directory
(``--traces``), one JSON document that follows genom2bip/cli/verify_schema.json (``--json``), and a bad
``--traces`` refused before anything runs (docs/output.md)."""
from __future__ import annotations

import io
import json
import os
import shutil
from pathlib import Path

import jsonschema
import pytest

from genom2bip.cli import main
from genom2bip.cli.verify_report import SCHEMA
from tests.verifykit import FIXTURES

ROOT = Path(__file__).resolve().parents[1]
DINING = str(FIXTURES / "Dining.bip")
COUNTERS = str(FIXTURES / "Counters.bip")
SERVER = str(FIXTURES / "Server.bip")
PLATFORM = ROOT / "tests" / "fixtures" / "platform"
FP1 = "cores: 1\npolicy: fixed-priority\nbest: wcet\n"


@pytest.fixture
def default_traces(monkeypatch, tmp_path):
    """verify as a user runs it: no GENOM2BIP_TRACES, in a fresh working directory."""
    monkeypatch.delenv("GENOM2BIP_TRACES", raising=False)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def run(capsys, *argv) -> tuple[int, str, str]:
    code = main(["verify", *[str(a) for a in argv]])
    out, err = capsys.readouterr()
    return code, out, err


def document(capsys, *argv) -> tuple[int, dict]:
    """``verify --json``: the exit status and the document, validated against the shipped schema."""
    code, out, err = run(capsys, *argv, "--json")
    data = json.loads(out)
    jsonschema.validate(data, json.loads(SCHEMA.read_text()))
    assert data["exit_status"] == code, err
    return code, data


def props(tmp_path: Path) -> Path:
    path = tmp_path / "p.mcl"
    path.write_text('ok: "S.req" precedes "S.work";\nbad: never "S.reply"\n')
    return path


def listing(path: Path) -> list[str]:
    return sorted(str(p.relative_to(path)) for p in path.rglob("*"))


# --------------------------------------------------------------------------- the summary and the files


def test_by_default_the_summary_comes_first_and_the_traces_go_to_out_traces(capsys, default_traces):
    code, out, err = run(capsys, DINING, "--root", "Table2()")
    assert code == 4, err
    lines = out.splitlines()
    assert lines[0] == f"model {DINING} (Table2())"
    assert lines[1] == "summary (1 check: 1 violated):"
    assert lines[2].startswith("  violated  deadlock freedom (compiled search, 6 states, 8 transitions, ")
    assert lines[2].endswith(": 1 reachable deadlock  → deadlock-1.txt")
    where = Path("out/traces/Dining")
    assert lines[3] == f"details in {where}/verify.txt, 1 trace as NAME.txt and NAME.json (--traces terminal " \
                       "prints them here)"
    assert lines[4].startswith("exit status 4: found: a deadlock")  # said when not 0
    assert len(lines) == 5  # no trace on the terminal
    directory = default_traces / where
    assert sorted(p.name for p in directory.iterdir()) == [".genom2bip", "deadlock-1.json", "deadlock-1.txt",
                                                          "verify.txt"]
    text = (directory / "deadlock-1.txt").read_text()
    assert text.splitlines() == ["deadlock freedom: deadlock", "deadlock 1 of 1 (state 4, 2 steps):",
                                 "       1  left0", "       2  left1", "  state:", "    p0: ONE", "    p1: ONE",
                                 "    f0: BUSY", "    f1: BUSY"]
    data = json.loads((directory / "deadlock-1.json").read_text())
    assert [s["label"] for s in data["trace"]["steps"]] == ["left0", "left1"]
    assert data["state"] == ["p0: ONE", "p1: ONE", "f0: BUSY", "f1: BUSY"] and data["what"] == "deadlock"
    details = (directory / "verify.txt").read_text()
    assert "deadlocks: 1 reachable state without enabled interaction" in details and "       2  left1" in details


def test_traces_terminal_prints_the_details_and_traces_as_they_come_and_writes_nothing(capsys, default_traces):
    code, out, _ = run(capsys, DINING, "--root", "Table2()", "--traces", "terminal")
    assert code == 4
    lines = out.splitlines()
    assert lines[0] == f"model {DINING} (Table2())" and lines[1].startswith("explored: 6 states")
    assert lines[3:6] == ["deadlock 1 of 1 (state 4, 2 steps):", "       1  left0", "       2  left1"]
    assert "summary" not in out
    assert listing(default_traces) == []


def test_the_details_file_holds_what_the_terminal_mode_prints(capsys, tmp_path):
    code, terminal, _ = run(capsys, SERVER, "--property", props(tmp_path), "--engine", "python",
                            "--traces", "terminal")
    code2, _, _ = run(capsys, SERVER, "--property", props(tmp_path), "--engine", "python",
                      "--traces", tmp_path / "t")
    assert code == code2 == 4
    details = (tmp_path / "t" / "verify.txt").read_text()
    strip = [line for line in terminal.splitlines() if " s" not in line]  # times differ from run to run
    assert strip and all(line in details.splitlines() for line in strip)


def test_a_violated_property_names_its_counterexample_file(capsys, tmp_path):
    code, out, _ = run(capsys, SERVER, "--property", props(tmp_path), "--engine", "python",
                       "--traces", tmp_path / "t")
    assert code == 4
    summary = [line for line in out.splitlines() if line.startswith("  ")]
    assert [line.split()[:3] for line in summary] == [["holds", "property", "ok"], ["violated", "property", "bad"]]
    assert summary[1].endswith("→ property-bad-counterexample.txt")
    text = (tmp_path / "t" / "property-bad-counterexample.txt").read_text().splitlines()
    assert text[0] == "property bad: counterexample" and any("S.reply" in line for line in text)
    data = json.loads((tmp_path / "t" / "property-bad-counterexample.json").read_text())
    assert data["trace"]["steps"][-1]["label"] == "S.reply"


def test_a_second_run_replaces_the_traces_of_the_first(capsys, tmp_path):
    target = tmp_path / "t"
    assert run(capsys, DINING, "--root", "Table2()", "--traces", target)[0] == 4
    (target / "notes.md").write_text("mine")  # a file of the user's stays
    code, out, _ = run(capsys, DINING, "--root", "Table2()", "--traces", target, "--max-states", "1")
    assert code == 5 and "inconclusive" in out
    assert sorted(p.name for p in target.iterdir()) == [".genom2bip", "notes.md", "verify.txt"]


# --------------------------------------------------------------------------- bad --traces


@pytest.mark.parametrize("shape", ["file", "foreign", "under-a-file"])
def test_a_bad_traces_directory_is_refused_before_anything_runs_and_nothing_is_written(capsys, tmp_path, shape):
    if shape == "file":
        target = tmp_path / "report.txt"
        target.write_text("keep")
        expected = "exists and is not a directory"
    elif shape == "foreign":
        target = tmp_path / "mine"
        target.mkdir()
        (target / "notes.md").write_text("keep")
        expected = "genom2bip did not write it (no valid .genom2bip marker); move it away or choose another " \
                   "--traces DIR"
    else:
        (tmp_path / "plain").write_text("keep")
        target = tmp_path / "plain" / "traces"
        expected = f"{tmp_path / 'plain'} is not a directory"
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    code, out, err = run(capsys, DINING, "--root", "Table2()", "--traces", target)
    assert code == 1
    assert out == ""  # nothing ran
    assert err.startswith(f"genom2bip: error: --traces {target}: ") and expected in err, err
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == before


def test_the_traces_directory_cannot_be_an_input(capsys, tmp_path):
    model = tmp_path / "m"
    model.mkdir()
    (model / "Dining.bip").write_bytes(Path(DINING).read_bytes())
    code, out, err = run(capsys, model / "Dining.bip", "--root", "Table2()", "--traces", model)
    assert code == 1 and out == ""
    assert "it contains the input" in err and "choose another --traces DIR" in err
    assert listing(model) == ["Dining.bip"]


def test_a_bad_default_directory_says_how_to_choose_another(capsys, default_traces):
    Path("out").write_text("not a directory")
    code, out, err = run(capsys, DINING, "--root", "Table2()")
    assert code == 1 and out == ""
    assert "is not a directory" in err and "--traces DIR or --traces terminal" in err


# --------------------------------------------------------------------------- --json


def test_json_of_a_deadlock_found(capsys, tmp_path):
    code, data = document(capsys, DINING, "--root", "Table2()", "--traces", tmp_path / "t")
    assert code == 4
    (check,) = data["checks"]
    assert (check["kind"], check["subject"], check["verdict"]) == ("deadlock", "deadlock freedom", "violated")
    assert check["figures"]["states"] == 6 and check["figures"]["transitions"] == 8
    (trace,) = check["traces"]
    assert trace["files"] == {"text": str(tmp_path / "t" / "deadlock-1.txt"),
                              "json": str(tmp_path / "t" / "deadlock-1.json")}
    assert json.loads(Path(trace["files"]["json"]).read_text())["trace"]["steps"][0]["label"] == "left0"
    assert "trace" not in json.dumps(check["result"]["details"]).replace("traces", "")  # traces live in files
    assert data["model"]["root"] == "Table2()" and data["platform"] is None
    assert data["details"] == str(tmp_path / "t" / "verify.txt")


def test_json_of_an_lts_export_that_meets_a_deadlock(capsys, tmp_path):
    code, data = document(capsys, DINING, "--root", "Table3()", "--aut", tmp_path / "m.aut", "--engine", "explore",
                          "--traces", tmp_path / "t")
    assert code == 4 and data["exit_status"] == 4
    (check,) = data["checks"]
    assert (check["kind"], check["verdict"]) == ("deadlock", "violated")
    assert (tmp_path / "m.aut").read_text().startswith("des (0, 27, 14)")


def test_json_of_a_property_violated_with_traces_inline(capsys, tmp_path):
    code, data = document(capsys, SERVER, "--property", props(tmp_path), "--engine", "python",
                          "--traces", "terminal")
    assert code == 4
    verdicts = {c["subject"]: c["verdict"] for c in data["checks"]}
    assert verdicts == {"property ok": "holds", "property bad": "violated"}
    (trace,) = next(c for c in data["checks"] if c["subject"] == "property bad")["traces"]
    assert trace["files"] is None and trace["what"] == "counterexample"
    assert trace["trace"]["steps"][-1]["label"] == "S.reply"
    assert data["traces_directory"] is None
    assert listing(tmp_path) == ["p.mcl"]


def test_json_of_response_times_and_a_real_no_bound(capsys, tmp_path):
    platform = tmp_path / "fp1.yaml"
    platform.write_text(FP1)
    code, data = document(capsys, PLATFORM / "Waiting.gen", "--timed", "--platform", platform, "--response-times",
                          "--traces", tmp_path / "t")
    assert data["platform"] == "1 core, fixed-priority" or data["platform"].startswith("1 core")
    assert data["tick_ms"] == 1 and data["model"]["timed"] is True
    responses = {c["subject"]: c for c in data["checks"] if c["kind"] == "response"}
    ping = responses["response time of Waiting.Ping"]
    assert (ping["value"], ping["value_ms"]) == ("no bound", None)
    assert ping["message"] == "no bound: a request can wait for ever"
    assert ping["traces"][0]["what"] == "lasso" and ping["traces"][0]["loop"] is not None
    busy = responses["response time of Waiting.busy"]
    assert (busy["value"], busy["value_ms"], busy["verdict"]) == ("10 ms", 10, "holds")
    periods = {c["subject"]: c["verdict"] for c in data["checks"] if c["kind"] == "observer"}
    assert periods["period of Waiting.idle (10 ms)"] == "violated" and code == 4


def test_json_and_summary_of_services_that_run_until_stopped(capsys, tmp_path):
    platform = tmp_path / "fp1.yaml"
    platform.write_text(FP1)
    argv = (PLATFORM / "Polling.gen", "--timed", "--platform", platform, "--response-times")
    code, data = document(capsys, *argv, "--traces", tmp_path / "t")
    assert code == 0
    values = {c["subject"]: (c["value"], c["message"]) for c in data["checks"] if c["kind"] == "response"}
    running = "works every period once started, may go on for ever (not a fault)"
    assert values["response time of Polling.Poll"] == ("until stopped", running)
    assert values["response time of Polling.Track"] == ("until stopped", running)
    code, out, _ = run(capsys, *argv, "--traces", tmp_path / "t2")
    poll = next(line for line in out.splitlines() if "Polling.Poll" in line)
    assert poll.split()[:2] == ["until", "stopped"] and "no bound" not in out and running in poll
    assert out.splitlines()[-1].startswith(f"details in {tmp_path / 't2'}/verify.txt")  # exit status 0: no line


def test_json_of_a_timed_check_that_holds(capsys, tmp_path):
    code, data = document(capsys, PLATFORM / "Endless.gen", "--timed", "--schedulability", "--no-exceptions",
                          "--traces", tmp_path / "t")
    assert code == 0
    (check,) = data["checks"]
    assert (check["kind"], check["verdict"], check["message"]) == ("observer", "holds", "no overrun reachable")
    assert check["figures"]["states"] > 0 and check["traces"] == []
    assert data["platform"].startswith("a core per task")


def test_json_of_a_search_stopped_by_a_limit(capsys, tmp_path):
    code, data = document(capsys, COUNTERS, "--max-states", "3", "--traces", tmp_path / "t")
    assert code == 5
    (check,) = data["checks"]
    assert check["verdict"] == "inconclusive" and check["result"]["limit"] == "max-states"


def test_json_prints_nothing_but_the_document(capsys, tmp_path):
    code, out, err = run(capsys, DINING, "--root", "Table2()", "--json", "--traces", tmp_path / "t")
    assert code == 4 and out.startswith("{") and out.rstrip().endswith("}")
    assert json.loads(out)["checks"][0]["verdict"] == "violated"


def test_the_schema_is_shipped_with_the_package():
    text = (ROOT / "pyproject.toml").read_text()
    assert "cli/verify_schema.json" in text and SCHEMA.is_file()
    jsonschema.Draft202012Validator.check_schema(json.loads(SCHEMA.read_text()))


def test_the_environment_sets_the_default(capsys, monkeypatch, tmp_path):
    monkeypatch.setenv("GENOM2BIP_TRACES", str(tmp_path / "env"))
    code, out, _ = run(capsys, DINING, "--root", "Table2()")
    assert code == 4 and f"details in {tmp_path / 'env'}/verify.txt" in out
    assert os.path.isfile(tmp_path / "env" / "deadlock-1.txt")


# --------------------------------------------------------------------------- progress on long waits


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_progress_line_fits_one_row_of_the_terminal(monkeypatch):
    """A line wider than the terminal wraps, and ``\\r`` then redraws only its last row: the line is cut to fit."""
    from runtime.explore.progress import Progress

    monkeypatch.setenv("COLUMNS", "50")
    stream = _Terminal()
    progress = Progress(stream, delay=0)
    progress.tick(3_855_360, 12_345_678, 1_234_567, lambda: 7 * 2**30, depth=1234)
    drawn = stream.getvalue().split("\r")[-1]
    assert drawn.startswith("states 3,855,360  transitions 12,345,678") and len(drawn) <= 49


@pytest.mark.skipif(shutil.which("spin") is None, reason="SPIN is not installed (apt-get install spin)")
def test_spin_says_what_it_does_before_its_search(capsys, tmp_path):
    code, out, err = run(capsys, DINING, "--root", "Table2()", "--engine", "spin", "--progress",
                         "--traces", tmp_path / "t")
    assert code == 4 and "violated  deadlock freedom (SPIN, " in out
    assert "genom2bip: SPIN: translating the model to Promela, generating pan.c and compiling it ..." in err
    assert "genom2bip: SPIN: pan ready in " in err


def test_a_ctrl_c_the_search_does_not_take_still_gives_the_summary_and_writes_what_is_known(capsys, tmp_path,
                                                                                             monkeypatch):
    """The second property's check is cut by a KeyboardInterrupt (a Ctrl-C outside a search's own handler)."""
    import genom2bip.verify as api

    checked = []
    original = api.check_property

    def check_then_interrupt(*a, **kw):
        if checked:
            raise KeyboardInterrupt
        checked.append(1)
        return original(*a, **kw)

    monkeypatch.setattr(api, "check_property", check_then_interrupt)
    code, out, err = run(capsys, SERVER, "--property", props(tmp_path), "--engine", "python",
                         "--traces", tmp_path / "t")
    assert code == 130 and "genom2bip: interrupted" in err
    lines = out.splitlines()
    assert lines[1] == "summary (1 check: 1 holds):" and lines[2].startswith("  holds  property ok (")
    assert lines[-1] == "exit status 130: interrupted by Ctrl-C (or SIGTERM), after saying what was known"
    assert "property ok" in (tmp_path / "t" / "verify.txt").read_text()


def test_a_violation_found_while_the_search_goes_on_is_said_at_once_and_its_trace_written(capsys, tmp_path):
    platform = tmp_path / "fp1.yaml"
    platform.write_text(FP1)
    code, out, err = run(capsys, PLATFORM / "Starved.gen", "--timed", "--platform", platform,
                         "--traces", tmp_path / "t")
    assert code == 4
    assert "genom2bip: found: period of Starved.idle (10 ms): overrun reachable (found after " in err
    line = next(line for line in out.splitlines() if "Starved.idle" in line)
    assert line.split()[0] == "violated" and line.endswith("→ overrun-period-of-Starved.idle-10-ms.txt")
    text = (tmp_path / "t" / "overrun-period-of-Starved.idle-10-ms.txt").read_text()
    assert text.startswith("period of Starved.idle (10 ms): counterexample\n") and "Starved.idle:late" in text


def test_an_empty_traces_option_is_a_usage_error(capsys):
    code, out, err = run(capsys, DINING, "--root", "Table2()", "--traces", "")
    assert code == 2 and out == "" and "--traces: give a directory, or 'terminal'" in err
