"""SMC batches on Dask: the campaign's cluster (local or ``--scheduler``), one task per batch of consecutive runs.

A batch is a pure function of the model's parameters, the simulator's
configuration, the seed and its run indices: a worker builds the model once
(:func:`genom2bip.campaign.worker.model_of`) and keeps its simulator.  The
runner keeps a few batches ahead of the one it waits for and hands results
back in index order; a batch whose worker dies is computed again by another
worker (Dask reruns it), with the same runs, so nothing is counted twice or
lost and the estimate is the one of an undisturbed run.
"""
from __future__ import annotations

import hashlib
import pickle
import uuid
from collections import OrderedDict, deque
from typing import Any, Iterable, Iterator

from genom2bip.campaign.cluster import ClusterSpec, connect, describe
from genom2bip.campaign.params import ModelParams

#: Batches submitted ahead of the one the estimate waits for, per worker.
AHEAD_PER_WORKER = 2
#: Simulators kept per worker process.
KEPT = 4

_sims: OrderedDict[tuple[ModelParams, str], Any] = OrderedDict()


def config_key(config) -> str:
    """A digest of a simulator configuration (what a worker's cache is keyed by)."""
    return hashlib.sha256(pickle.dumps(config)).hexdigest()[:16]


def smc_batch(params: ModelParams, key: str, config, seed: int, first: int, count: int):
    """Runs ``first .. first + count - 1`` of ``seed`` on the model of ``params`` (a
    :class:`~genom2bip.verify.smc.BatchResult`)."""
    from genom2bip.campaign.worker import model_of
    from genom2bip.verify.smc import run_batch, simulator

    sim = _sims.get((params, key))
    if sim is None:
        sim, _ = simulator(model_of(params), config)
        _sims[(params, key)] = sim
        while len(_sims) > KEPT:
            _sims.popitem(last=False)
    _sims.move_to_end((params, key))
    return run_batch(sim, seed, first, count)


class DaskRunner:
    """Batches on a Dask cluster, read back in index order."""

    def __init__(self, spec: ClusterSpec, params: ModelParams, config) -> None:
        self.params, self.config, self.key = params, config, config_key(config)
        self.client, self.cluster = connect(spec)
        self.name = describe(self.client, self.cluster)
        self.workers = max(1, len(self.client.scheduler_info().get("workers", {})))
        self.token = uuid.uuid4().hex[:8]

    def run(self, seed: int, ranges: Iterable[tuple[int, int]]) -> Iterator:
        ranges = iter(ranges)
        queue: deque = deque()

        def submit() -> None:
            r = next(ranges, None)
            if r is not None:
                queue.append(self.client.submit(smc_batch, self.params, self.key, self.config, seed, r[0], r[1],
                                                key=f"genom2bip-smc-{self.token}-{seed}-{r[0]}", pure=False))

        for _ in range(AHEAD_PER_WORKER * self.workers):
            submit()
        try:
            while queue:
                future = queue.popleft()
                result = future.result()
                future.release()
                submit()
                yield result
        finally:
            if queue:
                self.client.cancel(list(queue))

    def close(self) -> None:
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()
