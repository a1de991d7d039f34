"""Where a campaign's results go: one JSON line per job in ``results.jsonl``, each job's whole result in
``jobs/<id>.json``, pictures beside them.  Written by the client alone, as each result comes back.

Each line is appended and flushed to the disk before the next one, so a
campaign killed at any moment keeps every result it announced.  A line that
is not a job's record as this module writes it (cut by a kill, edited by
hand, written by something else) is never deleted: when the directory is
opened it is moved, as it was, to ``results.unreadable.jsonl`` beside it, and
its job runs again.  A job's last line is its result: a job run again
appends one, and the file is rewritten with one line per job when the
campaign ends.  A lock keeps two campaigns from writing to one directory at
once.
"""
from __future__ import annotations

import fcntl
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from runtime.errors import Genom2bipError

RESULTS = "results.jsonl"
#: Where the lines of ``results.jsonl`` that are not a job's record are kept, as they were.
UNREADABLE = "results.unreadable.jsonl"
#: What a record's ``status`` may be: the worker's ``done`` and ``failed``, the client's ``crashed`` and ``timeout``.
STATUSES = ("done", "failed", "crashed", "timeout")
JOBS = "jobs"
LOCK = ".lock"


class OutputError(Genom2bipError):
    """The output directory cannot be used (another campaign writes to it, it is not a directory)."""


@dataclass
class Output:
    """An open output directory: the records already there (by job id) and the lock held while it is open."""

    directory: Path
    records: dict[str, dict[str, Any]] = field(default_factory=dict)
    dropped: int = 0  # lines that were not records (a kill during a write, an edit), moved to UNREADABLE
    _lock: Any = None

    @property
    def results(self) -> Path:
        return self.directory / RESULTS

    @property
    def unreadable(self) -> Path:
        return self.directory / UNREADABLE

    @classmethod
    def peek(cls, directory: str | Path) -> dict[str, dict[str, Any]]:
        """The records ``directory`` holds, read without creating or changing anything."""
        out = cls(Path(directory))
        if out.results.is_file():
            out._read(rewrite=False)
        return out.records

    @staticmethod
    def check(directory: str | Path) -> None:
        """OutputError when ``directory`` cannot be the output, found without creating or changing anything: so
        that the cluster is not started for a campaign whose results could not be kept."""
        directory = Path(directory)
        if os.path.lexists(directory) and not directory.is_dir():
            raise OutputError(f"{directory}: not a directory")
        for name, kind in ((RESULTS, "a file"), (JOBS, "a directory"), (LOCK, "a file")):
            _check_kind(directory / name, kind)
        missing = _missing_parents(directory)
        existing = missing[-1].parent if missing else directory
        if not existing.is_dir():
            raise OutputError(f"{directory}: cannot be used as the output directory: {existing} is not a directory")
        if not os.access(existing, os.W_OK | os.X_OK):
            raise OutputError(f"{directory}: cannot be used as the output directory: {existing} cannot be written")

    @classmethod
    def open(cls, directory: str | Path) -> "Output":
        """Create or reopen ``directory``: lock it, read the records it holds, drop a line a kill cut short."""
        directory = Path(directory)
        cls.check(directory)
        created = [directory / JOBS] * (not os.path.lexists(directory / JOBS)) + _missing_parents(directory)
        try:
            directory.mkdir(parents=True, exist_ok=True)
            (directory / JOBS).mkdir(exist_ok=True)
            lock = open(directory / LOCK, "a+")
        except OSError as exc:
            for made in created:  # what this call made, newest first; nothing of what was there
                _remove_empty(made)
            raise OutputError(f"{directory}: cannot be used as the output directory: {_why(exc)}") from None
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            lock.close()
            raise OutputError(f"{directory}: another campaign is writing to this directory") from None
        out = cls(directory, _lock=lock)
        out._read()
        return out

    def close(self) -> None:
        """Keep one line per job (a job run again with --retry-failed appended a second one), then unlock."""
        if self._lock is not None:
            self._compact()
            self._lock.close()
            self._lock = None

    def _compact(self) -> None:
        if not self.results.exists():
            return
        lines = self.results.read_text(encoding="utf-8").splitlines(keepends=True)
        if len(lines) > len(self.records):
            _replace(self.results, "".join(json.dumps(r) + "\n" for r in self.records.values()))

    def _read(self, rewrite: bool = True) -> None:
        """The records of ``results.jsonl``; with ``rewrite``, a line that is not one is moved to
        :data:`UNREADABLE` (appended there first, then the file rewritten without it)."""
        if not self.results.exists():
            return
        try:
            lines = self.results.read_text(encoding="utf-8", errors="surrogateescape").splitlines(keepends=True)
        except OSError as exc:
            raise OutputError(f"cannot read {self.results}: {_why(exc)}") from None
        kept, aside = [], []
        for line in lines:
            try:
                line.encode("utf-8")  # bytes that are not UTF-8 are kept aside as they were, never rewritten
                record = json.loads(line) if line.endswith("\n") else None
            except (ValueError, RecursionError):  # JSONDecodeError, UnicodeEncodeError; 100,000 nested [
                record = None
            if record_problem(record) is not None:
                aside.append(line if line.endswith("\n") else line + "\n")
                continue
            self.records.pop(record["job"], None)  # the last line of a job is its result, in the order written
            self.records[record["job"]] = record
            kept.append(line)
        self.dropped = len(aside)
        if aside and rewrite:
            with open(self.unreadable, "a", encoding="utf-8", errors="surrogateescape") as f:
                f.write("".join(aside))
                f.flush()
                os.fsync(f.fileno())
            _replace(self.results, "".join(kept))

    def write(self, record: dict[str, Any]) -> dict[str, Any]:
        """Write one job's record: its whole result to ``jobs/<id>.json`` first, then its line; the line written.

        A write that fails (a full disk) raises OutputError and leaves ``results.jsonl`` as it was before it:
        no line cut half-way, no temporary file."""
        result = record.pop("result", None)
        line = dict(record)
        line["result"] = line["trace"] = None
        if result is not None:
            path = Path(JOBS) / f"{record['job']}.json"
            _replace(self.directory / path, json.dumps(result, indent=1) + "\n")
            line["result"] = str(path)
            line["trace"] = str(path) if result.get("trace") else None
        text = json.dumps(line, sort_keys=False) + "\n"
        try:
            with open(self.results, "ab") as f:
                size = f.tell()
                try:
                    f.write(text.encode("utf-8"))
                    f.flush()
                    os.fsync(f.fileno())
                except OSError:
                    f.truncate(size)  # the line cut by the failure goes; the lines before it stay
                    raise
        except OSError as exc:
            raise OutputError(f"cannot write {self.results}: {_why(exc)}; the results written before are kept, "
                              "the same command runs the rest") from None
        self.records.pop(record["job"], None)
        self.records[record["job"]] = line
        return line


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def record_problem(record: Any) -> str | None:
    """Why ``record`` (a line of ``results.jsonl``, read) is not a job's record as :meth:`Output.write` writes it
    and the summary, the pictures and a resumed run read it; None when it is one."""
    if not isinstance(record, dict) or not isinstance(record.get("job"), str):
        return "not a job's record"
    if record.get("status") not in STATUSES:
        return f"status: one of {', '.join(STATUSES)} expected"
    if not isinstance(record.get("verdict"), str if record["status"] == "done" else (str, type(None))):
        return "verdict: a word expected"
    for key in ("message", "host", "worker", "limit", "result", "trace"):
        if record.get(key) is not None and not isinstance(record[key], str):
            return f"{key}: a string expected"
    for key in ("seconds", "cpu_seconds", "peak_memory"):
        if record.get(key) is not None and not _number(record[key]):
            return f"{key}: a number expected"
    figures, values = record.get("figures"), record.get("values")
    if figures is not None and not (isinstance(figures, dict) and (
            figures.get("states") is None or _number(figures["states"]))):
        return "figures: a mapping expected"
    if values is not None and not (isinstance(values, dict) and all(
            _number(v) or isinstance(v, str) for v in values.values())):
        return "values: a mapping of numbers or words expected"
    return None


def _replace(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (a temporary file renamed over it); on a failure (a full disk) the
    temporary file is removed, ``path`` is left as it was and OutputError says why."""
    partial = path.with_name(f".{path.name}.{os.getpid()}.partial")
    try:
        with open(partial, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(partial, path)
    except OSError as exc:
        partial.unlink(missing_ok=True)
        raise OutputError(f"cannot write {path}: {_why(exc)}; it is left as it was") from None


def _why(exc: OSError) -> str:
    return exc.strerror or str(exc)


def _check_kind(path: Path, kind: str) -> None:
    """OutputError unless ``path`` is absent or is ``kind`` ("a file", "a directory")."""
    if not os.path.lexists(path):
        return
    if path.is_symlink() and not path.exists():
        raise OutputError(f"{path}: a link to nothing where the campaign keeps {kind}")
    if kind == "a directory" and not path.is_dir():
        raise OutputError(f"{path}: not a directory (the campaign keeps each job's result in it): move it away")
    if kind == "a file" and not path.is_file():
        raise OutputError(f"{path}: not a regular file (the campaign keeps {path.name} there): move it away")


def _missing_parents(directory: Path) -> list[Path]:
    """The directories ``mkdir(parents=True)`` would make for ``directory``, newest first."""
    missing = []
    for path in [directory, *directory.parents]:
        if os.path.lexists(path):
            break
        missing.append(path)
    return missing


def _remove_empty(path: Path) -> None:
    try:
        path.rmdir()
    except OSError:
        pass
