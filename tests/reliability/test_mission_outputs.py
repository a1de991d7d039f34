"""A mission's run is never lost, and its name never escapes ``--out``: everything it will write, every name and
every input it sends is checked before it runs; ``--view`` keeps the controller's token."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import urllib.error
import urllib.request

import pytest

from badinputkit import DALA, ROOT, genom2bip, tree

pytestmark = pytest.mark.reliability

SHORT = "steps:\n  - send: RFLEX.Init\n    expect: ok\n"


def _mission(tmp_path, text: str):
    path = tmp_path / "m.yaml"
    path.write_text(text)
    return path


def _not_run(done) -> None:
    """Refused before the controller started: exit 1, no report, never an internal error."""
    assert done.code == 1, done.out + done.err
    assert "internal error" not in done.err and "Traceback" not in done.err, done.err
    assert "mission " not in done.out and "requests:" not in done.out, done.out


def test_an_out_that_is_a_file_is_refused_before_the_run_and_the_file_is_kept(tmp_path):
    out = tmp_path / "results"
    out.write_text("kept\n")
    done = genom2bip("mission", _mission(tmp_path, SHORT), "--out", out, "--quiet")
    _not_run(done)
    assert done.err == f"genom2bip: error: --out {out}: the mission's trace and picture cannot be written there: " \
                       "not a directory\n"
    assert out.read_text() == "kept\n"


def test_an_out_where_nothing_can_be_made_is_refused_before_the_run(tmp_path):
    done = genom2bip("mission", _mission(tmp_path, SHORT), "--out", "/proc/genom2bip-x", "--quiet")
    _not_run(done)
    assert done.err.startswith("genom2bip: error: --out /proc/genom2bip-x: the mission's trace and picture cannot "
                               "be written there: nothing can be made in /proc: "), done.err
    assert not os.path.exists("/proc/genom2bip-x")


def test_codel_times_where_nothing_can_be_made_are_refused_before_the_run(tmp_path):
    done = genom2bip("mission", _mission(tmp_path, SHORT), "--out", tmp_path / "out", "--codel-times",
                     "/proc/genom2bip-times.json", "--quiet")
    _not_run(done)
    assert done.err.startswith("genom2bip: error: --codel-times /proc/genom2bip-times.json: cannot write it: "
                               "nothing can be made in /proc: "), done.err
    assert not (tmp_path / "out").exists()


def test_a_trace_file_that_is_a_directory_is_refused_before_the_run(tmp_path):
    out = tmp_path / "out"
    (out / "m.jsonl").mkdir(parents=True)
    done = genom2bip("mission", _mission(tmp_path, SHORT), "--out", out, "--quiet")
    _not_run(done)
    assert done.err == f"genom2bip: error: --out {out}: the mission's trace and picture cannot be written there: " \
                       f"{out / 'm.jsonl'} exists and is not a file\n"
    assert tree(out) == ["m.jsonl"]


@pytest.mark.parametrize("name, where, message", [
    ("../../escape1", "1:10", "mission: '../../escape1' cannot name the files written: a name is one component of "
                              "a path, without '/' or '\\'"),
    ("a/b", "1:10", "mission: 'a/b' cannot name the files written: a name is one component of a path, without "
                    "'/' or '\\'"),
    ("'..'", "1:10", "mission: '..' cannot name the files written: '..' names a directory"),
    ("''", "1:10", "mission: '' cannot name the files written: an empty name, or one with spaces at its ends"),
    ('"x\\ud800"', "1:10", "mission: 'x\\ud800' cannot name the files written: a name holds no control character "
                           "and no lone surrogate"),
    ("[a, b]", "1:10", "mission: a name expected (it names the files written: NAME.png, NAME.jsonl)"),
    ("{a: 1}", "1:10", "mission: a name expected (it names the files written: NAME.png, NAME.jsonl)"),
])
def test_a_mission_name_that_is_not_one_plain_file_name_is_located_and_nothing_is_written(tmp_path, name, where,
                                                                                           message):
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    mission = _mission(work, f"mission: {name}\n{SHORT}")
    done = genom2bip("mission", mission, "--out", work / "out", "--quiet")
    _not_run(done)
    assert done.err.startswith(f"{mission}:{where}: error: {message}\n"), done.err
    assert tree(tmp_path) == ["a", "a/b", "a/b/m.yaml"]  # nothing inside --out, nothing beside it


@pytest.mark.parametrize("inputs, message", [
    ("{goal: {x: fast, y: 0, theta: 0}}", "goal.x: expected a number, got 'fast'"),
    ("{goal: {x: 1, y: 0, theta: 0}, bogus: 1}", "unknown parameter 'bogus' (parameters of NDD.GoTo: goal)"),
    ("{}", "missing parameter 'goal'"),
])
def test_inputs_the_controller_would_refuse_are_located_before_the_run(tmp_path, inputs, message):
    mission = _mission(tmp_path, f"mission: m\nsteps:\n  - send: NDD.GoTo\n    with: {inputs}\n")
    done = genom2bip("mission", mission, "--out", tmp_path / "out", "--quiet")
    _not_run(done)
    assert done.err.startswith(f"{mission}:4:11: error: with: the controller would refuse this request to "
                               "NDD.GoTo: "), done.err
    assert message in done.err.splitlines()[0], done.err
    assert not (tmp_path / "out").exists()


def test_a_mission_with_the_token_set_runs_and_writes_its_trace(tmp_path, monkeypatch):
    """The mission's own requests carry the token the controller now asks for."""
    monkeypatch.setenv("GENOM2BIP_TOKEN", "jeton-€-secret")
    done = genom2bip("mission", _mission(tmp_path, SHORT), "--out", tmp_path / "out")
    assert done.code == 0, done.out + done.err
    assert "every expectation met" in done.out
    finals = [json.loads(line) for line in (tmp_path / "out" / "m.jsonl").read_text().splitlines()]
    assert [(e["service"], e["status"]) for e in finals if e.get("final")] == [("Init", "ok")]


def _post(url: str, token: str | None) -> int:
    headers = {"Content-Type": "application/json"} | ({"Authorization": f"Bearer {token}"} if token else {})
    request = urllib.request.Request(url, data=b"{}", headers=headers, method="POST")
    try:
        with urllib.request.urlopen(request, timeout=60) as answer:
            return answer.status
    except urllib.error.HTTPError as exc:
        return exc.code


def test_view_refuses_a_request_without_the_token(tmp_path):
    mission = _mission(tmp_path, f"mission: look\nworld: {DALA / 'worlds' / 'corridor.yaml'}\nsteps:\n"
                                 "  - wait: 600\n")  # the test ends the run once it has asked
    proc = subprocess.Popen([sys.executable, "-m", "genom2bip", "mission", str(mission), "--view", "--quiet",
                             "--out", str(tmp_path / "out")], cwd=ROOT, stdout=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONPATH": str(ROOT), "GENOM2BIP_TOKEN": "sekret"},
                            start_new_session=True)
    try:
        line = proc.stdout.readline()
        assert line.startswith("live view: http://127.0.0.1:"), line
        base = line.split()[2].removesuffix("/live/")
        assert _post(f"{base}/components/RFLEX/services/Stop", None) == 401
        assert _post(f"{base}/components/RFLEX/services/Stop", "wrong") == 401
        assert _post(f"{base}/components/RFLEX/services/Stop", "sekret") == 202
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=120)
        proc.stdout.close()


def test_the_report_of_a_goal_without_numbers_names_it_and_draws_no_star():
    """A package whose schema says nothing of a goal takes any value: the report says it as it was sent."""
    from genom2bip.mission import report
    from genom2bip.mission.runner import Outcome
    from genom2bip.mission.session import Run
    from genom2bip.mission.spec import Mission, Step
    from runtime.diagnostics import Span

    step = Step("send", Span("m.yaml", 3, 5), target="NDD.GoTo", inputs={"goal": {"x": "fast"}})
    outcome = Outcome(step, request=1, report={"status": "failed", "exception": "e_bad", "final": True})
    run = Run(Mission("m", ROOT / "m.yaml", None, [step]), None, [outcome])
    assert "  goal {'x': 'fast'}: not reached: e_bad" in report.text(run).splitlines()  # was a TypeError
    assert [(g["point"], g["distance_left"]) for g in report.goals(run)] == [(None, None)]


def test_a_token_file_that_cannot_be_read_is_refused_before_the_run(tmp_path):
    done = genom2bip("mission", _mission(tmp_path, SHORT), "--out", tmp_path / "out", "--token-file",
                     tmp_path / "nope")
    assert done.code == 2, done.out + done.err
    assert done.err == f"genom2bip: error: --token-file {tmp_path / 'nope'}: No such file or directory\n"
    assert not (tmp_path / "out").exists()
