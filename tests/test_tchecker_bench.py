"""bench/tchecker_bench.py reads our command's answers: a limit reached is "unknown" with how far the search got,
an exit status without an answer an error, never the other way round (tck-reach itself is not needed here)."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
import tchecker_bench as tb  # noqa: E402

FIXTURES = ROOT / "tests" / "fixtures" / "tchecker"


def output(verdict: str, stored: str = "81,035", kept: str = "25,080", transitions: str = "132,592") -> str:
    """What ``python -m runtime reach`` prints (runtime/tchecker/cli.py), with the figures given."""
    return (f"labels: cs1,cs2\nverdict: {verdict}\nstored states: {stored} ({kept} not covered at the end, "
            f"{kept} discrete)\nvisited transitions: {transitions}\ntime: 60.012 s\n"
            "memory: 300.5 MiB peak (the search holds 147.64 MiB)\n")


def test_a_time_limit_reached_is_unknown_with_how_far_the_search_got():
    mine = tb.read_ours(5, output("unknown (stopped at the time limit)"), "", 61.0)
    assert (mine.verdict, mine.note, mine.stored, mine.states, mine.transitions) == \
        ("unknown", "time limit", 81_035, 25_080, 132_592)
    assert mine.seconds == 60.012 and mine.wall == 61.0
    theirs = tb.Run("unreachable", 25_080, 132_592, 1.0, 28.0)
    cell = tb.verdict_cell(theirs, theirs, mine)
    assert cell == ("unknown (time limit: 81,035 states stored, 132,592 transitions in 60 s; "
                    "tck-reach: unreachable)")


def test_a_state_limit_is_said_as_such():
    mine = tb.read_ours(5, output("unknown (stopped at the state limit)"), "", 1.0)
    assert (mine.verdict, mine.note) == ("unknown", "state limit")


@pytest.mark.parametrize("code,verdict", [(0, "unreachable (on the 1/2 time grid: the model has strict clock "
                                                  "constraints)"), (4, "reachable")])
def test_answers_are_read_with_their_figures(code, verdict):
    mine = tb.read_ours(code, output(verdict, "4,486", "2,378", "9,312"), "", 0.5)
    assert (mine.verdict, mine.stored, mine.states, mine.transitions, mine.rss_mib, mine.note) == \
        (verdict.split()[0], 4_486, 2_378, 9_312, 300.5, "")
    assert tb.verdict_cell(mine, mine, mine) == mine.verdict


@pytest.mark.parametrize("code", [1, 2, 3, 130])
def test_an_exit_status_without_an_answer_is_an_error_with_its_first_line(code):
    err = "fischer.tck:3:7: error: strict clock constraint\n  x < 2\n      ^\n"
    mine = tb.read_ours(code, "", err, 0.2)
    assert mine.verdict == "error" and mine.states is None
    assert mine.note == f"exit status {code}: fischer.tck:3:7: error: strict clock constraint"
    theirs = tb.Run("reachable", 5, 4, 0.0, 8.0)
    assert tb.verdict_cell(theirs, theirs, mine) == f"error (ours: {mine.note}); tck-reach: reachable"


def test_an_internal_error_that_printed_a_verdict_is_still_an_error():
    # exit status 3 is an internal error, whatever was printed before it
    assert tb.read_ours(3, output("unreachable"), "internal error: ...", 0.2).verdict == "error"


def test_two_answers_that_differ_are_a_disagreement():
    yes, no = tb.Run("reachable", 5, 4, 0.0, 8.0), tb.Run("unreachable", 5, 4, 0.0, 8.0)
    assert tb.verdict_cell(yes, yes, no) == "DISAGREE: reachable/reachable/unreachable"
    stopped = tb.Run("unknown", None, None, 60.0, None, "time limit")
    assert tb.verdict_cell(stopped, yes, yes) == "reachable"  # tck-reach -a reach stopped: no disagreement


def test_our_command_s_answer_is_what_the_bench_reads(capsys):
    # the output read above is the command's own: run it on a fixture, once complete and once stopped
    from runtime.cli import main
    from runtime.tchecker.reach import reach

    code = main(["reach", str(FIXTURES / "fischer2.tck"), "--labels", "cs1,cs2", "--grid", "2", "--no-trace"])
    out = capsys.readouterr().out
    mine = tb.read_ours(code, out, "", 0.1)
    direct = reach(FIXTURES / "fischer2.tck", ["cs1", "cs2"], 2, want_trace=False)
    assert (mine.verdict, mine.states, mine.stored, mine.transitions) == \
        ("unreachable", direct.kept, direct.states, direct.transitions)
    code = main(["reach", str(FIXTURES / "fischer2.tck"), "--grid", "2", "--max-states", "3", "--no-trace"])
    mine = tb.read_ours(code, capsys.readouterr().out, "", 0.1)
    assert (mine.verdict, mine.note) == ("unknown", "state limit") and mine.stored >= 3


def test_best_of_several_runs_only_where_the_first_was_quick():
    times = iter([0.5, 0.2, 0.4, 9.0])
    calls = []

    def run():
        calls.append(1)
        return tb.Run("unreachable", 10, 20, next(times), 44.0)

    assert tb.best(run, 3).seconds == 0.2 and len(calls) == 3
    assert tb.best(run, 3).seconds == 9.0 and len(calls) == 4  # a slow first run is not repeated
    stopped = tb.Run("unknown", None, None, 0.1, None, "time limit")
    assert tb.best(lambda: stopped, 3) is stopped


def test_a_time_ratio_against_a_run_stopped_at_the_limit_is_a_bound():
    done, stopped = tb.Run("unreachable", 5, 4, 24.0, 8.0), tb.Run("unknown", None, None, 60.0, None, "time limit")
    assert tb.time_bound(done, stopped) + tb.ratio(done.seconds, stopped.seconds) == "<0.4×"
    assert tb.time_bound(stopped, done) == ">" and tb.time_bound(done, done) == ""
