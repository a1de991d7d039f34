"""Jobs spread over Dask workers: a local cluster (one worker process per core, listening on loopback) or a running
cluster (``--scheduler tcp://HOST:PORT``); each result written as it comes back.

Dask gives what a campaign needs: a job whose worker dies is run again on
another worker (a job that keeps killing its workers is given up as crashed:
``distributed.scheduler.allowed-failures``); the client keeps one future per
job, so each result comes back once.  A worker tells when it starts a job
(an event on :data:`~genom2bip.campaign.worker.TOPIC`), which the progress
line counts as running.
"""
from __future__ import annotations

import logging
import os
import threading
import time
import uuid
from dataclasses import dataclass, field
from typing import Any, Callable

from genom2bip.campaign.jobs import Job
from genom2bip.campaign.worker import TOPIC, run_job

#: A job whose worker dies is run again; one that has killed this many workers more is recorded as crashed.
LOCAL_ALLOWED_FAILURES = 2
#: Where a local cluster listens unless told otherwise.
LOOPBACK = "127.0.0.1"


@dataclass
class ClusterSpec:
    """Which cluster: a running one's scheduler address (and TLS files), or a local one of ``workers`` processes."""

    scheduler: str | None = None
    workers: int | None = None  # local cluster: None is one per core
    listen: str = LOOPBACK
    tls_ca_file: str | None = None
    tls_cert: str | None = None
    tls_key: str | None = None
    connect_timeout: float = 30.0  # seconds to reach a running scheduler

    def security(self):
        """Dask's ``Security`` for the TLS files given, else None (plain TCP)."""
        if not (self.tls_ca_file or self.tls_cert or self.tls_key):
            return None
        from distributed.security import Security

        return Security(tls_ca_file=self.tls_ca_file, tls_client_cert=self.tls_cert, tls_client_key=self.tls_key,
                        require_encryption=True)


@dataclass
class Run:
    """What happened: the records written in this run, the jobs left undone when it was interrupted."""

    written: list[dict[str, Any]] = field(default_factory=list)
    undone: list[Job] = field(default_factory=list)
    interrupted: bool = False
    seconds: float = 0.0
    where: str = ""  # the cluster, in words


def connect(spec: ClusterSpec):
    """``(client, cluster)``: a client of the running scheduler (cluster None), or of a new local cluster."""
    import dask
    from distributed import Client, LocalCluster

    if spec.scheduler:
        return Client(spec.scheduler, security=spec.security(), timeout=spec.connect_timeout), None
    workers = spec.workers or os.cpu_count() or 1
    with dask.config.set({"distributed.scheduler.allowed-failures": LOCAL_ALLOWED_FAILURES}):
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host=spec.listen,
                               scheduler_port=0, dashboard_address=None, silence_logs=logging.CRITICAL)
    return Client(cluster), cluster


def describe(client, cluster) -> str:
    """The cluster in a few words: where its scheduler is and how many workers it has."""
    info = client.scheduler_info()
    workers = info.get("workers", {})
    threads = sum(w.get("nthreads", 1) for w in workers.values())
    kind = "local cluster" if cluster is not None else "cluster"
    return f"{kind} {info.get('address', '?')}: {len(workers)} workers, {threads} threads"


def run(jobs: list[Job], client, write: Callable[[dict[str, Any]], dict[str, Any]], display) -> Run:
    """Submit every job, write each record as it comes back, tell ``display``; Ctrl-C stops with what is done."""
    from distributed import as_completed

    out = Run()
    token = uuid.uuid4().hex[:8]  # another run's keys never collide with this one's on a shared scheduler
    lock = threading.Lock()
    by_id = {job.id: job for job in jobs}

    def started(event) -> None:
        _, message = event
        if isinstance(message, dict) and message.get("job") in by_id:
            with lock:
                display.started(message["job"], message.get("worker", ""))

    client.subscribe_topic(TOPIC, started)
    futures = {client.submit(run_job, job, key=f"genom2bip-{job.id}-{token}", pure=False): job for job in jobs}
    remaining = dict(futures)
    start = time.perf_counter()
    try:
        for future in as_completed(futures):
            job = remaining.pop(future)
            record = _record(job, future)
            line = write(record)
            out.written.append(line)
            with lock:
                display.finished(job, line)
    except KeyboardInterrupt:
        out.interrupted = True
        out.undone = sorted(remaining.values(), key=lambda j: j.index)
        client.cancel(list(remaining))
    finally:
        out.seconds = time.perf_counter() - start
        try:
            client.unsubscribe_topic(TOPIC)
        except Exception:  # noqa: BLE001 - a client closing after Ctrl-C
            pass
    return out


def _record(job: Job, future) -> dict[str, Any]:
    """The job's record from its future: the worker's, or (its workers died, or it could not run) a crash."""
    if future.status == "finished":
        return future.result()
    exc = future.exception()
    name = type(exc).__name__
    message = str(exc).split(". ")[0] if name == "KilledWorker" else f"{name}: {exc}"
    return {"job": job.id, **job.parameters(), "host": None, "worker": None, "pid": None, "status": "crashed",
            "verdict": None, "message": f"the job's worker process died each time it ran it ({message})"
            if name == "KilledWorker" else message, "limit": None, "figures": None, "values": None, "result": None,
            "seconds": None, "peak_memory": None}
