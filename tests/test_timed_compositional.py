"""Time in the compositional analysis: the tick is one more interaction; observers are decided by localization."""
from __future__ import annotations

import re
from pathlib import Path

from genom2bip.cli import main
from tests.runkit import dala_without_wcets

ROOT = Path(__file__).resolve().parents[1]
CRUISE = str(ROOT / "tests/fixtures/timed/Cruise.gen")
NDD = str(dala_without_wcets() / "NDD.gen")  # each codel takes 0 ms: the tick is the period


def verify(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(["verify", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_a_timed_model_is_proved_free_of_time_locks_as_exploration_finds(capsys):
    code, out, _ = verify(capsys, NDD, "--no-rules", "--timed", "--method", "compositional")
    assert code == 0 and "deadlock-free (compositional" in out
    assert "  time: the tick is one more interaction (all timed atoms at once); deadlock-free means no time-lock" \
        in out.splitlines()
    assert out.splitlines()[-1].startswith("period of NDD.motion (100 ms): no overrun reachable (localization, ")
    code, out, _ = verify(capsys, NDD, "--no-rules", "--timed", "--deadlock")
    assert code == 0 and "deadlocks: none" in out


def test_the_compositional_method_decides_the_observers_as_exploration_does(capsys):
    for option in (["--schedulability"], ["--observers", str(ROOT / "tests/fixtures/timed/observers.yaml")]):
        code, out, err = verify(capsys, CRUISE, "--timed", "--method", "compositional", *option)
        explored, by_search, _ = verify(capsys, CRUISE, "--timed", *option)
        assert code == explored == 4 and "error" not in err
        verdicts = re.findall(r"^(period of .*?|latency .*?) \(.*?\): (.*? reachable)", out, re.M)
        assert verdicts == re.findall(r"^(period of .*?|latency .*?) \(.*?\): (.*? reachable)", by_search, re.M)
        assert ("period of Cruise.loop", "overrun reachable") in verdicts


def test_both_methods_prove_no_time_lock_then_explore_the_observers(capsys):
    code, out, _ = verify(capsys, CRUISE, "--timed", "--method", "both", "--schedulability")
    assert code == 4
    assert "deadlock-free (compositional" in out
    assert re.search(r"period of Cruise\.loop \(10 ms\): overrun reachable \(\d+ steps\):", out)
