"""Mission files: what they say, and every mistake named with file:line:column before anything runs."""
from __future__ import annotations

import pytest

from genom2bip.cli import main
from genom2bip.mission.runner import unmet
from genom2bip.mission.spec import read_mission
from runtime.diagnostics import DiagnosticError
from tests.runkit import ROOT

GOOD = """\
mission: trip
world: worlds/w.yaml
steps:
  - send: NDD.GoTo
    as: drive
    with: {goal: {x: 1, y: 2, theta: 0}}
    until: started
  - wait: 2.5
  - await: drive
    expect: {status: failed, exception: e_blocked}
    timeout: 30
"""


def test_a_mission_reads_into_steps(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text(GOOD)
    m = read_mission(path)
    assert m.name == "trip" and m.world == (tmp_path / "worlds" / "w.yaml").resolve()
    send, wait, wait_for = m.steps
    assert (send.kind, send.target, send.name, send.until) == ("send", "NDD.GoTo", "drive", "started")
    assert send.inputs == {"goal": {"x": 1, "y": 2, "theta": 0}}
    assert (wait.kind, wait.seconds) == ("wait", 2.5)
    assert (wait_for.target, wait_for.expect, wait_for.timeout) == ("drive", {"status": "failed",
                                                                               "exception": "e_blocked"}, 30.0)


@pytest.mark.parametrize(
    "text, where, message",
    [
        ("steps:\n  - send: GoTo\n", "2:11", "send: Module.Service expected, got 'GoTo'"),
        ("steps:\n  - send: NDD.Stop\n    expect: done\n", "3:13", "expect: unknown status 'done'"),
        ("steps:\n  - send: NDD.Stop\n    expect: {status: ok, rules: x}\n", "3:26", "expect: unknown key 'rules'"),
        ("steps:\n  - await: drive\n", "2:12", "await: no earlier step named 'drive'"),
        ("steps:\n  - wait: soon\n", "2:11", "wait: a number of seconds (0 or more) expected, got 'soon'"),
        ("steps:\n  - send: NDD.Stop\n    until: done\n", "3:12", "until: one of queued, started, final expected"),
        (
            "steps:\n  - send: NDD.Stop\n    wait: 2\n",
            "2:5",
            "a step has exactly one of send, wait, await (has send, wait)",
        ),
        ("steps:\n  - send: NDD.Stop\n    with: 3\n", "3:11", "with: a mapping of the service's inputs expected"),
        ("steps:\n  - send: NDD.Stop\n    retry: 3\n", "3:5", "send step: unknown key 'retry'"),
        ("mission: x\n", "1:1", "'steps': a list of send, wait and await steps expected"),
        ("steps: [\n", "2:1", "not valid YAML"),
    ],
)
def test_mistakes_are_named_with_their_position(tmp_path, text, where, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(DiagnosticError) as err:
        read_mission(path)
    shown = str(err.value)
    assert f"{path}:{where}" in shown
    assert message in shown


def test_the_mission_verb_reports_a_bad_file_and_writes_nothing(tmp_path, capsys):
    path = tmp_path / "bad.yaml"
    path.write_text("steps:\n  - send: NDD.Stop\n    expect: done\n  - await: nobody\n")
    out = tmp_path / "out"
    assert main(["mission", str(path), "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"{path}:3:13" in err and f"{path}:4:12" in err and "2 errors" in err
    assert not out.exists()


def test_the_mission_verb_names_a_missing_world_or_package(tmp_path, capsys):
    path = tmp_path / "m.yaml"
    path.write_text("steps:\n  - wait: 1\n")
    out = tmp_path / "out"
    assert main(["mission", str(path), "--world", str(tmp_path / "nowhere.yaml"), "--out", str(out)]) == 1
    assert "nowhere.yaml: no such world file" in capsys.readouterr().err
    assert main(["mission", str(path), "--package", str(tmp_path / "nopkg"), "--out", str(out)]) == 1
    assert "no generated package here" in capsys.readouterr().err
    assert not out.exists()


def test_expectations_compare_status_rule_exception_and_interrupter():
    report = {"status": "failed", "exception": "NDD::e_blocked", "message": "codel nddPlan threw NDD::e_blocked"}
    assert unmet({"status": "failed", "exception": "e_blocked"}, report) is None
    assert unmet({"exception": "NDD::e_blocked"}, report) is None
    assert unmet({"status": "ok"}, report) == ("expected status ok, got 'failed' "
                                               "(codel nddPlan threw NDD::e_blocked)")
    assert unmet({"status": "rejected", "rule": "goto-after-pom-run"},
                 {"status": "rejected", "rule": "NDD.GoTo.after"}).startswith("expected rule goto-after-pom-run")
    assert unmet(None, report) is None


def test_the_repository_missions_read(tmp_path):
    for path in sorted((ROOT / "descriptions" / "dala" / "missions").glob("*.yaml")):
        m = read_mission(path)
        assert m.world is not None and m.world.is_file(), path
