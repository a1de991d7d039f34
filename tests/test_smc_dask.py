"""SMC on a real Dask cluster (``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1), one worker killed
while it computes a batch: the estimate is the one this process computes alone, every run counted once.

The test waits for events: the first batch back, then the victim holding a batch in progress (the scheduler says
so), before it kills it; the batches are long (runs of 2 s of model time) so that the one in progress is still
running when the kill comes.
"""
from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import pytest

from genom2bip.verify import TimeSettings, build_model
from genom2bip.verify.smc import SmcSettings, estimate, sim_config
from tests.nativekit import needs_cc
from tests.test_campaign_dask import PATIENCE, start_cluster, stop_cluster

distributed = pytest.importorskip("distributed")
pytestmark = needs_cc

ROOT = Path(__file__).resolve().parents[1]
SMC = ROOT / "tests" / "fixtures" / "smc"


class Killing:
    """A runner that passes the batches of ``runner`` on, and kills a worker busy with one after the first."""

    def __init__(self, runner, workers: dict) -> None:
        self.runner, self.workers = runner, workers
        self.name, self.workers_count = runner.name, runner.workers
        self.victim: str | None = None
        self.held: list = []

    def run(self, seed, ranges):
        for k, batch in enumerate(self.runner.run(seed, ranges)):
            if k == 0:
                self.kill()
            yield batch

    def kill(self) -> None:
        client = self.runner.client
        deadline = time.monotonic() + PATIENCE
        while time.monotonic() < deadline:  # a worker with a batch in progress (the next ones were submitted)
            busy = {w: keys for w, keys in client.processing().items() if keys}
            if busy:
                break
            time.sleep(0.01)
        address, self.held = next(iter(busy.items()))
        name = client.scheduler_info()["workers"][address]["name"]
        self.victim = name
        os.killpg(self.workers[name].pid, signal.SIGKILL)
        self.workers[name].wait()


def test_a_worker_killed_mid_estimate_gives_the_undisturbed_estimate(tmp_path):
    from genom2bip.campaign.cluster import ClusterSpec
    from genom2bip.campaign.params import ModelParams
    from genom2bip.campaign.smc import DaskRunner

    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    address, processes, workers = start_cluster(tmp_path, env)
    runner = None
    try:
        platform = str(SMC / "slack.yaml")
        model = build_model([SMC / "Slack.gen"], time=TimeSettings(platform=platform))
        settings = SmcSettings(horizon_us=2_000_000, runs=160, batch=16, seed=3)
        alone = estimate(model, settings)
        config = sim_config(model, settings)
        params = ModelParams(paths=(str(SMC / "Slack.gen"),), timed=True, platform=platform)
        runner = DaskRunner(ClusterSpec(scheduler=address, connect_timeout=PATIENCE), params, config)
        runner.client.wait_for_workers(2, timeout=PATIENCE)
        runner.workers = 2
        killing = Killing(runner, workers)
        disturbed = estimate(model, settings, runner=killing, config=config)
    finally:
        if runner is not None:
            runner.close()
        stop_cluster(processes)
    assert killing.victim in ("a", "b") and killing.held  # killed while it computed a batch
    assert workers[killing.victim].returncode is not None
    assert disturbed.runs == alone.runs == 160
    assert [(r.hits, r.first_run) for r in disturbed.results] == [(r.hits, r.first_run) for r in alone.results]
    assert [d.counts for d in disturbed.responses] == [d.counts for d in alone.responses]
    assert alone.results[0].hits > 0
