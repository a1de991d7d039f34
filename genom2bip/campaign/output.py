"""Where a campaign's results go: one JSON line per job in ``results.jsonl``, each job's whole result in
``jobs/<id>.json``, pictures beside them.  Written by the client alone, as each result comes back.

Each line is appended and flushed to the disk before the next one, so a
campaign killed at any moment keeps every result it announced; a line cut by
the kill is dropped when the directory is opened again (and its job runs
again).  A job's last line is its result: a job run again appends one, and
the file is rewritten with one line per job when the campaign ends.  A lock
keeps two campaigns from writing to one directory at once.
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
JOBS = "jobs"
LOCK = ".lock"


class OutputError(Genom2bipError):
    """The output directory cannot be used (another campaign writes to it, it is not a directory)."""


@dataclass
class Output:
    """An open output directory: the records already there (by job id) and the lock held while it is open."""

    directory: Path
    records: dict[str, dict[str, Any]] = field(default_factory=dict)
    dropped: int = 0  # lines that were not whole records (a kill during a write)
    _lock: Any = None

    @property
    def results(self) -> Path:
        return self.directory / RESULTS

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
        """The whole records of ``results.jsonl``; a damaged line is dropped and the file rewritten without it."""
        if not self.results.exists():
            return
        try:
            lines = self.results.read_text(encoding="utf-8", errors="replace").splitlines(keepends=True)
        except OSError as exc:
            raise OutputError(f"cannot read {self.results}: {_why(exc)}") from None
        kept = []
        for line in lines:
            try:
                record = json.loads(line) if line.endswith("\n") else None
            except json.JSONDecodeError:
                record = None
            if not isinstance(record, dict) or not isinstance(record.get("job"), str):
                self.dropped += 1
                continue
            self.records.pop(record["job"], None)  # the last line of a job is its result, in the order written
            self.records[record["job"]] = record
            kept.append(line)
        if self.dropped and rewrite:
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
