"""Bad platform files: each error names file:line:column and what was expected, exits 1, and writes nothing."""
from __future__ import annotations

import pytest

from genom2bip.cli import main
from platformkit import FIXTURES, platform_file, verify

ANOMALY = FIXTURES / "Anomaly.gen"

BAD = [
    ("cores: 0\n", 1, 8, "cores is '0'; expected a whole number from 1 to 256"),
    ("cores: 257\n", 1, 8, "cores is '257'; expected a whole number from 1 to 256"),
    ("cores: two\n", 1, 8, "cores is 'two'; expected a whole number from 1 to 256"),
    ("policy: edf\n", 1, 1, "the platform has no 'cores'"),
    ("cores: 1\npolicy: rms\n", 2, 9, "policy is 'rms'; expected edf or fixed-priority"),
    ("cores: 1\ncore: 2\n", 2, 1, "unknown key 'core'"),
    ("cores: 1\nbest: -1 ms\n", 2, 7, "best is '-1 ms'; expected a duration"),
    ("cores: 1\nexecution:\n  Anomaly.mid.mid_stp: [1 ms, 4 ms]\n", 3, 3, "Anomaly.mid runs no codel 'mid_stp'"),
    ("cores: 1\nexecution:\n  Anomaly.middle.mid_step: 1 ms\n", 3, 3,
     "component Anomaly has no task or service 'middle'"),
    ("cores: 1\nexecution:\n  Anomly.mid.mid_step: 1 ms\n", 3, 3, "unknown component 'Anomly'"),
    ("cores: 1\nreleases: one by one\n", 2, 11, "releases is 'one by one'; expected together or one-by-one"),
    ("cores: 1\nreleases: [together]\n", 2, 11, "releases must be a single value"),
    ("cores: 1\nexecution:\n  mid_step: 1 ms\n", 3, 3, "'mid_step' is not Component.Owner.codel"),
    ("cores: 1\nexecution:\n  Anomaly.mid.low_step: 1 ms\n", 3, 3, "Anomaly.mid runs no codel 'low_step'"),
    ("cores: 1\nexecution:\n  Anomaly.mid.mid_step: [4 ms, 1 ms]\n", 3, 25,
     "execution of Anomaly.mid.mid_step: the best case 4 ms is longer than the worst 1 ms"),
    ("cores: 1\nexecution:\n  Anomaly.mid.mid_step: [1 ms, soon]\n", 3, 32,
     "execution of Anomaly.mid.mid_step is 'soon'; expected a duration"),
    ("cores: 1\nexecution:\n  Anomaly.mid.mid_step: [1 ms, 2 ms, 3 ms]\n", 3, 25,
     "execution of Anomaly.mid.mid_step must be [best, worst] or one duration"),
    ("cores: 1\nexecution:\n  Anomaly.mid.mid_step: 1 ms\n  Anomaly.mid.mid_step: 2 ms\n", 4, 3,
     "execution: key 'Anomaly.mid.mid_step' given twice"),
    ("cores: 1\ntasks:\n  Anomaly.hgh:\n    priority: 1\n", 3, 3, "component Anomaly has no task 'hgh'"),
    ("cores: 1\ntasks:\n  Anomaly.high:\n    prio: 1\n", 4, 5, "task Anomaly.high: unknown key 'prio'"),
    ("cores: 1\ntasks:\n  Anomaly.high:\n    priority: 256\n", 4, 15,
     "priority of Anomaly.high is '256'; expected 0 (highest) to 255"),
    ("cores: 1\ntasks:\n  Anomaly.high:\n    delay: [5 ms, 2 ms]\n", 4, 12,
     "delay of Anomaly.high: the best case 5 ms is longer than the worst 2 ms"),
    ("", 1, 1, "a platform file is a mapping with at least 'cores'"),
    ("cores: [1\n", 2, 1, "not valid YAML: expected ',' or ']', but got '<stream end>'"),
]


@pytest.mark.parametrize("text,line,column,message", BAD, ids=[b[3][:40] for b in BAD])
def test_a_bad_platform_file_is_located_and_verify_exits_1(tmp_path, capsys, text, line, column, message):
    path = platform_file(tmp_path, text)
    code, out, err = verify(capsys, ANOMALY, "--timed", "--schedulability", "--platform", path)
    assert code == 1
    assert f"{path}:{line}:{column}: error: {message}" in err, err
    assert "overrun" not in out  # nothing was checked


WRITES_NOTHING = BAD[:3] + BAD[7:9] + [b for b in BAD if b[3].startswith("releases is")]


@pytest.mark.parametrize("text,line,column,message", WRITES_NOTHING, ids=[b[3][:40] for b in WRITES_NOTHING])
def test_a_bad_platform_file_writes_nothing(tmp_path, capsys, text, line, column, message):
    path = platform_file(tmp_path, text)
    out_dir = tmp_path / "gen"
    out_dir.mkdir()
    (out_dir / "kept.txt").write_text("before")
    code = main([str(ANOMALY), "--timed", "--platform", str(path), "-o", str(out_dir)])
    _, err = capsys.readouterr()
    assert code == 1
    assert f"{path}:{line}:{column}: error: {message}" in err
    assert sorted(p.name for p in out_dir.iterdir()) == ["kept.txt"]
    assert (out_dir / "kept.txt").read_text() == "before"
    assert path.read_text() == text


def test_every_error_of_a_file_is_reported_at_once(tmp_path, capsys):
    path = platform_file(tmp_path, "cores: 0\npolicy: rms\nexecution:\n  Anomaly.mid.mid_stp: 1 ms\n")
    code, _, err = verify(capsys, ANOMALY, "--timed", "--platform", path)
    assert code == 1
    for where in ("1:8", "2:9", "4:3"):
        assert f"{path}:{where}: error: " in err, err


def test_a_missing_platform_file_is_bad_input(tmp_path, capsys):
    code, _, err = verify(capsys, ANOMALY, "--timed", "--platform", tmp_path / "nowhere.yaml")
    assert code == 1 and f"{tmp_path / 'nowhere.yaml'}: no such platform file" in err


def test_platform_needs_timed(tmp_path, capsys):
    code, _, err = verify(capsys, ANOMALY, "--platform", platform_file(tmp_path, "cores: 1\n"))
    assert code == 2 and "--platform needs --timed" in err


# --------------------------------------------------------------------------- bad client missions

ZENO = FIXTURES / "Zeno.gen"


@pytest.mark.parametrize("text,line,column,message", [
    ("steps:\n  - send: Zeno.C\n    expect: ok\n", 2, 5, "client: no service Zeno.C in the model"),
    ("steps:\n  - send: Zeno.A\n    after: soon\n", 3, 12,
     "after: a number of seconds (0 or more) expected, got 'soon'"),
    ("steps:\n  - send: Zeno.A\n    until: begun\n", 3, 12,
     "until: one of queued, started, final expected, got 'begun'"),
])
def test_a_bad_client_mission_is_located(tmp_path, capsys, text, line, column, message):
    path = platform_file(tmp_path, text, "mission.yaml")
    code, out, err = verify(capsys, ZENO, "--timed", "--schedulability", "--client", path)
    assert code == 1
    assert f"{path}:{line}:{column}: error: {message}" in err, err
    assert "overrun" not in out


def test_a_missing_client_mission_is_bad_input(tmp_path, capsys):
    code, _, err = verify(capsys, ZENO, "--timed", "--client", tmp_path / "nowhere.yaml")
    assert code == 1 and f"{tmp_path / 'nowhere.yaml'}: no such mission file" in err


def test_client_needs_timed(capsys):
    code, _, err = verify(capsys, ZENO, "--client", FIXTURES / "a_then_b.yaml")
    assert code == 2 and "--client needs --timed" in err
