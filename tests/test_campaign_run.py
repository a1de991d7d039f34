"""``genom2bip campaign`` on a local Dask cluster: a line per job, the table, the picture; a second run resumes; a job
that crashes its worker or fails is recorded and the others go on; Ctrl-C writes what is done and says what is not.

Each test waits for events (a line printed, a file written), never for a time.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from genom2bip.campaign import expand, read_campaign
from tests.nativekit import needs_cc

pytest.importorskip("distributed")
pytestmark = needs_cc

ROOT = Path(__file__).resolve().parents[1]
CRUISE = ROOT / "tests" / "fixtures" / "timed" / "Cruise.gen"
CRUISE_OBSERVERS = ROOT / "tests" / "fixtures" / "timed" / "observers.yaml"
FIXTURES = ROOT / "tests" / "fixtures" / "campaign"
#: Far past what a loaded machine needs for these small campaigns: a hang fails, a slow machine does not.
PATIENCE = 900

SWEEP = f"""campaign: cruise
models:
  cruise:
    paths: [{CRUISE}]
    timed: {{observers: {CRUISE_OBSERVERS}}}
vary:
  define.PERIOD: [10, 12, 15]
checks:
  - check: observer
    model: cruise
"""


def campaign(args, cwd: Path, env=None, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "genom2bip", "campaign", *map(str, args)], capture_output=True,
                          text=True, cwd=cwd, env={**os.environ, **(env or {})}, timeout=PATIENCE, **kw)


def interruptible() -> None:
    """In the child: SIGINT as a terminal's Ctrl-C finds it, even when the tests run where it is ignored (a
    background job of a shell without job control), which Python would then keep ignoring."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def lines(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def test_a_sweep_writes_a_line_per_job_a_table_a_picture_and_a_second_run_resumes(tmp_path):
    path = tmp_path / "cruise.yaml"
    path.write_text(SWEEP)
    jobs = expand(read_campaign(path)).jobs
    out = tmp_path / "out"
    proc = campaign([path, "-o", out, "--workers", "2"], tmp_path)
    assert proc.returncode == 4, proc.stderr  # some observers are violated
    records = lines(out / "results.jsonl")
    assert sorted(r["job"] for r in records) == sorted(j.id for j in jobs) and len(jobs) == 9
    by_point = {(r["point"]["define.PERIOD"], r["target"]): r for r in records}
    # 4 + 4 + 4 ms of codels in a period: a period of 10 ms overruns, 15 ms does not; a command within 2 ms never
    assert by_point[10, "Cruise.loop.overrun"]["verdict"] == "violated"
    assert by_point[15, "Cruise.loop.overrun"]["verdict"] == "holds"
    assert {by_point[p, "command_quickly"]["verdict"] for p in (10, 12, 15)} == {"violated"}
    for r in records:
        assert r["status"] == "done" and r["host"] and r["worker"].startswith("tcp://127.0.0.1:")
        assert r["seconds"] > 0 and r["peak_memory"] > 0 and r["figures"]["states"] > 0
        job_file = out / r["result"]
        assert json.loads(job_file.read_text())["verdict"] == r["verdict"]
        assert (r["trace"] is None) == (r["verdict"] == "holds")
    violated = by_point[10, "Cruise.loop.overrun"]
    assert json.loads((out / violated["trace"]).read_text())["trace"]["timed"]
    # the table: a row per job, the answers counted; the picture of the numeric axis
    assert "model   check     method   target" in proc.stdout and "define.PERIOD=15" in proc.stdout
    assert "9 jobs: " in proc.stdout and f"picture: {out / 'define.PERIOD.png'}" in proc.stdout
    assert (out / "define.PERIOD.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    # again: nothing runs, the results stay as they were
    before = (out / "results.jsonl").read_bytes()
    again = campaign([path, "-o", out, "--workers", "2"], tmp_path)
    assert again.returncode == 4 and "9 jobs, 9 already in" in again.stdout and "0 to run" in again.stdout
    assert (out / "results.jsonl").read_bytes() == before

    # a line cut by a kill: kept aside as it was, its job run again, every job once
    cut = before[:-40]
    (out / "results.jsonl").write_bytes(cut)
    third = campaign([path, "-o", out, "--workers", "2"], tmp_path)
    assert f"note: 1 line(s) of {out / 'results.jsonl'} are not job records" in third.stdout, third.stdout
    assert "8 already in" in third.stdout and "1 to run" in third.stdout
    assert (out / "results.unreadable.jsonl").read_bytes() == cut[cut.rindex(b"\n") + 1:] + b"\n"
    assert sorted(r["job"] for r in lines(out / "results.jsonl")) == sorted(j.id for j in jobs)


def test_a_job_that_crashes_its_workers_or_fails_is_recorded_and_the_others_go_on(tmp_path):
    """One worker: the job that crashes it runs first (submitted first), and the others wait on that worker each time
    it dies.  Dask counts a death against every job its worker holds, so they too reach the limit of deaths; they are
    not the cause, and run again."""
    path = tmp_path / "c.yaml"
    path.write_text(f"""models:
  gate: {{paths: [{FIXTURES / 'Gate.bip'}]}}
  cruise: {{paths: [{CRUISE}], timed: true}}
checks:
  - {{check: deadlock, model: gate, options: {{externs: {FIXTURES / 'crash.py'}}}}}
  - {{check: deadlock, model: gate, options: {{externs: {FIXTURES / 'broken_externs.py'}}}}}
  - {{check: observer, model: cruise}}
""")
    out = tmp_path / "out"
    proc = campaign([path, "-o", out, "--workers", "1"], tmp_path)
    assert proc.returncode == 5, proc.stderr
    by_externs = {Path(r["options"].get("externs", "-")).name: r for r in lines(out / "results.jsonl")}
    crashed, failed, done = by_externs["crash.py"], by_externs["broken_externs.py"], by_externs["-"]
    assert crashed["status"] == "crashed" and "worker process died each time it ran it" in crashed["message"]
    assert failed["status"] == "failed" and failed["message"] == (
        f"externs: importing {FIXTURES / 'broken_externs.py'} failed: RuntimeError: this module is broken on purpose")
    assert done["status"] == "done" and done["verdict"] == "violated"
    assert "crashed" in proc.stdout and "failed" in proc.stdout and "3 jobs: " in proc.stdout
    # run again: what is done stays done; with --retry-failed the failed and the crashed run again
    assert "3 already in" in campaign([path, "-o", out, "--workers", "1"], tmp_path).stdout
    again = campaign([path, "-o", out, "--workers", "1", "--retry-failed"], tmp_path)
    assert "1 already in" in again.stdout and "2 to run" in again.stdout, again.stderr
    records = lines(out / "results.jsonl")
    assert sorted(r["status"] for r in records) == ["crashed", "done", "failed"]  # a line per job, the last run's


def test_a_job_past_its_time_limit_is_stopped_and_recorded_and_its_worker_serves_again(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text(f"""models:
  gate: {{paths: [{FIXTURES / 'Gate.bip'}]}}
  cruise: {{paths: [{CRUISE}], timed: true, defines: {{PERIOD: 15}}}}
checks:
  - {{check: deadlock, model: gate, timeout: 2 s, options: {{externs: {FIXTURES / 'gate.py'}}}}}
  - {{check: observer, model: cruise, vary: {{wcet-scale: [1, 2, 3]}}}}
""")
    out = tmp_path / "out"  # the gate never opens: the job would wait forever
    proc = campaign([path, "-o", out, "--workers", "1"], tmp_path, env={"GENOM2BIP_TEST_GATE": str(tmp_path / "no")})
    assert proc.returncode == 5, proc.stderr
    records = lines(out / "results.jsonl")
    stopped = next(r for r in records if r["model"] == "gate")
    assert (stopped["status"], stopped["limit"], stopped["timeout"]) == ("timeout", "timeout", 2.0)
    assert stopped["message"] == "stopped past its time limit of 2 s; its worker was restarted"
    # the one worker, restarted, ran the others: 12 ms of codels in 15 ms hold, twice or thrice that do not
    verdicts = {r["point"]["wcet-scale"]: r["verdict"] for r in records if r["model"] == "cruise"}
    assert verdicts == {1: "holds", 2: "violated", 3: "violated"}
    assert "timeout" in proc.stdout and "4 jobs: " in proc.stdout


def test_ctrl_c_writes_what_is_done_says_what_is_not_and_the_next_run_does_it(tmp_path):
    gate = tmp_path / "gate"
    path = tmp_path / "c.yaml"
    gated = f"models:\n  gate: {{paths: [{FIXTURES}/Gate.bip]}}\n"
    text = SWEEP.replace("[10, 12, 15]", "[10]").replace("models:\n", gated)
    path.write_text(text + f"  - {{check: deadlock, model: gate, options: {{externs: {FIXTURES / 'gate.py'}}}}}\n")
    out = tmp_path / "out"
    env = {**os.environ, "GENOM2BIP_TEST_GATE": str(gate)}
    proc = subprocess.Popen([sys.executable, "-m", "genom2bip", "campaign", str(path), "-o", str(out), "--workers",
                             "2"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path, env=env,
                            preexec_fn=interruptible)
    try:
        answers = 0
        for line in proc.stdout:  # the three observers end while the gated job waits in the other worker
            answers += line.split(" ")[0] in ("holds", "violated")
            if answers == 3:
                break
        waiting = Path(str(gate) + ".waiting")  # the gated job runs (not only queued) when Ctrl-C comes
        deadline = time.monotonic() + PATIENCE
        while not waiting.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert waiting.exists(), "the gated job never started"
        # each worker leads a session of its own, not the command's: a busy machine that shares the CPU between
        # sessions gives each worker a part (bench/campaign_bench.py), and a Ctrl-C at the terminal reaches the
        # command alone
        workers = {r["pid"] for r in lines(out / "results.jsonl")}
        assert all(os.getsid(pid) == pid != os.getsid(proc.pid) for pid in workers), workers
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=PATIENCE)
    finally:
        if proc.poll() is None:  # a failed assertion above: the held job would keep the command forever
            proc.kill()
            proc.communicate()
    assert proc.returncode == 130, err
    assert "interrupted: 3 jobs done in this run and written; 1 not done:" in err
    assert "  gate deadlock deadlock freedom [define.PERIOD=10]  (was running: stopped)\n" in err, err
    assert "run the same command again" in err
    assert len(lines(out / "results.jsonl")) == 3
    gate.write_text("")
    again = campaign([path, "-o", out, "--workers", "2"], tmp_path, env={"GENOM2BIP_TEST_GATE": str(gate)})
    assert "3 already in" in again.stdout and "1 to run" in again.stdout, again.stderr
    records = lines(out / "results.jsonl")
    assert len(records) == 4 and len({r["job"] for r in records}) == 4


def test_a_scheduler_out_of_reach_is_named_and_nothing_is_written(tmp_path):
    import socket

    path = tmp_path / "c.yaml"
    path.write_text(SWEEP)
    with socket.socket() as s:  # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    proc = campaign([path, "-o", tmp_path / "out", "--scheduler", f"tcp://127.0.0.1:{port}", "--connect-timeout", "2"],
                    tmp_path)
    assert proc.returncode == 1
    assert f"genom2bip: error: cannot reach the Dask scheduler tcp://127.0.0.1:{port}" in proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml"]
