"""Jobs spread over Dask workers: a local cluster (one worker process per core, listening on loopback) or a running
cluster (``--scheduler tcp://HOST:PORT``); each result written as it comes back.

Dask gives what a campaign needs: a job whose worker dies is run again on
another worker (a job that keeps killing its workers is given up as crashed:
``distributed.scheduler.allowed-failures``); the client keeps one future per
job, so each result comes back once.  A worker tells when it starts a job
(an event on :data:`~genom2bip.campaign.worker.TOPIC`), which the progress
line counts as running.

Dask counts a worker's death against every job the worker holds, the one it
runs and those waiting there for their turn, so a job waiting behind one that
crashes its worker reaches the limit of deaths too.  The client knows which
jobs started (the events): a job given up by Dask having started no more
times than the deaths allowed was not the cause, and is submitted again (at
most :data:`RESUBMITS` times).
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
#: Times a job given up by Dask without having started as often as its workers died is submitted again.
RESUBMITS = 3
#: Seconds between two looks at the running jobs' time limits.
WATCH_PERIOD = 0.5
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
    closed: bool = False  # stopped because the output's reader went away (``campaign FILE | head``)
    running: list[str] = field(default_factory=list)  # the jobs under way when it stopped (ids)
    seconds: float = 0.0
    where: str = ""  # the cluster, in words


#: Dask settings of a local cluster: a job that keeps killing its workers is given up; no HTTP routes (no dashboard,
#: no metrics, no health page) on the scheduler nor on the workers.
LOCAL_CONFIG: dict[str, Any] = {"distributed.scheduler.allowed-failures": LOCAL_ALLOWED_FAILURES,
                                "distributed.scheduler.http.routes": [], "distributed.worker.http.routes": []}


#: Where the HTTP servers of a local cluster's scheduler and workers listen: loopback, a port of their own.
HTTP_LOOPBACK = f"{LOOPBACK}:0"


def local_cluster_arguments(spec: ClusterSpec) -> dict[str, Any]:
    """``LocalCluster``'s arguments for ``spec``: one single-threaded worker process per job slot, the scheduler's and
    the workers' connections on ``spec.listen``, and no dashboard.

    Dask's scheduler and workers start an HTTP server whatever the dashboard options say; a worker's binds to the
    worker's own host unless told where, which ``--listen 0.0.0.0`` would open to every interface.  Both are bound
    to loopback (:data:`HTTP_LOOPBACK`) whatever ``--listen`` says, the workers' by :func:`loopback_nanny`
    (LocalCluster's own ``worker_dashboard_address`` would turn the worker's dashboard on); with no routes
    (:data:`LOCAL_CONFIG`) they serve nothing, and the scheduler's is stopped as soon as it has started.
    """
    return {"n_workers": spec.workers or os.cpu_count() or 1, "threads_per_worker": 1, "processes": True,
            "host": spec.listen, "scheduler_port": 0, "silence_logs": logging.CRITICAL,
            "dashboard_address": HTTP_LOOPBACK, "scheduler_kwargs": {"dashboard": False},
            "worker_class": loopback_nanny(),
            "preload": ["genom2bip.campaign.session"]}  # each worker in a session of its own


def loopback_nanny() -> type:
    """Dask's ``Nanny`` whose worker has no dashboard and keeps its HTTP server on loopback."""
    from distributed import Nanny

    class LoopbackNanny(Nanny):
        """A nanny starting a worker whose HTTP server listens on :data:`HTTP_LOOPBACK`, dashboard off."""

        def __init__(self, *args: Any, **kwargs: Any) -> None:
            kwargs.update(dashboard_address=HTTP_LOOPBACK, dashboard=False)
            super().__init__(*args, **kwargs)

    return LoopbackNanny


def connect(spec: ClusterSpec):
    """``(client, cluster)``: a client of the running scheduler (cluster None), or of a new local cluster."""
    import dask
    from distributed import Client, LocalCluster

    from genom2bip.campaign.frames import bound_frames

    bound_frames()  # a peer announcing exabytes is refused before they are allocated
    if spec.scheduler:
        return Client(spec.scheduler, security=spec.security(), timeout=spec.connect_timeout), None
    with dask.config.set(LOCAL_CONFIG):
        cluster = LocalCluster(**local_cluster_arguments(spec))
    http = getattr(cluster.scheduler, "http_server", None)
    if http is not None:
        http.stop()
    return Client(cluster), cluster


def describe(client, cluster) -> str:
    """The cluster in a few words: where its scheduler is and how many workers it has."""
    info = client.scheduler_info()
    workers = info.get("workers", {})
    threads = sum(w.get("nthreads", 1) for w in workers.values())
    kind = "local cluster" if cluster is not None else "cluster"
    return f"{kind} {info.get('address', '?')}: {len(workers)} workers, {threads} threads"


def run(jobs: list[Job], client, write: Callable[[dict[str, Any]], dict[str, Any]], display,
        closed: Callable[[], bool] = lambda: False) -> Run:
    """Submit every job, write each record as it comes back, tell ``display``; Ctrl-C stops with what is done, and
    so does ``closed()`` becoming true (the output has lost its reader: nobody would see the rest).

    A job past its ``timeout`` is cancelled and recorded as such, and its worker restarted (the only way to stop
    a search in another process); the others go on.
    """
    from distributed import as_completed

    out = Run()
    if closed():
        out.closed, out.undone = True, sorted(jobs, key=lambda j: j.index)
        return out
    token = uuid.uuid4().hex[:8]  # another run's keys never collide with this one's on a shared scheduler
    lock = threading.Lock()
    by_id = {job.id: job for job in jobs}
    started_at: dict[str, tuple[float, dict]] = {}
    starts: dict[str, int] = {}  # per job: times it started in its current submission
    resubmitted: dict[str, int] = {}
    recorded: set[str] = set()

    def keep(job: Job, record: dict[str, Any]) -> None:
        """Write a record, once per job (called with ``lock`` held)."""
        if job.id not in recorded:
            recorded.add(job.id)
            line = write(record)
            out.written.append(line)
            display.finished(job, line)

    def started(event) -> None:
        _, message = event
        if isinstance(message, dict) and message.get("job") in by_id:
            with lock:
                started_at[message["job"]] = (time.monotonic(), message)
                starts[message["job"]] = starts.get(message["job"], 0) + 1
                display.started(message["job"], message.get("worker", ""))

    client.subscribe_topic(TOPIC, started)
    # the futures of the jobs not done: one taken is released at once, else Dask would compute it again when the
    # worker holding its result dies
    remaining = {client.submit(run_job, job, key=f"genom2bip-{job.id}-{token}", pure=False): job for job in jobs}
    future_of = {job.id: f for f, job in remaining.items()}
    futures_done = as_completed(remaining)
    stop = threading.Event()

    def watch() -> None:
        """Stop the jobs past their time limit."""
        while not stop.wait(WATCH_PERIOD):
            now = time.monotonic()
            with lock:
                late = [(by_id[j], m) for j, (t, m) in started_at.items() if j not in recorded
                        and by_id[j].timeout is not None and now - t > by_id[j].timeout]
            for job, message in late:
                with lock:
                    future = future_of.get(job.id)
                if future is not None:
                    client.cancel([future])
                restarted = _restart(client, message.get("worker", ""))
                with lock:
                    keep(job, _timed_out(job, message, restarted))

    watchdog = threading.Thread(target=watch, daemon=True, name="campaign-timeouts")
    if any(job.timeout is not None for job in jobs):
        watchdog.start()
    start = time.perf_counter()
    try:
        for future in futures_done:
            job = remaining.pop(future)
            with lock:
                del future_of[job.id]
                again = _bystander(future, starts.get(job.id, 0)) and resubmitted.get(job.id, 0) < RESUBMITS
                if again:
                    resubmitted[job.id] = resubmitted.get(job.id, 0) + 1
                    starts[job.id] = 0
            record = _record(job, future) if future.status != "cancelled" else None  # cancelled: past its limit
            future.release()
            if again:
                future = client.submit(run_job, job, key=f"genom2bip-{job.id}-{token}-{resubmitted[job.id]}",
                                       pure=False)
                with lock:
                    remaining[future] = job
                    future_of[job.id] = future
                futures_done.add(future)
            elif record is not None:
                with lock:
                    keep(job, record)
            if remaining and closed():
                out.closed = True
                break
    except KeyboardInterrupt:
        out.interrupted = True
    finally:
        if out.interrupted or out.closed:  # every job without a record, the one taken from ``remaining`` included
            with lock:
                out.undone = sorted((j for j in jobs if j.id not in recorded), key=lambda j: j.index)
                out.running = [j.id for j in out.undone if j.id in started_at]
            client.cancel(list(remaining))
        stop.set()
        if watchdog.is_alive():
            watchdog.join()
        out.seconds = time.perf_counter() - start
        try:
            client.unsubscribe_topic(TOPIC)
        except Exception:  # noqa: BLE001 - a client closing after Ctrl-C
            pass
    return out


def _bystander(future, starts: int) -> bool:
    """Whether Dask gave the job up for its workers' deaths (``KilledWorker``) though it started no more times than
    the deaths it allows: it waited on workers that another job crashed."""
    if future.status != "error":
        return False
    allowed = getattr(future.exception(), "allowed_failures", None)
    return allowed is not None and starts <= allowed


def _restart(client, worker: str) -> str:
    """Restart ``worker`` (its nanny starts a fresh process); "" when done, else why not."""
    try:
        client.restart_workers([worker])
        return ""
    except Exception as exc:  # noqa: BLE001 - a worker without a nanny, gone already: said in the record
        return f"{type(exc).__name__}: {exc}"


def _timed_out(job: Job, started: dict, restarted: str) -> dict[str, Any]:
    """The record of a job stopped past its time limit."""
    how = "its worker was restarted" if not restarted else f"its worker could not be restarted ({restarted})"
    return {"job": job.id, **job.parameters(), "host": started.get("host"), "worker": started.get("worker"),
            "pid": started.get("pid"), "status": "timeout", "verdict": None,
            "message": f"stopped past its time limit of {job.timeout:g} s; {how}", "limit": "timeout",
            "figures": None, "values": None, "result": None, "seconds": job.timeout, "cpu_seconds": None,
            "peak_memory": None}


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
            "seconds": None, "cpu_seconds": None, "peak_memory": None}
