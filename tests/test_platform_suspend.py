"""A task's self-suspension (``suspend`` in the platform file): what it changes, and its bad values located."""
from __future__ import annotations

import pytest

from genom2bip.cli import main
from platformkit import FIXTURES, platform_file, response_ms, verdicts, verify

PAIR = FIXTURES / "Pair.gen"
TWO_CORES = "cores: 2\npolicy: edf\n"


def _pair(capsys, tmp_path, tasks: str) -> tuple[int, str]:
    path = platform_file(tmp_path, TWO_CORES + tasks)
    code, out, err = verify(capsys, PAIR, "--timed", "--platform", path, "--response-times")
    assert "error" not in err, err
    return code, out


def test_a_suspension_delays_the_task_after_each_release(tmp_path, capsys):
    """Pair on two cores: slow's 6 ms codel starts 3 ms after its release, so it ends at 9 ms (6 without)."""
    code, out = _pair(capsys, tmp_path, "")
    assert response_ms(out) == {"Pair.fast": 6, "Pair.slow": 6}
    code, out = _pair(capsys, tmp_path, "tasks:\n  Pair.slow:\n    suspend: 3 ms\n")
    assert code == 0, out
    assert response_ms(out) == {"Pair.fast": 6, "Pair.slow": 9}
    assert "Pair.slow:back" in out  # the trace shows where the suspension ends


def test_a_suspension_interval_takes_its_longest_end(tmp_path, capsys):
    code, out = _pair(capsys, tmp_path, "tasks:\n  Pair.slow:\n    suspend: [2 ms, 4 ms]\n")
    assert code == 0, out
    assert response_ms(out)["Pair.slow"] == 10


def test_a_suspension_that_leaves_too_little_of_the_period_overruns(tmp_path, capsys):
    code, out = _pair(capsys, tmp_path, "tasks:\n  Pair.slow:\n    suspend: 5 ms\n")
    assert code == 4
    assert verdicts(out) == {"Pair.fast": "none", "Pair.slow": "overrun"}


def test_a_suspended_task_is_not_there_to_take_the_core(tmp_path, capsys):
    """One core, fixed priority: fast (priority 0) keeps its period, unless it suspends after its release: slow
    then takes the free core at 0 and keeps it 6 ms, and fast, back at 2 ms, overruns."""
    fixed = "cores: 1\npolicy: fixed-priority\n"
    code, out, _ = verify(capsys, PAIR, "--timed", "--platform", platform_file(tmp_path, fixed))
    assert verdicts(out) == {"Pair.fast": "none", "Pair.slow": "overrun"}
    path = platform_file(tmp_path, fixed + "tasks:\n  Pair.fast:\n    suspend: 2 ms\n")
    code, out, _ = verify(capsys, PAIR, "--timed", "--platform", path)
    assert code == 4
    assert verdicts(out)["Pair.fast"] == "overrun"


@pytest.mark.parametrize("after,fast", [("release", 12), ("grant", 14)])
def test_a_suspension_after_the_grant_keeps_the_core_idle(tmp_path, capsys, after, fast):
    """One core, EDF, fast suspends 2 ms.  After its release, slow takes the core meanwhile: fast runs 6..12.
    After its grant, fast may hold the core idle 0..2, or wait for slow and then suspend 6..8, running 8..14."""
    path = platform_file(tmp_path, f"cores: 1\npolicy: edf\ntasks:\n  Pair.fast:\n"
                                   f"    suspend: {{for: 2 ms, after: {after}}}\n")
    code, out, _ = verify(capsys, PAIR, "--timed", "--platform", path, "--response-times")
    assert code == 4
    assert response_ms(out)["Pair.fast"] == fast


def test_the_bip_text_shows_the_suspension(tmp_path, capsys):
    path = platform_file(tmp_path, TWO_CORES + "tasks:\n  Pair.slow:\n    suspend: 3 ms\n")
    out_dir = tmp_path / "gen"
    assert main([str(PAIR), "--timed", "--platform", str(path), "-o", str(out_dir)]) == 0
    capsys.readouterr()
    text = "\n".join(p.read_text() for p in out_dir.rglob("*.bip"))
    assert "atom type SuspendingCoreScheduler" in text
    assert "SUSPENDED" in text and "port Port back()" in text


APERIODIC = """component Idle {
  version "1.0";
  lang "c";
  task worker {
    codel <start> step() yield pause::start wcet 1 ms;
  };
};
"""

BAD = [
    ("tasks:\n  Pair.slow:\n    suspend: [5 ms, 2 ms]\n", 3, 14,
     "suspend of Pair.slow: the best case 5 ms is longer than the worst 2 ms"),
    ("tasks:\n  Pair.slow:\n    suspend: soon\n", 3, 14, "suspend of Pair.slow is 'soon'; expected a duration"),
    ("tasks:\n  Pair.slow:\n    suspend: 10 ms\n", 3, 14,
     "suspend of Pair.slow: 10 ms is not shorter than its period, 10 ms"),
    ("tasks:\n  Pair.slow:\n    suspend: [1 ms, 12 ms]\n", 3, 14,
     "suspend of Pair.slow: 12 ms is not shorter than its period, 10 ms"),
    ("tasks:\n  Pair.slow:\n    suspnd: 1 ms\n", 3, 5, "task Pair.slow: unknown key 'suspnd'"),
    ("tasks:\n  Pair.slow:\n    suspend: {for: 1 ms, after: start}\n", 3, 33,
     "suspend of Pair.slow: after is 'start'; expected release or grant"),
    ("tasks:\n  Pair.slow:\n    suspend: {fr: 1 ms}\n", 3, 15, "suspend of Pair.slow: unknown key 'fr'"),
    ("tasks:\n  Pair.slow:\n    suspend: {after: grant}\n", 3, 14, "suspend of Pair.slow has no 'for'"),
    ("tasks:\n  Pair.slow:\n    suspend: {for: 20 ms}\n", 3, 20,
     "suspend of Pair.slow: 20 ms is not shorter than its period, 10 ms"),
]


@pytest.mark.parametrize("text,line,column,message", BAD, ids=[b[3][:40] for b in BAD])
def test_a_bad_suspension_is_located_and_nothing_is_written(tmp_path, capsys, text, line, column, message):
    path = platform_file(tmp_path, TWO_CORES + text)
    line += 2  # the two lines of TWO_CORES
    code, out, err = verify(capsys, PAIR, "--timed", "--platform", path)
    assert code == 1
    assert f"{path}:{line}:{column}: error: {message}" in err, err
    assert "overrun" not in out
    out_dir = tmp_path / "gen"
    out_dir.mkdir()
    (out_dir / "kept.txt").write_text("before")
    assert main([str(PAIR), "--timed", "--platform", str(path), "-o", str(out_dir)]) == 1
    assert f"{path}:{line}:{column}: error: {message}" in capsys.readouterr().err
    assert sorted(p.name for p in out_dir.iterdir()) == ["kept.txt"]
    assert path.read_text() == TWO_CORES + text


def test_a_suspension_after_the_grant_needs_edf(tmp_path, capsys):
    path = platform_file(tmp_path, "cores: 1\npolicy: fixed-priority\ntasks:\n  Pair.slow:\n"
                                   "    suspend: {for: 1 ms, after: grant}\n")
    code, _, err = verify(capsys, PAIR, "--timed", "--platform", path)
    assert code == 1
    assert f"{path}:5:33: error: suspend of Pair.slow: after grant needs policy edf" in err, err


def test_a_task_without_period_cannot_suspend(tmp_path, capsys):
    gen = tmp_path / "Idle.gen"
    gen.write_text(APERIODIC)
    path = platform_file(tmp_path, "cores: 1\ntasks:\n  Idle.worker:\n    suspend: 1 ms\n")
    code, out, err = verify(capsys, gen, "--timed", "--platform", path)
    assert code == 1
    assert f"{path}:4:14: error: suspend of Idle.worker: task Idle.worker has no period" in err, err
