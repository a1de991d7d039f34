"""What a person sees of a campaign: a line per job as it ends, a progress line on a terminal (done, running,
failed, time left by the average), and the summary table at the end."""
from __future__ import annotations

import sys
import time
from collections import Counter
from typing import Any, TextIO

from genom2bip.campaign.jobs import Job


def human_bytes(n: float) -> str:
    """``98.2 MB``: a memory figure as the table shows it."""
    for unit in ("B", "KB", "MB"):
        if n < 1024:
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} GB"


def outcome(record: dict[str, Any] | None) -> str:
    """A record's answer in one word: its verdict when done, else its status (failed, crashed); "-" if none."""
    if record is None:
        return "-"
    return record.get("verdict") or record.get("status") or "?"


def _states(record: dict[str, Any]) -> str:
    figures = record.get("figures") or {}
    return f"{figures['states']:,}" if figures.get("states") else "-"


class Display:
    """The running campaign on a terminal: each job's line on ``out``, a progress line on ``err`` (a terminal)."""

    def __init__(self, total: int, out: TextIO | None = None, err: TextIO | None = None) -> None:
        self.total, self.out, self.err = total, out or sys.stdout, err or sys.stderr
        self.tty = getattr(self.err, "isatty", lambda: False)()
        self.running: dict[str, str] = {}
        self.done = self.failed = 0
        self.start = time.monotonic()
        self.width = 0

    def started(self, job_id: str, worker: str) -> None:
        self.running[job_id] = worker
        self._draw()

    def finished(self, job: Job, record: dict[str, Any]) -> None:
        """A job's line: its answer, what it is, its figures and where it ran."""
        self.running.pop(job.id, None)
        self.done += 1
        self.failed += record.get("status") != "done"
        self._clear()
        where = f", {record['host']}" if record.get("host") else ""
        figures = (f"{_states(record)} states, {record['seconds']:.1f} s{where}" if record.get("seconds") is not None
                   else "no figures")
        print(f"{outcome(record):<12} {job.title}  ({figures})", file=self.out, flush=True)
        if record.get("status") != "done" and record.get("message"):
            print(f"{'':12} {record['message'].splitlines()[0]}", file=self.out, flush=True)
        self._draw()

    def line(self) -> str:
        """``12/25 done, 2 running, 1 failed, about 0:32 left`` (by the average time of the jobs done so far)."""
        text = f"{self.done}/{self.total} done, {len(self.running)} running, {self.failed} failed"
        if self.done and self.done < self.total:
            left = (time.monotonic() - self.start) / self.done * (self.total - self.done)
            text += f", about {int(left // 60)}:{int(left % 60):02d} left"
        return text

    def _draw(self) -> None:
        if self.tty:
            line = self.line()
            self.err.write("\r" + line + " " * max(0, self.width - len(line)))
            self.err.flush()
            self.width = len(line)

    def _clear(self) -> None:
        if self.tty and self.width:
            self.err.write("\r" + " " * self.width + "\r")
            self.err.flush()
            self.width = 0

    def close(self) -> None:
        self._clear()


#: Columns the reason of a job that did not answer takes in the table (results.jsonl has the whole message).
WHY = 72


def why(record: dict[str, Any] | None) -> str:
    """Why a job gave no answer, in a few words: the limit that stopped an inconclusive search (with what it had
    reached), the first line of a failure's message; "-" for a job that holds or is violated."""
    if record is None:
        return "not run yet"
    answer = outcome(record)
    if answer in ("holds", "violated"):
        return "-"
    message = (record.get("message") or "").strip().splitlines()
    if answer == "inconclusive":
        limit = record.get("limit")
        text = f"stopped by {limit}" if limit else ""
        if message and message[0] != limit:
            text = f"{text}: {message[0]}" if text else message[0]
        text = text or "stopped before an answer"
    else:
        text = message[0] if message else answer
    return text if len(text) <= WHY else text[:WHY - 3] + "..."


def summary(jobs: list[Job], records: dict[str, dict[str, Any]], out: TextIO | None = None) -> Counter:
    """The table of every job (model, check, method, target, point, answer, states, seconds, memory, host, and why
    a job gave no answer); the answers counted."""
    out = out or sys.stdout
    header = ("model", "check", "method", "target", "point", "answer", "states", "seconds", "memory", "host", "why")
    rows = []
    counts: Counter = Counter()
    for job in sorted(jobs, key=lambda j: j.index):
        record = records.get(job.id)
        answer = outcome(record) if record is not None else "not done"
        counts[answer] += 1
        seconds = record.get("seconds") if record else None
        memory = record.get("peak_memory") if record else None
        point = " ".join(f"{k}={v}" for k, v in job.point) or "-"
        rows.append((job.model, job.check, job.method, job.target, point, answer,
                     _states(record) if record else "-", f"{seconds:.2f}" if seconds is not None else "-",
                     human_bytes(memory) if memory else "-", (record or {}).get("host") or "-", why(record)))
    widths = [max(len(str(r[i])) for r in (header, *rows)) for i in range(len(header))]
    right = {6, 7, 8}
    for row in (header, *rows):
        cells = [str(c).rjust(w) if i in right else str(c).ljust(w) for i, (c, w) in enumerate(zip(row, widths))]
        print("  ".join(cells).rstrip(), file=out)
    print(f"{len(jobs)} jobs: " + ", ".join(f"{n} {word}" for word, n in counts.most_common()), file=out)
    return counts


def values_table(jobs: list[Job], records: dict[str, dict[str, Any]], out: TextIO | None = None) -> None:
    """The values of the jobs that give some (response times): a row per model and figure (a task), a column per
    point of the axes; a word where there is no number (``unbounded``), ``-`` where the job has no record."""
    out = out or sys.stdout
    given = [j for j in sorted(jobs, key=lambda j: j.index) if (records.get(j.id) or {}).get("values")]
    if not given:
        return
    columns = list(dict.fromkeys(" ".join(f"{k}={v}" for k, v in j.point) or "-" for j in given))
    rows: dict[tuple[str, str, str], dict[str, str]] = {}
    for job in given:
        column = " ".join(f"{k}={v}" for k, v in job.point) or "-"
        for name, value in records[job.id]["values"].items():
            text = f"{value:g} ms" if isinstance(value, (int, float)) else str(value)
            rows.setdefault((job.model, job.check, name), {})[column] = text
    header = ("model", "check", "task or service", *columns)
    lines = [(*key, *(cells.get(c, "-") for c in columns)) for key, cells in rows.items()]
    widths = [max(len(str(r[i])) for r in (header, *lines)) for i in range(len(header))]
    print(file=out)
    for row in (header, *lines):
        cells = [str(c).rjust(w) if i >= 3 else str(c).ljust(w) for i, (c, w) in enumerate(zip(row, widths))]
        print("  ".join(cells).rstrip(), file=out)
