"""What ``genom2bip verify`` answers: a summary line per check first, the details and the traces in files, or one
JSON document (``--json``); ``--traces terminal`` prints everything as it comes, traces inline.

The checks print their details as they run (genom2bip/cli/verify*.py); a
:class:`Report` records, beside them, each check's verdict and figures and
each trace printed.  With traces in a directory, the details go to
``DIR/verify.txt`` (what ``--traces terminal`` prints) and each trace to
``DIR/NAME.txt`` and ``DIR/NAME.json``; the terminal gets the model, the
summary and where the rest is.  docs/output.md describes both forms and the
JSON schema (verify_schema.json beside this file).
"""
from __future__ import annotations

import contextlib
import io
import json
import os
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

#: ``--traces terminal``: today's output, everything printed as it comes.
TERMINAL = "terminal"
#: Where traces go by default: ``out/traces/<model>/`` (the mission writes ``out/`` too).
DEFAULT_PARENT = Path("out") / "traces"
#: The details of a run, in its traces directory.
DETAILS = "verify.txt"
#: The JSON document's schema, shipped with the package.
SCHEMA = Path(__file__).with_name("verify_schema.json")


@dataclass
class TraceFile:
    """One trace of a check: its name in the directory (``NAME.txt``, ``NAME.json``), what it shows, its lines."""

    name: str
    subject: str
    what: str  # "counterexample", "witness", "trace", "lasso", "deadlock"
    steps: int
    loop: int | None
    text: str
    data: dict[str, Any]


@dataclass
class Check:
    """One line of the summary: a check's verdict (or a response time's value), figures and message."""

    kind: str  # deadlock, property, observer, response, model-error
    subject: str
    verdict: str  # holds, violated, inconclusive, error
    figures: dict[str, Any] = field(default_factory=dict)
    how: str = ""  # the figures in words: "compiled observer search, 55,680 states, 0.04 s"
    message: str = ""
    value: str = ""  # a response time in words: "8 ms", "no bound", "runs until stopped"
    value_ms: float | None = None
    result: dict[str, Any] | None = None  # CheckResult.to_json() without its trace
    traces: list[str] = field(default_factory=list)  # TraceFile names

    @property
    def word(self) -> str:
        return self.value or self.verdict


class Report:
    """The summary of one ``verify`` run, the traces it printed, and where they go."""

    def __init__(self, mode: str = TERMINAL, directory: Path | None = None, as_json: bool = False) -> None:
        self.mode, self.directory, self.as_json = mode, directory, as_json
        self.header: list[str] = []
        self.model: dict[str, Any] = {}
        self.platform: str | None = None
        self.tick_ms: float | None = None
        self.checks: list[Check] = []
        self.traces: dict[str, TraceFile] = {}
        self.files: list[dict[str, str]] = []  # exports: {"path", "what"}
        self.not_run: list[str] = []
        self.log = io.StringIO()

    @property
    def captured(self) -> bool:
        """The details go to a buffer (a file, or nowhere with --json), not to the terminal as they come."""
        return self.mode != TERMINAL or self.as_json

    # ------------------------------------------------------------------ recording

    def line(self, text: str) -> None:
        """A header line (model, platform, time): printed as it comes, and again above the summary."""
        print(text, flush=True)
        if self.captured and text not in self.header:
            self.header.append(text)

    def check(self, kind: str, subject: str, verdict: str, result=None, how: str = "", message: str = "",
              **extra) -> Check:
        """Record one check's answer; a trace printed just before it with the same subject is attached."""
        data = _without_traces(result.to_json()) if result is not None else None
        figures = data["figures"] if data is not None else extra.pop("figures", {})
        item = Check(kind, subject, verdict, figures, how, message or (data or {}).get("message", ""),
                     result=data, **extra)
        item.traces = [t.name for t in self.traces.values() if t.subject == subject and not self._claimed(t.name)]
        self.checks.append(item)
        return item

    def _claimed(self, name: str) -> bool:
        return any(name in c.traces for c in self.checks)

    def wrote(self, path: str, what: str) -> None:
        """A file an option asked for (--aut, --dot, --promela, --trace-picture, --graph)."""
        self.files.append({"path": str(path), "what": what})

    @contextlib.contextmanager
    def trace(self, subject: str, name: str, trace, what: str, state: str = "") -> Iterator[None]:
        """Everything printed inside is one trace of ``subject``: printed as before, and kept as its own files."""
        buffer = io.StringIO()
        before = sys.stdout
        sys.stdout = _Tee(before, buffer)
        try:
            yield
        finally:
            sys.stdout = before
        name = self._unique(_slug(name))
        data = {"subject": subject, "what": what, "trace": trace.to_json() if trace is not None else None}
        if state:
            data["state"] = state.splitlines()
        text = f"{subject}: {what}\n{buffer.getvalue()}"
        self.traces[name] = TraceFile(name, subject, what, len(trace) if trace is not None else 0,
                                      getattr(trace, "loop", None), text, data)
        for c in reversed(self.checks):  # a check already recorded (deadlocks print their traces after it)
            if c.subject == subject:
                c.traces.append(name)
                break

    def _unique(self, name: str) -> str:
        out, k = name, 1
        while out in self.traces or out == Path(DETAILS).stem:
            k += 1
            out = f"{name}-{k}"
        return out

    # ------------------------------------------------------------------ the answer

    def paths(self) -> dict[str, dict[str, str]]:
        """Each trace's files, as the summary and the JSON name them (none when traces stay on the terminal)."""
        if self.directory is None or self.mode == TERMINAL:
            return {}
        return {n: {"text": str(self.directory / f"{n}.txt"), "json": str(self.directory / f"{n}.json")}
                for n in self.traces}

    def files_to_write(self) -> dict[str, str]:
        """The directory's files: the details, and two per trace."""
        out = {DETAILS: self.log.getvalue()}
        for t in self.traces.values():
            out[f"{t.name}.txt"] = t.text
            out[f"{t.name}.json"] = json.dumps(t.data, indent=1) + "\n"
        return out

    def summary_lines(self, status: int) -> list[str]:
        """The header, one line per check, what was not run, and where the details and traces are."""
        lines: list[str] = []
        for text in self.header:  # "platform: ..." and "time: ..." of a timed model make one line
            if text.startswith("time: ") and lines and lines[-1].startswith("platform: "):
                lines[-1] += f"; {text}"
            else:
                lines.append(text)
        if self.checks:
            lines.append(f"summary ({_counted(self.checks)}):")
        width = min(max((len(c.word) for c in self.checks), default=0), 16)
        for c in self.checks:
            how = f" ({c.how})" if c.how else ""
            tail = f": {c.message}" if c.message and c.message != c.value else ""
            files = [f"{n}.txt" if self.directory is not None else f"{self.traces[n].what} above" for n in c.traces]
            lines.append(f"  {c.word:<{width}}  {c.subject}{how}{tail}" + (f"  → {', '.join(files)}" if files else ""))
        for f in self.files:
            lines.append(f"  wrote {f['path']} ({f['what']})")
        if self.not_run:
            lines.append(f"interrupted: not run: {', '.join(self.not_run)}")
        if self.directory is not None:
            n = len(self.traces)
            traces = f", {n} trace{'s' if n != 1 else ''} as NAME.txt and NAME.json" if n else ""
            lines.append(f"details in {self.directory}/{DETAILS}{traces} (--traces terminal prints them here)")
        if status:  # 0 says itself: every line above holds
            lines.append(f"exit status {status}: {_meaning(status)}")
        return lines

    def document(self, status: int, interrupted: bool) -> dict[str, Any]:
        """The ``--json`` document (docs/output.md; genom2bip/cli/verify_schema.json)."""
        paths = self.paths()
        checks = []
        for c in self.checks:
            traces = []
            for n in c.traces:
                t = self.traces[n]
                item = {"name": n, "what": t.what, "steps": t.steps, "loop": t.loop, "files": paths.get(n)}
                if not paths:
                    item["trace"] = t.data["trace"]
                traces.append(item)
            entry = {"kind": c.kind, "subject": c.subject, "verdict": c.verdict, "how": c.how, "message": c.message,
                     "figures": c.figures, "traces": traces}
            if c.kind == "response":
                entry["value"], entry["value_ms"] = c.value, c.value_ms
            if c.result is not None:
                entry["result"] = c.result
            checks.append(entry)
        return {"tool": "genom2bip verify", "schema": 1, "model": self.model, "platform": self.platform,
                "tick_ms": self.tick_ms, "checks": checks, "files": list(self.files),
                "traces_directory": str(self.directory) if paths else None,
                "details": str(self.directory / DETAILS) if paths else None,
                "not_run": list(self.not_run), "interrupted": interrupted,
                "exit_status": status, "meaning": _meaning(status)}


def _without_traces(data):
    """A result's JSON without its traces (each is a file of its own, or inline in its check's ``traces``)."""
    if isinstance(data, dict):
        return {k: _without_traces(v) for k, v in data.items() if k != "trace"}
    if isinstance(data, list):
        return [_without_traces(v) for v in data]
    return data


class _Tee(io.TextIOBase):
    """A stream that writes to two: what a trace prints goes on to the terminal (or the log) and into its file."""

    def __init__(self, first, second) -> None:
        self.first, self.second = first, second

    def write(self, text: str) -> int:
        self.first.write(text)
        return self.second.write(text)

    def flush(self) -> None:
        self.first.flush()

    def isatty(self) -> bool:
        return False


def _slug(text: str) -> str:
    """A file name of a check's words: ``response RFLEX.TrackSpeed`` -> ``response-RFLEX.TrackSpeed``."""
    out = re.sub(r"[^A-Za-z0-9_.]+", "-", text).strip("-.")
    return out[:80] or "trace"


def _counted(checks: list[Check]) -> str:
    """``13 checks: 3 holds, 10 response times`` (a response time is a value, whatever the API's verdict)."""
    counts: dict[str, int] = {}
    for c in checks:
        word = "response times" if c.kind == "response" else c.verdict
        counts[word] = counts.get(word, 0) + 1
    n = len(checks)
    return f"{n} check{'s' if n != 1 else ''}: " + ", ".join(f"{k} {v}" for v, k in counts.items())


def _meaning(status: int) -> str:
    from runtime.exits import TABLE

    return dict(TABLE).get(status, "")


# --------------------------------------------------------------------------- the run's report


_ACTIVE: list[Report] = []


def active() -> Report:
    """The report of the ``verify`` being run (a terminal one that records nothing elsewhere)."""
    return _ACTIVE[-1] if _ACTIVE else Report()


def traces_directory(option: str | None, name: str) -> Path | None:
    """``--traces``: DIR, ``terminal`` (None), or by default ``out/traces/<model>``."""
    if option == TERMINAL:
        return None
    return Path(option) if option else DEFAULT_PARENT / name


def check_directory(directory: Path, inputs: list[Path]) -> str | None:
    """Why ``directory`` cannot take the traces (written at the end, replacing only what genom2bip wrote), or None.

    Checked before anything runs, so that a bad ``--traces`` costs nothing and writes nothing.
    """
    from genom2bip.output import OutputError, check_inputs, kept_entries

    for parent in [directory, *directory.parents]:
        if os.path.lexists(parent):
            if not parent.is_dir():
                return f"cannot write {directory}: {parent} is not a directory" if parent != directory else \
                    f"cannot write {directory}: it exists and is not a directory"
            if not os.access(parent, os.W_OK | os.X_OK):
                return f"cannot write {directory}: {parent} is not writable"
            break
    try:
        check_inputs(directory, inputs)
        if directory.is_dir() and not directory.is_symlink() and not any(directory.iterdir()):
            pass  # an empty directory is taken as it is
        else:
            kept_entries(directory, {})
    except OutputError as exc:
        return str(exc).replace("choose another -o DIR", "choose another --traces DIR")
    except OSError as exc:
        return f"cannot read {directory}: {exc.strerror or exc}"
    return None


def write_directory(report: Report, inputs: list[Path]) -> None:
    """Write the details and the traces as ``report.directory`` (OutputError, OSError when it cannot be)."""
    from genom2bip.output import write_tree

    directory = report.directory
    assert directory is not None
    if directory.is_dir() and not directory.is_symlink() and not any(directory.iterdir()):
        directory.rmdir()  # empty: write_tree puts its own in place
    write_tree(report.files_to_write(), directory.parent, directory.name, inputs)


@contextlib.contextmanager
def running(report: Report) -> Iterator[Report]:
    """Make ``report`` the active one; with traces in files or ``--json``, the details printed go to its log."""
    _ACTIVE.append(report)
    before = sys.stdout
    if report.captured:
        sys.stdout = report.log
    try:
        yield report
    finally:
        sys.stdout = before
        _ACTIVE.pop()
