"""An output closed by its reader (``genom2bip verify ... | head -1``) never turns a verdict into success: printing
stops quietly and the exit status stays the verdict's; a campaign with jobs left stops, says so on stderr and
exits 141.

The reader goes away at a known moment: the test holds the pipe's read end
and closes it, so no output can slip through the pipe's buffer first.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from badinputkit import HANG, ROOT

pytestmark = pytest.mark.reliability

PAIR = ROOT / "tests" / "fixtures" / "platform" / "Pair.gen"
FIXTURES = ROOT / "tests" / "fixtures" / "campaign"
CRUISE = ROOT / "tests" / "fixtures" / "timed" / "Cruise.gen"
SWEEP = f"""campaign: cruise
models:
  cruise:
    paths: [{CRUISE}]
    timed: {{observers: {CRUISE.parent / "observers.yaml"}}}
vary:
  define.PERIOD: [10]
checks:
  - check: observer
    model: cruise
"""


def _closed_at_once(*argv, cwd=ROOT, both=False) -> tuple[int, str]:
    """Run ``genom2bip ARGV`` with a stdout (``both``: and stderr, ``2>&1``) whose reader has gone before the first
    byte; its status and (unless ``both``) its stderr."""
    read, write = os.pipe()
    child = subprocess.Popen([sys.executable, "-m", "genom2bip", *map(str, argv)], cwd=cwd, stdout=write,
                             stderr=write if both else subprocess.PIPE, stdin=subprocess.DEVNULL, text=True,
                             env={**os.environ, "PYTHONPATH": str(ROOT)})
    os.close(write)
    os.close(read)
    _, err = child.communicate(timeout=HANG)
    return child.returncode, err or ""


def test_a_violation_stays_a_violation_when_the_output_is_closed(tmp_path):
    one = tmp_path / "one.yaml"
    one.write_text("cores: 1\n")
    alone = subprocess.run([sys.executable, "-m", "genom2bip", "verify", PAIR, "--timed", "--platform", one],
                           cwd=ROOT, capture_output=True, text=True, timeout=HANG,
                           env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert alone.returncode == 4, alone.stdout + alone.stderr  # an overrun is reachable on one core
    code, err = _closed_at_once("verify", PAIR, "--timed", "--platform", one)
    assert code == 4, err
    assert "Traceback" not in err and "Exception ignored" not in err and "BrokenPipe" not in err, err


def test_a_violation_stays_a_violation_when_stdout_and_stderr_are_one_closed_pipe(tmp_path):
    one = tmp_path / "one.yaml"
    one.write_text("cores: 1\n")
    assert _closed_at_once("verify", PAIR, "--timed", "--platform", one, both=True) == (4, "")


def test_help_into_a_closed_output_is_quiet():
    code, err = _closed_at_once("--help")
    assert (code, err) == (0, "")


@pytest.fixture
def campaign_file(tmp_path):
    pytest.importorskip("distributed")
    path = tmp_path / "c.yaml"
    gated = f"models:\n  gate: {{paths: [{FIXTURES}/Gate.bip]}}\n"
    path.write_text(SWEEP.replace("models:\n", gated)
                    + f"  - {{check: deadlock, model: gate, options: {{externs: {FIXTURES / 'gate.py'}}}}}\n")
    return path


def test_a_campaign_whose_output_is_closed_stops_says_so_and_exits_141(tmp_path, campaign_file):
    out = tmp_path / "out"
    code, err = _closed_at_once("campaign", campaign_file, "-o", out, "--workers", "1", cwd=tmp_path)
    assert code == 141, err
    assert "stopped: the output was closed (nobody reads the rest): 0 jobs done in this run and written; 4 not " \
           "done:\n" in err, err
    assert "  gate deadlock deadlock freedom [define.PERIOD=10]\n" in err, err
    assert "run the same command again to run them" in err
    assert "Traceback" not in err and "internal error" not in err
    assert not (out / "results.jsonl").exists() or (out / "results.jsonl").read_text() == ""


def test_a_campaign_whose_output_closes_after_its_last_job_keeps_its_verdict(tmp_path, campaign_file):
    """The three observers end, the reader goes, then the gated job ends: nothing is left to stop, and the
    status is the verdict's (a violated observer: 4), as if the output had been read."""
    gate, out = tmp_path / "gate", tmp_path / "out"
    child = subprocess.Popen([sys.executable, "-m", "genom2bip", "campaign", str(campaign_file), "-o", str(out),
                              "--workers", "2"], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True, env={**os.environ, "PYTHONPATH": str(ROOT), "GENOM2BIP_TEST_GATE": str(gate)})
    try:
        answers = 0
        for line in child.stdout:
            answers += line.split(" ")[0] in ("holds", "violated")
            if answers == 3:
                break
        child.stdout.close()  # the reader goes while the gated job still runs
        gate.write_text("")
        _, err = child.communicate(timeout=HANG)
    finally:
        if child.poll() is None:
            child.kill()
            child.communicate()
    assert child.returncode == 4, err
    assert "Traceback" not in err and "internal error" not in err and "stopped" not in err, err
    records = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert len(records) == 4 and {r["status"] for r in records} == {"done"}
