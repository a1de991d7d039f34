"""Time in the compositional analysis: the tick is one more interaction; observers are left to exploration."""
from __future__ import annotations

from pathlib import Path

from genom2bip.cli import main

ROOT = Path(__file__).resolve().parents[1]
CRUISE = str(ROOT / "tests/fixtures/timed/Cruise.gen")
NDD = str(ROOT / "descriptions/dala/NDD.gen")


def verify(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(["verify", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_a_timed_model_is_proved_free_of_time_locks_as_exploration_finds(capsys):
    code, out, _ = verify(capsys, NDD, "--no-rules", "--timed", "--method", "compositional")
    assert code == 0 and out.splitlines()[-1].startswith("deadlock-free (compositional")
    assert "  time: the tick is one more interaction (all timed atoms at once); deadlock-free means no time-lock; " \
           "the observers are checked by --method both or explore" in out.splitlines()
    code, out, _ = verify(capsys, NDD, "--no-rules", "--timed", "--deadlock")
    assert code == 0 and "deadlocks: none" in out


def test_observers_are_refused_by_the_compositional_method_alone(capsys):
    for option in (["--schedulability"], ["--observers", str(ROOT / "tests/fixtures/timed/observers.yaml")]):
        code, out, err = verify(capsys, CRUISE, "--timed", "--method", "compositional", *option)
        assert code == 2 and out == ""
        assert err.strip() == (
            "genom2bip: error: --method compositional proves deadlock freedom (on a --timed model: no time-lock); "
            "whether an observer reaches ERROR is reachability, which it does not decide: use --method both (the "
            "observers are then checked by exploration) or --method explore")


def test_both_methods_prove_no_time_lock_then_explore_the_observers(capsys):
    code, out, _ = verify(capsys, CRUISE, "--timed", "--method", "both", "--schedulability")
    assert code == 4
    assert "deadlock-free (compositional" in out
    assert "period of Cruise.loop (10 ms): overrun reachable (25 steps):" in out
