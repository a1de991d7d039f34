"""Timed execution (simulated and real time) and discrete-time exploration of timed BIP2 models."""
import io
import time
from pathlib import Path

import pytest

from runtime.bip2 import parse_file, parse_text
from runtime.cli import main
from runtime.engine import first
from runtime.engine.timed import TimedEngine, format_time
from runtime.engine.timed_run import run_timed
from runtime.explore.timed import explore_timed

TIMED = Path(__file__).parent / "fixtures" / "bip" / "timed"


def parse_time(text: str) -> int:
    """The nanoseconds of a time printed like 1s417ms203us."""
    import re
    sizes = {"s": 10**9, "ms": 10**6, "us": 10**3, "ns": 1}
    return sum(int(n) * sizes[u] for n, u in re.findall(r"(\d+)(ms|us|ns|s)", text))


def naps():
    return {"nap": lambda ms: time.sleep(ms / 1000)}


def chosen(text: str) -> list[str]:
    return [line.split("] ", 1)[1] for line in text.splitlines() if line.startswith("-> choose")]


def run(model: str, root: str = "Top()", real_time: bool = False, limit=None):
    te = TimedEngine(parse_file(TIMED / f"{model}.bip"), root, naps())
    out = io.StringIO()
    summary = run_timed(te, first, limit, out, real_time=real_time)
    return summary, out.getvalue()


def test_interactions_wait_for_their_clocks():
    summary, text = run("heartbeat")
    assert chosen(text) == [
        "p: s.beat l.beat at global time 10ms",   # eager: as soon as t == 10
        "l.note at global time 11ms",             # delayable in [1 ms, 3 ms] after the beat: its earliest instant
        "p: s.beat l.beat at global time 20ms",
        "l.note at global time 21ms",
        "p: s.beat l.beat at global time 30ms",
        "l.note at global time 31ms",
        "s.stop at global time 35ms",
    ]
    assert "  [0] l.note [ 11ms, 13ms ]" in text  # the window the invariant and the guard allow
    assert (summary.outcome, summary.time, summary.steps) == ("deadlock", 35 * 10**6, 7)


def test_rates_and_resume():
    summary, text = run("resumer")
    # the clock 'slow' runs at half speed: slow >= 2 after 4 s; the invariant x <= 4 at BUSY ends the window at 6 s
    assert chosen(text) == ["w.start at global time 2s", "w.hand at global time 4s"]
    assert "[0] w.hand [ 4s, 6s ]" in text
    assert summary.outcome == "deadlock"


def test_time_lock_is_reported_where_time_stops():
    summary, text = run("locked")
    assert text.splitlines()[0] == "state #0 and global time 0: time-lock at 3ms!"
    assert (summary.outcome, summary.message) == ("time-lock", "at 3ms")


def test_strict_bound_time_lock_is_right_before():
    src = (TIMED / "locked.bip").read_text().replace("(c <= 3)", "(c < 3)")
    te = TimedEngine(parse_text(src, "locked.bip"), "Top()")
    out = io.StringIO()
    summary = run_timed(te, first, None, out)
    assert "time-lock right before 3ms!" in out.getvalue()
    assert summary.outcome == "time-lock"


def test_simulated_time_ignores_how_long_actions_take():
    summary, text = run("overrun", "Slow()")
    assert chosen(text) == ["j.go at global time 5ms", "j.done at global time 5ms"]
    assert summary.outcome == "deadlock"


def test_real_time_waits_and_keeps_the_order():
    start = time.monotonic()
    summary, text = run("overrun", "Top()", real_time=True)
    assert time.monotonic() - start >= 0.005  # it waited for x >= 5 ms for real
    assert [c.split(" at ")[0] for c in chosen(text)] == ["j.go", "j.done"]
    assert summary.outcome == "deadlock"


def test_real_time_overrun_is_a_violation():
    summary, text = run("overrun", "Slow()", real_time=True)
    assert summary.outcome == "violation"
    assert "state #1 and global time" in text and "violation of the following timing constraints:" in text
    # x was reset when 'go' fired (at 5 ms or later on a busy machine): resume (x <= 200) ends 200 ms after
    started = chosen(text)[0].split(" at global time ")[1]
    assert f"  j resume [ -INFTY, {format_time(parse_time(started) + 200 * 10**6)} ]" in text
    assert summary.time >= 405 * 10**6


def test_data_invariant_violation_stops_the_run():
    src = (TIMED / "overrun.bip").read_text().replace("(runs <= 1)", "(runs < 1)")
    te = TimedEngine(parse_text(src, "overrun.bip"), "Top()", naps())
    out = io.StringIO()
    summary = run_timed(te, first, None, out)
    assert (summary.outcome, summary.message) == ("invariant", "j.sane")
    assert "state #1 and global time 5ms: invariant violated: j.sane" in out.getvalue()


@pytest.mark.parametrize("ns, text", [(0, "0"), (10**9, "1s"), (1_417_203_000, "1s417ms203us"), (61 * 10**9, "1min1s"),
                                      (None, "+INFTY")])
def test_times_print_as_the_reference_engine_prints_them(ns, text):
    assert format_time(ns) == text


def test_cli_exit_status_follows_the_outcome(capsys):
    model = str(TIMED / "overrun.bip")
    assert main(["run", model, "--root", "Slow()", "--real-time", "--quiet", "--externs", __file__]) == 4
    assert "timing constraint violated" in capsys.readouterr().err
    assert main(["run", str(TIMED / "locked.bip"), "--root", "Top()", "--quiet"]) == 0
    assert "time-lock (at 3ms)" in capsys.readouterr().out


def nap(ms):  # the extern the CLI test binds through --externs this file
    time.sleep(ms / 1000)


# ------------------------------------------------------------------------------------------------ exploration
def explore(model: str, tick: int, root: str = "Top()", max_states: int = 100_000):
    return explore_timed(TimedEngine(parse_file(TIMED / f"{model}.bip"), root, naps()), tick, max_states)


def test_exploration_finds_the_end_and_no_time_lock():
    r = explore("heartbeat", 10**6)
    assert r.complete and not r.time_locks and not r.uncapped
    (end,) = r.deadlocks
    trace = r.traces[end]
    assert trace.count("p") == 3 and trace.count("l.note") == 3 and "s.stop" in trace


def test_exploration_finds_the_time_lock_with_its_ticks():
    r = explore("locked", 10**6)
    assert r.complete and not r.deadlocks
    (lock,) = r.time_locks
    assert r.traces[lock] == ["tick", "tick", "tick"]


def test_a_coarse_tick_can_miss_an_instant():
    # heartbeat's beat needs t == 10 ms exactly: with 3 ms ticks time jumps over it and nothing can happen
    r = explore("heartbeat", 3 * 10**6)
    assert r.time_locks or r.deadlocks
    assert not any("s.stop" in r.traces[s] for s in r.deadlocks)


def test_clocks_compared_with_data_are_not_capped():
    src = (TIMED / "heartbeat.bip").read_text().replace("t >= 5", "t >= count")
    r = explore_timed(TimedEngine(parse_text(src, "heartbeat.bip"), "Top()"), 10**6, 2000)
    assert r.uncapped == ["s.t"]
    assert not r.complete and r.states == 2000  # t grows for ever in DONE: only the limit stops it


def test_explore_cli(capsys):
    assert main(["explore", str(TIMED / "locked.bip"), "--root", "Top()", "--tick", "1ms"]) == 4
    assert "time-lock at state 3: tick tick tick" in capsys.readouterr().out
    assert main(["explore", str(TIMED / "locked.bip"), "--root", "Top()", "--tick", "fast"]) == 1
    assert "a tick is a positive duration" in capsys.readouterr().err


def test_violation_names_the_deadline_that_was_passed():
    # the worker's action sleeps past the moment the eager watcher had to fire
    src = """package late
  extern function nap(int)
  port type Port()
  atom type Worker()
    port Port work()
    place A, B
    initial to A
    on work from A to B do { nap(300); }
  end
  atom type Watcher()
    clock w unit millisecond
    port Port ring()
    place A, B
    initial to A do { w = 0; }
    on ring from A to B provided (w >= 100) eager
  end
  compound type Top()
    component Worker k()
    component Watcher v()
  end
end
"""
    te = TimedEngine(parse_text(src, "late.bip"), "Top()", naps())
    out = io.StringIO()
    summary = run_timed(te, first, None, out, real_time=True)
    assert summary.outcome == "violation"
    assert "  v.ring [ 100ms, +INFTY ] eager" in out.getvalue()


def test_eager_after_a_strict_bound_locks_time_at_the_bound():
    # an eager transition stops time at the start of its window even when the window excludes it: x > 3
    # cannot fire at 3 ms, and time cannot pass it: the reference engine says "time-lock at 3ms"
    src = (TIMED / "locked.bip").read_text().replace("    invariant wait at SHUT provided (c <= 3)\n", "")
    src = src.replace("provided (c > 3)", "provided (c > 3) eager")
    te = TimedEngine(parse_text(src, "locked.bip"), "Top()")
    out = io.StringIO()
    assert run_timed(te, first, None, out).outcome == "time-lock"
    assert out.getvalue().startswith("state #0 and global time 0: time-lock at 3ms!")


def test_cli_trace_records_steps_with_their_time(tmp_path, capsys):
    import json
    trace = tmp_path / "t.jsonl"
    assert main(["run", str(TIMED / "resumer.bip"), "--root", "Top()", "--quiet", "--trace", str(trace)]) == 0
    lines = [json.loads(line) for line in trace.read_text().splitlines()]
    assert [(x["interaction"], x["time_ns"]) for x in lines[:-1]] == [("w.start", 2 * 10**9), ("w.hand", 4 * 10**9)]
    assert lines[-1] == {"end": "deadlock", "steps": 2, "time_ns": 4 * 10**9, "message": ""}
    assert main(["run", str(TIMED / "resumer.bip"), "--root", "Top()", "--trace", str(tmp_path / "no" / "t")]) == 1
    assert "cannot write trace" in capsys.readouterr().err


def test_explore_cli_warns_about_uncapped_clocks(tmp_path, capsys):
    model = tmp_path / "heartbeat.bip"
    model.write_text((TIMED / "heartbeat.bip").read_text().replace("t >= 5", "t >= count"))
    assert main(["explore", str(model), "--root", "Top()", "--max-states", "500"]) == 5
    captured = capsys.readouterr()
    assert "500 states" in captured.out and "stopped at the state limit" in captured.out
    assert "warning: clock s.t is compared with a non-constant" in captured.err


def test_random_instants_stay_in_their_windows():
    import random
    from runtime.engine.timed_run import Planner
    te = TimedEngine(parse_file(TIMED / "resumer.bip"), "Top()")
    hands = set()
    for seed in range(20):
        out = io.StringIO()
        summary = run_timed(te, first, None, out, planner=Planner(random.Random(seed)))
        go, hand = chosen(out.getvalue())
        assert go.endswith("at global time 2s")  # a single instant: no choice
        t = parse_time(hand.split(" at global time ")[1])
        assert 4 * 10**9 <= t <= 6 * 10**9       # anywhere in [ 4s, 6s ]
        hands.add(t)
        assert summary.outcome == "deadlock"
    assert len(hands) > 10


def test_random_resume_can_reach_the_deadlock_the_earliest_instant_avoids():
    # 'go' resumes somewhere in [0, 200 ms] after its start; 'done' needs x <= 1000, always true: compare with a
    # tighter bound where a late completion leaves 'done' disabled for ever
    import random
    from runtime.engine.timed_run import Planner
    src = (TIMED / "overrun.bip").read_text().replace("(x <= 1000)", "(x <= 100)")
    te = TimedEngine(parse_text(src, "overrun.bip"), "Top()", naps())
    ends = set()
    for seed in range(12):
        out = io.StringIO()
        summary = run_timed(te, first, None, out, planner=Planner(random.Random(seed)))
        ends.add(summary.steps)
    assert ends == {1, 2}
    out = io.StringIO()
    assert run_timed(te, first, None, out).steps == 2


def test_cli_random_time_is_seeded(capsys):
    args = ["run", str(TIMED / "resumer.bip"), "--root", "Top()", "--random-time", "--seed", "3"]
    assert main(args) == 0
    once = capsys.readouterr().out
    assert main(args) == 0
    assert capsys.readouterr().out == once
    hand = parse_time(chosen(once)[1].split(" at global time ")[1])
    assert 4 * 10**9 < hand <= 6 * 10**9  # drawn in the window, not its earliest instant
