"""``genom2bip verify``: verdicts, traces, exit statuses, and the LTS exports."""
import io

import pytest

from genom2bip.cli import main
from runtime.explore import explore
from runtime.export.lts import write_aut, write_dot
from tests.verifykit import FIXTURES, NDD, NDD_NO_AFTER, space

DINING = str(FIXTURES / "Dining.bip")


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_deadlock_report_with_trace_and_state_per_atom(capsys):
    code, out, err = run(capsys, "verify", DINING, "--root", "Table2()", "--deadlock")
    assert code == 4, err
    lines = out.splitlines()
    assert lines[0] == f"model {DINING} (Table2())"
    assert lines[1].startswith("explored: 6 states, 8 transitions, depth 2, complete;")
    assert "bytes/state" in lines[1]
    assert lines[2] == "deadlocks: 1 reachable state without enabled interaction, each with a shortest trace"
    assert lines[3:] == [
        "deadlock 1 of 1 (state 4, 2 steps):",
        "       1  left0",
        "       2  left1",
        "  state:",
        "    p0: ONE",
        "    p1: ONE",
        "    f0: BUSY",
        "    f1: BUSY",
    ]


def test_no_deadlock_exits_zero_and_the_default_check_is_deadlocks(capsys):
    code, out, _ = run(capsys, "verify", str(FIXTURES / "Counters.bip"))
    assert code == 0
    assert "deadlocks: none reachable" in out and "6 states, 13 transitions" in out


def test_variables_in_the_deadlocked_state(capsys):
    code, out, _ = run(capsys, "verify", str(FIXTURES / "Codel.bip"))
    assert code == 4
    assert "       1  run  [plan -> throw e_fail]" in out
    assert "    a: FAILED outcome=2" in out  # the engine's value, not the reduction's reset


def test_limits_give_exit_five(capsys):
    code, out, _ = run(capsys, "verify", str(FIXTURES / "Counters.bip"), "--max-states", "3")
    assert code == 5 and "stopped at max-states" in out and "in the explored part" in out


def test_property_verdicts_and_exit_status(capsys, tmp_path):
    props = tmp_path / "p.mcl"
    props.write_text('ok: "S.req" precedes "S.work";\nbad: never "S.reply"\n')
    code, out, _ = run(capsys, "verify", str(FIXTURES / "Server.bip"), "--property", str(props), "--engine", "python")
    assert code == 4
    assert 'property ok: "S.req" precedes "S.work"' in out
    assert "  holds (safety search" in out
    assert "  violated (safety search" in out
    assert "  counterexample (3 steps):\n       1  S.req\n       2  S.work\n       3  S.reply" in out
    props.write_text('ok: "S.req" precedes "S.work"')
    code, _, _ = run(capsys, "verify", str(FIXTURES / "Server.bip"), "--property", str(props))
    assert code == 0


def test_bad_property_file_exits_one_with_location(capsys, tmp_path):
    props = tmp_path / "p.mcl"
    props.write_text('never "S.req" .\n')
    code, out, err = run(capsys, "verify", str(FIXTURES / "Server.bip"), "--property", str(props))
    assert code == 1 and out == ""
    assert err.startswith(f"{props}:1:16: error: unexpected end of the file")


def test_descriptions_as_model_and_the_paper_property(capsys):
    prop = str(FIXTURES / "goto_after_setspeed.mcl")
    code, out, _ = run(capsys, "verify", str(NDD_NO_AFTER), "--no-rules", "--property", prop)
    assert code == 4
    assert "  counterexample (1 step):\n       1  NDD.GoTo:trigger  [nddCheckGoal -> ok]" in out


def test_usage_errors(capsys):
    code, _, err = run(capsys, "verify", DINING, "--max-states", "-1")
    assert code == 2 and "--max-states must be >= 0" in err
    code, _, err = run(capsys, "verify", DINING, "--engine", "spin", "--dfs")
    assert code == 2
    code, _, err = run(capsys, "verify", DINING, str(NDD))
    assert code == 2 and "either one .bip file or description files" in err


def test_bad_root_and_missing_file(capsys):
    code, _, err = run(capsys, "verify", DINING, "--root", "Table9()")
    assert code == 1 and "no compound or atom type named 'Table9'" in err
    code, _, err = run(capsys, "verify", "nowhere.bip")
    assert code == 1 and "nowhere.bip: no such file" in err


def test_forced_progress_goes_to_stderr(capsys):
    code, out, err = run(capsys, "verify", DINING, "--progress")
    assert code == 4 and "\r" not in out


# --- exports -----------------------------------------------------------------------------------------

def test_aut_header_and_transitions():
    sp = space("Dining", "Table2()", keep_edges=True)
    explore(sp)
    buf = io.StringIO()
    assert write_aut(sp, buf) == (6, 8)
    lines = buf.getvalue().splitlines()
    assert lines[0] == "des (0, 8, 6)"
    assert len(lines) == 9
    assert lines[1] == '(0, "left0", 1)'
    assert all(line.startswith("(") and line.count('"') == 2 for line in lines[1:])


def test_aut_with_several_initial_states_adds_a_root():
    from runtime.explore import Choice
    from tests.test_explore import EXTERN
    from tests.verifykit import text_space

    text = EXTERN.replace("initial to S\n", "initial to S do { x = measure(); }\n")
    sp = text_space(text, externs={"measure": Choice("measure", (4, 5))}, reduce=False, keep_edges=True)
    explore(sp)
    buf = io.StringIO()
    write_aut(sp, buf)
    lines = buf.getvalue().splitlines()
    # two initial states (x = 4, 5), each going to T with x = 4 or 5: 4 transitions, plus two from the root
    assert lines[0] == "des (4, 6, 5)"
    assert lines[1:3] == ['(4, "i", 0)', '(4, "i", 1)']


def test_dot_marks_initial_and_deadlock_states():
    sp = space("Dining", "Table2()", keep_edges=True)
    explore(sp)
    buf = io.StringIO()
    assert write_dot(sp, buf) == (6, 8)
    text = buf.getvalue()
    assert text.startswith("digraph lts {")
    assert "0 [style=bold" in text and "doublecircle" in text
    assert text.count(" -> ") == 8 and '[label="left0"]' in text


def test_exports_from_the_command_line(capsys, tmp_path):
    aut, dot = tmp_path / "m.aut", tmp_path / "m.dot"
    code, out, _ = run(capsys, "verify", DINING, "--root", "Table3()", "--aut", str(aut), "--dot", str(dot))
    assert code == 4  # the exploration the exports need finds Table3's deadlock: the default check still runs
    assert "deadlocks: 1 reachable state without enabled interaction" in out
    assert aut.read_text().splitlines()[0] == "des (0, 27, 14)"
    assert f"wrote {aut} (Aldebaran LTS: 14 states, 27 transitions)" in out
    assert dot.read_text().count(" -> ") == 27


@pytest.mark.parametrize("engine", ["explore", "compiled", "python"])
@pytest.mark.parametrize("export", ["--aut", "--dot"])
def test_an_lts_export_of_a_model_that_deadlocks_exits_with_the_violation_status(capsys, tmp_path, engine, export):
    path = tmp_path / "m.out"
    code, out, err = run(capsys, "verify", DINING, "--root", "Table3()", export, str(path), "--engine", engine,
                         "--traces", "terminal")
    assert code == 4, err
    assert "deadlock 1 of 1 (state 12, 3 steps):" in out and path.exists()


def test_an_lts_export_of_a_model_without_deadlock_exits_zero(capsys, tmp_path):
    code, out, err = run(capsys, "verify", str(FIXTURES / "Counters.bip"), "--aut", str(tmp_path / "c.aut"),
                         "--traces", "terminal")
    assert code == 0, err
    assert "deadlocks: none reachable" in out


def test_a_promela_translation_alone_explores_nothing(capsys, tmp_path):
    pml = tmp_path / "m.pml"
    code, out, err = run(capsys, "verify", DINING, "--root", "Table3()", "--promela", str(pml), "--traces", "terminal")
    assert code == 0, err  # SPIN searches it; verify only translates
    assert "explored" not in out and "deadlock" not in out and pml.exists()


def test_truncated_lts_is_not_exported(capsys, tmp_path):
    aut = tmp_path / "m.aut"
    code, _, err = run(capsys, "verify", DINING, "--max-states", "4", "--aut", str(aut))
    assert code == 5 and not aut.exists() and "not complete" in err
