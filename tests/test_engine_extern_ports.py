"""Extern ports run: pushed events, their queues, the three policies, the events file, and exploration."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from runtime.bip2 import parse_file, parse_text
from runtime.engine import Engine, EngineError
from runtime.engine.policies import make_policy
from runtime.explore import StateSpace

ROOT = Path(__file__).resolve().parents[1]
FIXTURE = ROOT / "tests" / "fixtures" / "engine" / "ExternPorts.bip"
STRICT = "port c.strict received an event while no transition can take it and its event policy is 'error'"


def run(*events, limit=50):
    """Run the fixture with the first-enabled policy after pushing ``events`` (port, values, after)."""
    engine = Engine(parse_file(FIXTURE), "System()")
    for port, values, after in events:
        engine.extern.push(port, *values, after=after)
    summary = engine.run(make_policy("first", None, engine.format_state), limit)
    return engine, summary, engine.describe_state(summary.state)["c"]


def test_the_guard_reads_the_state_before_the_event_and_a_remembered_event_waits():
    engine, summary, c = run(("c.add", [3], 0), ("c.add", [7], 0), ("c.add", [1], 0))
    # 7 is taken although 7 >= 5: the guard read seen = 3; then 1 cannot be taken (seen = 7) and is kept
    assert (summary.steps, summary.outcome) == (3, "deadlock")
    assert c == {"places": ["DONE"], "data": {"total": 10, "seen": 7}}
    assert engine.extern.pending() == {"c.add": 1}


def test_an_ignored_event_is_dropped_and_a_later_one_is_taken():
    _, summary, c = run(("c.add", [3], 0), ("c.add", [7], 0), ("c.noise", [100], 0), ("c.noise", [5], 3))
    assert (summary.steps, c["data"]) == (4, {"total": 15, "seen": 5})  # 100 came in RUN: dropped


def test_an_event_that_a_port_with_policy_error_cannot_take_ends_the_run():
    _, summary, c = run(("c.add", [3], 0), ("c.add", [7], 0), ("c.strict", [1], 3))
    assert (summary.steps, summary.outcome) == (3, "event")
    assert STRICT in summary.message and c["places"] == ["DONE"]
    assert summary.line() == f"3 steps, unexpected event: {summary.message}"


def test_no_deadlock_while_events_are_still_to_come():
    engine, summary, c = run(("c.add", [3], 0), ("c.add", [7], 0), ("c.bell", [], 10))
    assert (summary.steps, summary.outcome, c["places"], c["data"]) == (4, "deadlock", ["RUN"], {"total": 0, "seen": 0})
    assert engine.extern.next_arrival() is None


def test_an_extern_port_fires_only_on_an_event():
    engine, summary, _ = run()
    assert (summary.steps, summary.outcome) == (0, "deadlock")
    assert {i.label for i in engine.enabled(engine.initial_state())} == {"c.add", "c.strict"}  # could take one


@pytest.mark.parametrize("port, values, message", [
    ("c.nope", [1], "no extern port 'c.nope' (extern ports: c.add, c.noise, c.strict, c.bell)"),
    ("c.add", [1, 2], "extern port c.add carries 1 value(s) (x), the event has 2"),
    ("c.add", ["3"], "event for extern port c.add: x is int, got '3'"),
    ("c.bell", [True], "extern port c.bell carries 0 value(s) (none), the event has 1"),
])
def test_a_bad_event_is_refused_with_its_reason(port, values, message):
    engine = Engine(parse_file(FIXTURE), "System()")
    with pytest.raises(EngineError) as err:
        engine.extern.push(port, *values)
    assert str(err.value) == message
    assert engine.extern.next_arrival() is None  # nothing queued


def cli(*args):
    return subprocess.run([sys.executable, "-m", "runtime", "run", str(FIXTURE), *args], capture_output=True,
                          text=True, cwd=ROOT, env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})


def test_run_takes_events_from_a_file(tmp_path):
    events = tmp_path / "events.jsonl"
    events.write_text('# one event a line\n{"port": "c.add", "values": [3]}\n{"port": "c.add", "values": [7]}\n\n'
                      '{"port": "c.strict", "values": [1], "after": 3}\n')
    r = cli("--events", str(events), "--policy", "first")
    assert r.returncode == 4, r.stderr
    assert "c.add  c.add(x=7)" in r.stdout
    assert r.stdout.splitlines()[-1].startswith("3 steps, unexpected event: " + STRICT)
    assert f"ExternPorts.bip: ERROR: {STRICT}" in r.stderr


@pytest.mark.parametrize("line, message", [
    ('{"port": "c.add", "values": 3}', '"values" must be a list and "after" a step count >= 0'),
    ('{"values": [3]}', 'expected an object with "port"'),
    ('{"port": "c.add", "values": [3], "after": -1}', '"after" a step count >= 0'),
    ("not json", "Expecting value"),
])
def test_a_bad_events_file_is_located(tmp_path, line, message):
    events = tmp_path / "events.jsonl"
    events.write_text('{"port": "c.add", "values": [3]}\n' + line + "\n")
    r = cli("--events", str(events))
    assert r.returncode == 1 and r.stdout == ""
    assert f"{events}:2: bad event: " in r.stderr and message in r.stderr, r.stderr


def test_exploration_takes_a_dataless_extern_port_as_an_environment_choice():
    text = FIXTURE.read_text()
    with pytest.raises(EngineError, match="extern port c.add carries data .x.: exploration takes an extern port "
                                          "as an environment choice"):
        StateSpace(parse_text(text, "ExternPorts.bip"), "System()")
    bare = parse_text(text.replace("    extern port IntPort add(seen) as \"Adder\" remember\n", "")
                      .replace("    extern port IntPort noise(seen) ignore\n", "")
                      .replace("    extern port IntPort strict(seen) error\n", "")
                      .replace("    on add from RUN to RUN provided (seen < 5) do { total = total + seen; }\n",
                               "    internal from RUN to DONE provided (total == 0) do { total = 10; }\n")
                      .replace("    on noise from DONE to DONE do { total = total + seen; }\n", "")
                      .replace("    on strict from RUN to RUN do { total = total - 1; }\n", ""), "ExternPorts.bip")
    space = StateSpace(bare, "System()")
    labels = set()
    for state in space.engine.successors(space.engine.initial_state()):
        labels.add(state[0].label)
    assert labels == {"c.bell"}  # DONE after the internal step: only the environment's bell can come


def test_a_timed_run_refuses_extern_ports():
    from runtime.engine.timed import TimedEngine

    text = FIXTURE.read_text().replace("    data int seen\n", "    data int seen\n    clock t unit millisecond\n")
    with pytest.raises(EngineError, match="extern port c.add: timed runs do not take events pushed from outside yet"):
        TimedEngine(parse_text(text, "ExternPorts.bip"), "System()")
