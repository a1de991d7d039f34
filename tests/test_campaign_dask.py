"""A campaign on a real Dask cluster: ``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1, one of them
killed while it runs a job.  Every job's result is there exactly once, the killed job ran again on the other worker,
and every verdict is the one the job gives when run alone.

The test waits for events: the scheduler accepting a client, the workers joining, the job starting on its worker
(the campaign's own event, which a job held at a gate keeps running until the worker is killed).
"""
from __future__ import annotations

import json
import os
import queue
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from genom2bip.campaign import expand, read_campaign, run_job
from genom2bip.campaign.worker import TOPIC
from tests.nativekit import needs_cc

distributed = pytest.importorskip("distributed")
pytestmark = needs_cc

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "tests" / "fixtures"
DASK = [sys.executable, "-m", "dask"]  # the dask command of this Python, wherever pip put its scripts
#: Far past what a loaded machine needs: a hang fails, a slow machine does not.
PATIENCE = 900


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start(args: list[str], log: Path, env: dict) -> subprocess.Popen:
    """A process in a session of its own, so that killing its group kills a worker's nanny and worker at once."""
    return subprocess.Popen(args, stdout=log.open("w"), stderr=subprocess.STDOUT, env=env, start_new_session=True)


def start_cluster(tmp_path: Path, env: dict) -> tuple[str, list[subprocess.Popen], dict[str, subprocess.Popen]]:
    """A real ``dask scheduler`` and two ``dask worker``s (a, b) on loopback: (address, processes, workers)."""
    address = f"tcp://127.0.0.1:{free_port()}"
    processes = [start([*DASK, "scheduler", "--host", "127.0.0.1", "--port", address.rsplit(":", 1)[1],
                        "--no-dashboard"], tmp_path / "scheduler.log", env)]
    workers = {}
    for name in ("a", "b"):
        workers[name] = start([*DASK, "worker", address, "--nthreads", "1", "--host", "127.0.0.1", "--name", name,
                               "--no-dashboard"], tmp_path / f"worker-{name}.log", env)
        processes.append(workers[name])
    return address, processes, workers


def stop_cluster(processes: list[subprocess.Popen]) -> None:
    """Every process of the cluster killed with its group, and waited for."""
    for p in processes:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
        p.wait()


@pytest.fixture
def cluster(tmp_path):
    """``(address, client, workers by name, gate file)``: a scheduler and two workers on loopback."""
    gate = tmp_path / "gate"
    address, processes, workers = start_cluster(tmp_path, {**os.environ, "GENOM2BIP_TEST_GATE": str(gate)})
    client = None
    try:
        client = distributed.Client(address, timeout=PATIENCE)
        client.wait_for_workers(2, timeout=PATIENCE)
        yield address, client, workers, gate
    finally:
        if client is not None:
            client.close()
        stop_cluster(processes)


def test_a_worker_killed_mid_job_loses_nothing_and_changes_no_verdict(tmp_path, cluster):
    address, client, workers, gate = cluster
    path = tmp_path / "c.yaml"
    path.write_text(f"""campaign: killed
models:
  cruise:
    paths: [{FIXTURES / 'timed' / 'Cruise.gen'}]
    timed: {{observers: {FIXTURES / 'timed' / 'observers.yaml'}}}
  ndd: {{paths: [{ROOT / 'descriptions' / 'dala' / 'NDD.gen'}]}}
  gate: {{paths: [{FIXTURES / 'campaign' / 'Gate.bip'}]}}
checks:
  - {{check: deadlock, model: gate, options: {{externs: {FIXTURES / 'campaign' / 'gate.py'}}}}}
  - {{check: observer, model: cruise, vary: {{define.PERIOD: [10, 12, 15]}}}}
  - {{check: property, model: ndd, files: [{FIXTURES / 'verify' / 'goto_after_setspeed.mcl'}]}}
""")
    jobs = expand(read_campaign(path)).jobs
    assert len(jobs) == 13
    held = next(j for j in jobs if j.model == "gate")
    starts: queue.Queue = queue.Queue()
    client.subscribe_topic(TOPIC, lambda event: starts.put(event[1]))
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "genom2bip", "campaign", str(path), "--scheduler", address,
                             "-o", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        seen = []
        while not any(m["job"] == held.id for m in seen):  # the held job has started: it waits at the gate there
            seen.append(starts.get(timeout=PATIENCE))
        victim = next(m["worker"] for m in seen if m["job"] == held.id)
        name = client.scheduler_info()["workers"][victim]["name"]
        os.killpg(workers[name].pid, signal.SIGKILL)
        workers[name].wait()
        gate.write_text("")  # the job may pass now: on the worker left
        stdout, stderr = proc.communicate(timeout=PATIENCE)
    finally:
        if proc.poll() is None:  # a failed step above: do not leave the command behind
            proc.kill()
            proc.communicate()
    assert proc.returncode == 4, stderr  # Cruise's observers are violated at some periods

    records = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert sorted(r["job"] for r in records) == sorted(j.id for j in jobs)  # every job, exactly once
    assert all(r["status"] == "done" for r in records)
    again = next(r for r in records if r["job"] == held.id)
    assert again["worker"] != victim and again["verdict"] == "violated"  # Gate.bip ends in a deadlock
    while not starts.empty():
        seen.append(starts.get())
    assert [m["worker"] == victim for m in seen if m["job"] == held.id][:2] == [True, False]
    assert "13 jobs: " in stdout

    alone = {job.id: run_job(job)["verdict"] for job in jobs}
    assert {r["job"]: r["verdict"] for r in records} == alone
    assert set(alone.values()) == {"holds", "violated"}
