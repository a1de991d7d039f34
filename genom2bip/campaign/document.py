"""``genom2bip campaign --json``: the campaign's answer as one JSON document (genom2bip/cli/campaign_schema.json).

The document says what the table and the last lines say, for a script: each job with its answer and its record
(the line of results.jsonl), the answers counted, what this run did, the pictures drawn, what a stop left undone,
and the exit status with its meaning (docs/output.md, ``campaign --json``).
"""
from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from typing import Any

from genom2bip.campaign.jobs import Job
from genom2bip.campaign.report import outcome


@dataclass
class CampaignAnswer:
    """What a campaign command found, gathered for its document."""

    name: str
    file: str
    jobs: list[Job]
    records: dict[str, dict[str, Any]] | None = None  # None: --list, the results are not read
    directory: str | None = None
    results: str | None = None
    ran: set[str] = field(default_factory=set)  # the jobs whose record this run wrote
    run: dict[str, Any] | None = None  # cluster, jobs_run, wall_s, job_s, cpu_s
    pictures: list[str] = field(default_factory=list)
    undone: list[str] = field(default_factory=list)  # the jobs a stop left without a record (ids)
    stopped: str | None = None  # "interrupted" (Ctrl-C), "closed" (nobody reads the output)


def _job(job: Job, answer: CampaignAnswer) -> dict[str, Any]:
    record = None if answer.records is None else answer.records.get(job.id)
    word = None if answer.records is None else (outcome(record) if record is not None else "not done")
    return {"job": job.id, "title": job.title, "model": job.model, "check": job.check, "method": job.method,
            "target": job.target, "point": dict(job.point), "answer": word, "ran": job.id in answer.ran,
            "record": record}


def document(answer: CampaignAnswer, status: int) -> dict[str, Any]:
    """The ``--json`` document of ``answer``, the command exiting with ``status``."""
    from runtime.exits import TABLE

    jobs = [_job(j, answer) for j in sorted(answer.jobs, key=lambda j: j.index)]
    counts = Counter(j["answer"] for j in jobs if j["answer"] is not None)
    return {"tool": "genom2bip campaign", "schema": 1, "campaign": answer.name, "file": answer.file,
            "listed": answer.records is None, "directory": answer.directory, "results": answer.results,
            "jobs": jobs, "counts": dict(counts.most_common()), "run": answer.run, "pictures": list(answer.pictures),
            "stopped": answer.stopped, "undone": list(answer.undone), "exit_status": status,
            "meaning": dict(TABLE).get(status, "")}
