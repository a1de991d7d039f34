"""One job, run where a Dask worker runs it (or in any process): the model built through the verification API
(kept for the next job on the same parameters), the check run, the result returned as a record.

A job never raises: bad input, a model the engine refuses, an internal error
are a record with ``status: failed`` and the message, so the campaign goes
on.  A job that kills its process (a crash in the compiled step, the memory
limit of its worker) is the scheduler's to see: it runs the job again on
another worker, and records it as crashed when it keeps killing them.
"""
from __future__ import annotations

import os
import socket
import time
import traceback
from collections import OrderedDict
from typing import Any

from genom2bip.campaign.jobs import Job
from genom2bip.campaign.params import ModelParams

#: The topic of the events a worker publishes when a job starts (the client's progress reads them).
TOPIC = "genom2bip-campaign"
#: Models kept per worker process: the jobs of one model, one after another, build it once.
KEPT_MODELS = 4
#: Share of a worker's memory limit a search may use when the campaign gives no max-memory.
MEMORY_SHARE = 0.5

_models: OrderedDict[ModelParams, Any] = OrderedDict()


def model_of(params: ModelParams):
    """The model of ``params``, built once per process (the last :data:`KEPT_MODELS` kept)."""
    model = _models.get(params)
    if model is None:
        model = params.build()
        model.flat  # noqa: B018 - flattened once, for every job on it
        _models[params] = model
        while len(_models) > KEPT_MODELS:
            _models.popitem(last=False)
    _models.move_to_end(params)
    return model


def run_job(job: Job) -> dict[str, Any]:
    """Run ``job`` here; its record: parameters, status, verdict, figures, seconds (wall clock, and the CPU time of
    the thread that ran it), peak memory, host, result."""
    from genom2bip.campaign.kinds import KINDS

    worker = _dask_worker()
    address = worker.address if worker is not None else ""
    if worker is not None:
        worker.log_event(TOPIC, {"event": "started", "job": job.id, "worker": address, "host": socket.gethostname(),
                                 "pid": os.getpid()})
    _reset_peak()
    start, cpu = time.perf_counter(), time.thread_time()
    record: dict[str, Any] = {"job": job.id, **job.parameters(), "host": socket.gethostname(), "worker": address,
                              "pid": os.getpid()}
    try:
        model = model_of(job.params)
        kind = KINDS[job.check]
        result = kind.run(model, job, _options(job, worker))
        record.update(status="done", verdict=result.verdict.value, message=result.message,
                      limit=result.limit or None, figures=result.figures.to_json(),
                      values=kind.figures(result, job) if kind.figures else None, result=result.to_json())
    except Exception as exc:  # noqa: BLE001 - recorded: the campaign goes on with the other jobs
        record.update(status="failed", verdict=None, message=failure(exc), limit=None, figures=None, values=None,
                      result=None)
        if not _expected(exc):
            record["traceback"] = traceback.format_exc(limit=-8)
    record.update(seconds=round(time.perf_counter() - start, 3), cpu_seconds=round(time.thread_time() - cpu, 3),
                  peak_memory=_peak())
    return record


def failure(exc: BaseException) -> str:
    """What went wrong, in the product's words: bad input as the command line says it, else an internal error."""
    from genom2bip.loading import InputError

    if isinstance(exc, InputError):
        return "\n".join([*exc.messages, *(g.render() for g in exc.groups)])
    if _expected(exc):
        return str(exc)
    return f"internal error: {type(exc).__name__}: {exc}"


def _expected(exc: BaseException) -> bool:
    """Bad input, a model the engine refuses, a target the variant lacks: not a bug of ours."""
    from runtime.errors import Genom2bipError

    return isinstance(exc, (Genom2bipError, LookupError))


def _options(job: Job, worker):
    """The job's search options; without max-memory, half the worker's memory limit (the whole machine's
    otherwise, as verify does), so that a search stops as inconclusive before the worker is killed for it."""
    from genom2bip.verify import SearchOptions

    options = SearchOptions(**dict(job.options))
    limit = getattr(getattr(worker, "memory_manager", None), "memory_limit", None)
    if options.max_memory_mb is None and limit:
        options.max_memory_mb = max(1, int(limit * MEMORY_SHARE) // 2**20)
    return options


def _dask_worker():
    """The Dask worker running this job, or None outside one."""
    try:
        from distributed import get_worker
        return get_worker()
    except (ImportError, ValueError):
        return None


def _reset_peak() -> None:
    """Reset the process's peak resident memory (Linux: ``clear_refs`` 5), so that it measures this job alone."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        pass


def _peak() -> int | None:
    """The process's peak resident memory since :func:`_reset_peak`, in bytes (the lifetime peak elsewhere)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        import resource
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    except (ImportError, OSError):
        return None
