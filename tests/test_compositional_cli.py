"""``genom2bip verify --method compositional|both``: report, verdicts, exit statuses, graph, usage errors."""
import re
from pathlib import Path

import pytest

from genom2bip.cli import main
from tests.verifykit import NDD

FIXTURES = Path(__file__).parent / "fixtures" / "compositional"
PHILOSOPHERS = str(FIXTURES / "Philosophers.bip")
GUARDS = str(FIXTURES / "Guards.bip")


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_ndd_is_deadlock_free_by_the_compositional_method(capsys):
    code, out, err = run(capsys, "verify", str(NDD), "--no-rules", "--deadlock", "--method", "compositional")
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0] == "model NDD (NDD())"
    assert lines[1] == "compositional analysis (component invariants, interaction invariants, DIS; SAT: cadical153)"
    assert lines[2].startswith("  component invariants: ") and "17 atoms, 105 local states" in lines[2]
    assert lines[3].startswith("  formula: ") and "48 interactions" in lines[3]
    assert lines[4].startswith("  SAT: ") and "0 candidates" in lines[4]
    assert lines[-1].startswith("deadlock-free (compositional, ")
    assert "explored" not in out


def test_a_reachable_candidate_is_printed_with_its_state_cycles_and_trace(capsys):
    code, out, _ = run(capsys, "verify", PHILOSOPHERS, "--root", "Circle3()", "--method", "compositional")
    assert code == 4
    assert "  check: exploration: " in out
    block = out[out.index("candidate 1:"):].splitlines()
    assert block[0] == "candidate 1: reachable by exploration (shortest trace)"
    assert block[1:8] == ["  state:", "    p0: ONE", "    p1: ONE", "    p2: ONE", "    f0: BUSY", "    f1: BUSY",
                          "    f2: BUSY"]
    assert any(line.startswith("  waits: ") and line.count("->") == 6 for line in block)
    at = block.index("  trace (3 steps):")
    assert block[at + 1:at + 4] == ["       1  left0", "       2  left1", "       3  left2"]
    assert block[-1].startswith("deadlock reachable (compositional, ")


def test_both_methods_run_side_by_side_and_agree(capsys):
    code, out, _ = run(capsys, "verify", PHILOSOPHERS, "--root", "Ordered3()", "--method", "both")
    assert code == 0
    assert "deadlock-free (compositional, " in out
    assert "\nexploration\nexplored: " in out and "deadlocks: none reachable" in out
    assert "potential deadlocks: " in out and "refuted 1: interaction invariant: " in out


def test_an_unreached_candidate_is_unknown_with_its_reason(capsys):
    code, out, _ = run(capsys, "verify", GUARDS, "--root", "Bounded()", "--method", "compositional",
                       "--check-states", "5")
    assert code == 5
    assert "candidate 1: unknown: breadth-first exploration stopped at 5 states" in out
    assert re.search(r"^  check: candidate 1: [\d.]+ s \(unknown\)$", out, re.M)  # no empty "()" of a method
    assert out.splitlines()[-1].startswith("unknown: deadlock freedom neither proved nor refuted")


def test_the_dependency_graph_marks_the_wait_for_cycles(capsys, tmp_path):
    dot = tmp_path / "deps.dot"
    code, out, _ = run(capsys, "verify", PHILOSOPHERS, "--root", "Circle3()", "--method", "compositional",
                       "--graph", str(dot))
    assert code == 4
    assert f"wrote {dot} (dependency graph: 6 atoms, 18 edges, " in out
    text = dot.read_text()
    # p_i waits for f_i+1 (to take it); a busy fork waits for both its philosophers (to release it)
    assert text.count("color=red") == 9
    assert '"p0" -> "f1" [tooltip="right0\\nrelease0", color=red, penwidth=2];' in text
    assert "//   candidate 1: " in text


def test_graph_to_an_unwritable_place_is_an_error(capsys, tmp_path):
    target = tmp_path / "missing" / "deps.dot"
    code, _, err = run(capsys, "verify", PHILOSOPHERS, "--root", "Circle3()", "--method", "compositional",
                       "--graph", str(target))
    assert code == 1
    assert f"cannot write {target}: No such file or directory" in err
    assert not target.exists()


@pytest.mark.parametrize("extra, message", [
    (["--method", "both", "--property", "x.mcl"], "--property with both needs one method"),
    (["--method", "compositional", "--property", "x.mcl", "--timed"], "on untimed models; drop --timed"),
    (["--method", "both", "--engine", "spin"], "--method both decides candidates with our explorer"),
    (["--method", "compositional", "--requests", "2"], "drop --requests"),
    (["--method", "compositional", "--solver", "nosuch"], "--solver nosuch: not a python-sat solver (one of "),
    (["--graph", "g.dot"], "--graph belongs to --method compositional or both"),
    (["--method", "compositional", "--check-states", "-1"], "--check-states must be >= 0"),
])
def test_usage_errors(capsys, tmp_path, extra, message):
    code, out, err = run(capsys, "verify", PHILOSOPHERS, "--root", "Circle3()", *extra)
    assert code == 2
    assert message in err
    assert out == ""
    assert not (tmp_path / "g.dot").exists() and not Path("g.dot").exists()


@pytest.mark.parametrize("model", ["descriptions/dala", "descriptions/arm/Arm.gen"])
def test_whole_functional_levels_are_concluded_without_exploring(capsys, model):
    path = Path(__file__).resolve().parents[1] / model
    code, out, err = run(capsys, "verify", str(path), "--deadlock", "--method", "compositional")
    assert code == 0, err
    assert "check: " not in out and "explored" not in out
    assert out.splitlines()[-1].startswith("deadlock-free (compositional, ")
