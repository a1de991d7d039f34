"""Symbolic time: the timed model, period overruns (Fig. 8), latency observers and their bad input."""
from __future__ import annotations

import re
import textwrap
from pathlib import Path

import pytest

from genom2bip.build.timed import TimeOptions
from genom2bip.cli import main
from genom2bip.generate import model_of
from genom2bip.observers import load_observers
from genom2bip.parser import parse_paths
from runtime.bip2 import parse_file
from runtime.diagnostics import Reporter
from tests.runkit import dala_without_wcets

ROOT = Path(__file__).resolve().parents[1]
CRUISE = ROOT / "tests/fixtures/timed/Cruise.gen"
OBSERVERS = ROOT / "tests/fixtures/timed/observers.yaml"
NDD = dala_without_wcets() / "NDD.gen"  # NDD as written before its WCETs were measured: each codel takes the default


def verify(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(["verify", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def trace_times(out: str) -> list[tuple[int, str]]:
    """(time in ms, label) of every step line of a printed timed trace."""
    return [(int(float(t)), label) for t, label in re.findall(r"^\s+\d+\s+\[([\d.]+) ms\] (\S+)", out, re.M)]


# --------------------------------------------------------------------------- schedulability


def test_a_task_whose_codels_exceed_its_period_overruns_with_a_timed_trace(capsys):
    code, out, err = verify(capsys, str(CRUISE), "--timed", "--schedulability")
    assert code == 4
    assert "period of Cruise.loop (10 ms): overrun reachable" in out
    steps = trace_times(out)
    # The trace replays the paper's argument: within one period of 10 ms, sense (4 ms) then a step of Track
    # (8 ms) run; a Track requested during a period starts only at the next opening.  The next release comes
    # while the step still runs: the timer keeps it (late) for when the period closes.
    opening = max(i for i, (_, label) in enumerate(steps) if label == "Cruise.loop:period")
    period_start = steps[opening][0]
    after = [label for _, label in steps[opening:]]
    assert after[1:] == ["Cruise.loop:exec_sense", "Cruise.Track:exec_track", "Cruise.loop:late"]
    assert steps[-2][0] - period_start == 4  # the step starts 4 ms into the period and takes 8 ms
    assert steps[-1][0] - period_start == 10  # the next release, on the grid of the period
    assert re.search(r"\[\d+ ms \.\. (\d+) ms\] time passes", out.splitlines()[-1])
    last_time = int(re.search(r"\.\. (\d+) ms\]", out.splitlines()[-1]).group(1))
    assert last_time - period_start > 10
    assert "warning" not in err


def test_a_longer_period_is_proven_free_of_overrun(capsys):
    code, out, _ = verify(capsys, str(CRUISE), "--timed", "--schedulability", "-DPERIOD=15")
    assert code == 0
    assert re.search(r"period of Cruise\.loop \(15 ms\): no overrun reachable \([\d,]+ states", out)


def test_the_tick_resolution_is_the_gcd_and_can_be_chosen(capsys):
    _, out, _ = verify(capsys, str(CRUISE), "--timed", "--schedulability")
    assert "one tick is 2 ms" in out  # gcd(10 ms, 2 ms, 4 ms)
    code, out, _ = verify(capsys, str(CRUISE), "--timed", "--schedulability", "--tick", "1ms")
    assert "one tick is 1 ms" in out and code == 4


def test_codels_without_wcet_are_named_in_a_warning(capsys):
    code, out, err = verify(capsys, str(NDD), "--no-rules", "--timed", "--schedulability", "--max-states", "2000")
    assert "warning: codels without wcet take 0 ms: NDD.nddArrived, " in err
    assert "NDD.nddPlan" in err


ODO = """
component Odo {
  version "1.0";
  lang "c";
  ids { double x; };
  task odo { period 50 ms; };
  activity Track() {
    task odo;
    codel <start> to_start() yield compute wcet 5 ms;
    codel <compute> to_compute(ids inout x) yield pause::compute wcet 15 ms;
    codel <stop> to_stop() yield ether wcet 10 ms;
    interrupts Track;
  };
};
"""


def test_a_codel_only_a_self_interruption_reaches_gets_its_wcet(tmp_path, capsys):
    # Track interrupts only itself: a new request preempts the running one, which runs its stop codel (GenoM3);
    # the task's exec connector for it takes the codel's 10 ms.
    gen = tmp_path / "Odo.gen"
    gen.write_text(ODO)
    code, out, err = verify(capsys, str(gen), "--timed", "--schedulability")
    assert code == 0 and err == ""
    assert "period of Odo.odo (50 ms): no overrun reachable" in out
    assert main([str(gen), "--timed", "-o", str(tmp_path / "out")]) == 0
    capsys.readouterr()
    bip = (tmp_path / "out" / "odo" / "odo.bip").read_text()
    assert "on exec_stop from STOP to STOP_YIELD" in bip
    assert "connector Exec2_PP Track_exec_stop(odo.scheduler_exec, Track.activity_exec_stop)" in bip  # 10 ms / 5 ms


def test_a_default_wcet_gives_them_time(capsys):
    description = parse_paths([NDD])
    package, _, _ = model_of(description, "NDD", None, TimeOptions(default_wcet_us=20_000))
    timed = next(a for a in package.annotations if a.name == "timed")
    assert timed.arguments["tick_us"] == "20000"  # gcd(100 ms, 20 ms)
    assert timed.arguments["default_wcet_us"] == "20000"
    assert any(c.name.startswith("Exec1_") for c in package.connector_types)


# --------------------------------------------------------------------------- latency observers


def test_latency_observers_one_holds_one_violated(capsys):
    code, out, _ = verify(capsys, str(CRUISE), "--timed", "--observers", str(OBSERVERS), "-DPERIOD=15")
    assert code == 4
    assert re.search(r"latency track_reacts \(within 16 ms\): no violation reachable", out)
    assert "latency command_quickly (within 2 ms): violation reachable" in out
    block = out.split("command_quickly")[1]
    steps = trace_times(block)
    assert steps[-1][1] in ("Cruise.Track:exec_start", "Cruise.Track:start")
    assert "Cruise.Track:start" in [label for _, label in steps]
    assert "time passes" in block.splitlines()[-1]


def test_latency_only_with_schedulability_not_asked(capsys):
    code, out, _ = verify(capsys, str(CRUISE), "--timed", "--schedulability", "-DPERIOD=15")
    assert "latency" not in out


def observer_errors(tmp_path, text: str):
    path = tmp_path / "observers.yaml"
    path.write_text(textwrap.dedent(text))
    reporter = Reporter()
    specs = load_observers(path, parse_paths([CRUISE]), reporter)
    return specs, [(d.span.line, d.span.column, d.message) for d in reporter.diagnostics]


@pytest.mark.parametrize("text,line,col,message", [
    ("observers:\n  - name: a\n    from: Cruse.Track:start\n    to: Cruise.Track:exec_start\n    within: 1 s\n",
     3, 11, "observer a: unknown module 'Cruse'"),
    ("observers:\n  - name: a\n    from: Cruise.Trak:start\n    to: Cruise.Track:exec_start\n    within: 1 s\n",
     3, 11, "observer a: module Cruise has no service, task or poster 'Trak'"),
    ("observers:\n  - name: a\n    from: Cruise.Track:strat\n    to: Cruise.Track:exec_start\n    within: 1 s\n",
     3, 11, "observer a: Cruise.Track has no event 'strat'"),
    ("observers:\n  - name: a\n    from: Cruise.Track\n    to: Cruise.Track:exec_start\n    within: 1 s\n",
     3, 11, "observer a: 'Cruise.Track' is not an event Module.Name:port"),
    ("observers:\n  - name: a\n    from: Cruise.Track:start\n    to: Cruise.Track:exec_start\n    within: soon\n",
     5, 13, "observer a: within is 'soon'; expected a positive duration"),
    ("observers:\n  - name: a\n    from: Cruise.Track:start\n    to: Cruise.Track:exec_start\n",
     2, 5, "observer #1 has no 'within'"),
    ("observers:\n  - name: a\n    form: Cruise.Track:start\n",
     3, 5, "observer #1: unknown key 'form'"),
    ("observer:\n  - name: a\n", 1, 1, "unknown top-level key 'observer'"),
    ("observers: [1, 2\n", 2, 1, "not valid YAML: expected ',' or ']', but got '<stream end>'"),
    ("observers:\n  - name: a\n    from: Cruise.Track:start\n    to: Cruise.loop:period\n    within: 1 s\n"
     "  - name: a\n    from: Cruise.Track:start\n    to: Cruise.loop:period\n    within: 1 s\n",
     6, 11, "duplicate observer name 'a'"),
])
def test_bad_observer_files_are_located(tmp_path, text, line, col, message):
    specs, errors = observer_errors(tmp_path, text)
    assert (line, col, message) in errors


def test_an_event_without_interaction_is_located_and_nothing_is_written(tmp_path, capsys):
    path = tmp_path / "observers.yaml"
    path.write_text("observers:\n  - name: a\n    from: Cruise.Track:start\n    to: Cruise.Track:reject\n"
                    "    within: 1 s\n")
    out_dir = tmp_path / "gen"
    code = main([str(CRUISE), "-o", str(out_dir), "--timed", "--observers", str(path)])
    _, err = capsys.readouterr()
    assert code == 1
    assert f"{path}:4:9: error: observer a: no interaction of the model is a Cruise.Track:reject event" in err
    assert not out_dir.exists() or not any(out_dir.iterdir())


def test_observers_need_timed(capsys):
    code, _, err = verify(capsys, str(CRUISE), "--observers", str(OBSERVERS))
    assert code == 2 and "--schedulability and --observers need --timed" in err


def test_timed_observers_are_not_handed_to_spin(capsys):
    code, _, err = verify(capsys, str(CRUISE), "--timed", "--engine", "spin")
    assert code == 2 and "checked by our explorer: drop --engine spin" in err


def test_a_bad_tick_is_a_usage_error(capsys):
    code, _, err = verify(capsys, str(CRUISE), "--timed", "--tick", "fast")
    assert code == 2 and "--tick: 'fast' is not a duration" in err


# --------------------------------------------------------------------------- the timed NDD model


def test_timed_ndd_is_generated_explored_and_read_back(tmp_path, capsys):
    code = main([str(NDD), "-o", str(tmp_path), "--timed", "--default-wcet", "25ms"])
    assert code == 0
    bip = tmp_path / "ndd" / "ndd.bip"
    text = bip.read_text()
    assert '@timed(tick_us="25000"' in text
    package = parse_file(bip)
    kinds = {a.name for a in package.atom_types}
    assert {"PeriodObserver", "Timer", "Scheduler"} <= kinds
    timer = package.atom_type("Timer")
    assert [p.name for p in timer.ports] == ["trigger", "sleep", "late", "tick"]
    capsys.readouterr()
    code, out, _ = verify(capsys, str(bip), "--timed", "--schedulability")
    # Every NDD codel takes 25 ms; GoTo goes from start through plan to arrived without pausing, so
    # with the motion task's own codel five codels can fall into one 100 ms period.
    assert "period of NDD.motion (100 ms): overrun reachable" in out, out
    assert code == 4
    steps = [label for _, label in trace_times(out)]
    # the fifth codel starts as the next release comes, which the timer keeps (late) for the period's end
    assert steps[-4:] == ["NDD.GoTo:exec_start", "NDD.GoTo:exec_plan", "NDD.motion:late", "NDD.GoTo:exec_arrived"]
