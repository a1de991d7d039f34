"""``python -m runtime run``: summary line, exit codes, messages instead of tracebacks."""
import json
import subprocess
import sys
from pathlib import Path

from enginekit import FIXTURES

ROOT = Path(__file__).resolve().parents[1]


def cli(*args, stdin=""):
    return subprocess.run([sys.executable, "-m", "runtime", "run", *map(str, args)], capture_output=True,
                          text=True, cwd=ROOT, input=stdin, timeout=60)


def test_run_first_policy_with_trace(tmp_path):
    trace = tmp_path / "t.jsonl"
    r = cli(FIXTURES / "Dining.bip", "--root", "Table3()", "--policy", "first", "--limit", "4", "--trace", trace)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert [line.split()[2] for line in lines[:4]] == ["eat0", "done0", "eat0", "done0"]
    assert lines[-1] == "4 steps, step limit reached"
    recs = [json.loads(x) for x in trace.read_text().splitlines()]
    assert [r["chosen"] for r in recs[1:-1]] == ["eat0", "done0", "eat0", "done0"]


def test_deadlock_quiet_and_seed():
    r = cli(FIXTURES / "Chain.bip", "--quiet", "--seed", "3")
    assert (r.returncode, r.stdout) == (0, "2 steps, deadlock (no enabled interaction)\n")
    a = cli(FIXTURES / "Broadcast.bip", "--seed", "5", "--limit", "20")
    b = cli(FIXTURES / "Broadcast.bip", "--seed", "5", "--limit", "20")
    assert a.stdout == b.stdout and a.returncode == 0


def test_model_error_exit_code():
    r = cli(FIXTURES / "Errors.bip", "--root", "OneSafe()", "--policy", "first")
    assert r.returncode == 4  # found: a model error (runtime/exits.py)
    assert r.stdout.splitlines()[-1].startswith("0 steps, model error: 1-safety violated")
    assert "Traceback" not in r.stderr and "atom u" in r.stderr


def test_bad_inputs_are_messages(tmp_path):
    r = cli(FIXTURES / "Dining.bip", "--root", "Nope()")
    assert r.returncode == 1 and "no compound or atom type named 'Nope'" in r.stderr and "Traceback" not in r.stderr
    r = cli(tmp_path / "Missing.bip")
    assert r.returncode == 1 and "cannot read BIP2 file" in r.stderr and "Traceback" not in r.stderr
    bad = tmp_path / "Bad.bip"
    bad.write_text("package Bad\n  atom type A(\nend\n")
    r = cli(bad)
    assert r.returncode == 1 and "Bad.bip:" in r.stderr and "Traceback" not in r.stderr
    r = cli(FIXTURES / "Arith.bip")
    assert r.returncode == 1 and "without a Python binding: log, twice" in r.stderr
    r = cli(FIXTURES / "Arith.bip", "--externs", "no.such.module")
    assert r.returncode == 1 and "cannot import module 'no.such.module'" in r.stderr


def test_externs_module_path_and_interactive_eof():
    r = cli(FIXTURES / "Arith.bip", "--externs", FIXTURES / "arith_externs.py", "--policy", "first")
    assert r.returncode == 0 and r.stdout.splitlines()[-1] == "1 step, deadlock (no enabled interaction)"
    r = cli(FIXTURES / "Dining.bip", "--root", "Table3()", "--policy", "interactive", stdin="3\n")
    assert r.returncode == 0 and "Traceback" not in r.stderr
    assert r.stdout.splitlines()[-1] == "1 step, stopped"


def test_same_atom_twice_in_a_connector_is_a_message(tmp_path):
    text = (
        (FIXTURES / "Dining.bip").read_text().replace("eat0(f0.take, p0.eat, f1.take)", "eat0(f0.take, p0.eat, f0.put)")
    )
    path = tmp_path / "Dining.bip"
    path.write_text(text)
    r = cli(path, "--root", "Table3()")
    line = text[:text.index("eat0(f0.take, p0.eat, f0.put)")].count("\n") + 1
    assert r.returncode == 1 and f"Dining.bip:{line}:" in r.stderr
    assert "connector 'eat0' in compound type Table3 binds component 'f0' more than once" in r.stderr


def test_show_source():
    r = subprocess.run([sys.executable, "-m", "runtime", "run", str(FIXTURES / "Chain.bip"), "--show-source"],
                       capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert r.returncode == 0 and "def _in0(L):" in r.stdout and "Eager internal transitions of atom ch" in r.stdout


def test_no_maximal_progress_option():
    r = cli(FIXTURES / "Broadcast.bip", "--policy", "first", "--limit", "1", "--no-maximal-progress")
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[0].split()[2] == "bc[snd.snd]"   # the smallest interaction, first in order
    r = cli(FIXTURES / "Broadcast.bip", "--policy", "first", "--limit", "1")
    assert r.stdout.splitlines()[0].split()[2] == "bc"
