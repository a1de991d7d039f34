"""How long each codel runs: calls, longest, 99th percentile and mean, in CPU time and in wall time.

The binder (runtime.controller.binding) times every call of a Python codel,
in the thread that calls it, from the start the stuck-codel watchdog reads
(``CodelCall.started``) to the codel's return or exception: the *CPU time*
of that thread (``time.thread_time``) and the *wall time*
(``time.monotonic``).  CPU time is the codel's own demand: it leaves out the
time its thread waited for the interpreter (the services interface, the
watchdog and a mission's client share it) or for a core (other processes),
which wall time counts.  On a virtual clock the controller skips the waits
between periods, not the codels' own time: both measures hold there too.

A codel is named ``Module.Owner.codel``, the owner being the service or the
task it belongs to (``NDD.GoTo.nddPlan``, ``RFLEX.servo.rflexOdometry``).
Percentiles come from a DDSketch (relative accuracy 1%, bounded memory
whatever the length of the run); calls, longest and mean are exact.
"""
from __future__ import annotations

import json
import os
import tempfile
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ddsketch import DDSketch

#: Relative accuracy of the percentiles (the longest and the mean are exact).
ACCURACY = 0.01
#: What a file of codel times says it measured.
MEASURED = ("around each codel call in the controller, in the codel's thread: cpu = time.thread_time (the thread's "
            "own CPU time), wall = time.monotonic; ms")


@dataclass
class Spread:
    """The times of the calls of one codel on one clock (s)."""

    sketch: DDSketch = field(default_factory=lambda: DDSketch(ACCURACY))
    total: float = 0.0
    longest: float = 0.0

    def add(self, seconds: float) -> None:
        seconds = max(0.0, seconds)
        self.sketch.add(seconds)
        self.total += seconds
        self.longest = max(self.longest, seconds)

    def figures(self, calls: int) -> dict[str, float]:
        """``max``, ``p99`` and ``mean`` in ms; the percentile is never above the longest call."""
        p99 = min(self.sketch.get_quantile_value(0.99) or 0.0, self.longest)
        return {"max": _ms(self.longest), "p99": _ms(p99), "mean": _ms(self.total / calls if calls else 0.0)}


def _ms(seconds: float) -> float:
    return round(seconds * 1e3, 4)


@dataclass
class Codel:
    """What the description says of one codel: its task (None: the control task) and declared WCET (µs)."""

    task: str | None
    wcet_us: int | None


def declared(interface: dict[str, Any]) -> dict[str, Codel]:
    """Every codel of the interface by ``Module.Owner.codel``, with its task and its declared WCET."""
    out: dict[str, Codel] = {}
    for c, comp in interface["components"].items():
        owners = [(t, f"{c}.{t}", spec["codels"]) for t, spec in comp["tasks"].items()]
        owners += [(s, f"{c}.{spec['task']}" if spec.get("task") else None, spec["codels"])
                   for s, spec in comp["services"].items()]
        for owner, task, codels in owners:
            for entry in codels.values():
                runs_in = None if entry.get("role") == "validate" else task  # validate codels run in the control task
                out[f"{c}.{owner}.{entry['codel']}"] = Codel(runs_in, entry.get("wcet_us"))
    return out


class CodelTimes:
    """The times of the codel calls of a run, by ``Module.Owner.codel``; :meth:`record` is called from any thread."""

    def __init__(self, interface: dict[str, Any]) -> None:
        self.codels = declared(interface)
        self._index = {name: i for i, name in enumerate(self.codels)}
        self._calls: dict[str, tuple[list[int], Spread, Spread]] = {}
        self._lock = threading.Lock()

    def record(self, name: str, cpu: float, wall: float) -> None:
        """One call of ``name`` took ``cpu`` s of its thread's CPU time and ``wall`` s of wall time."""
        with self._lock:
            entry = self._calls.get(name)
            if entry is None:
                entry = self._calls[name] = ([0], Spread(), Spread())
            entry[0][0] += 1
            entry[1].add(cpu)
            entry[2].add(wall)

    def as_json(self, clock: str) -> dict[str, Any]:
        """The figures of every codel that ran, and the names of those that did not (``clock``: virtual or real)."""
        with self._lock:
            ran = {name: (count[0], cpu.figures(count[0]), wall.figures(count[0]))
                   for name, (count, cpu, wall) in self._calls.items()}
        codels = {}
        for name in sorted(ran, key=self._order):
            calls, cpu, wall = ran[name]
            known = self.codels.get(name, Codel(None, None))
            codels[name] = {"task": known.task, "calls": calls, "cpu": cpu, "wall": wall,
                            "wcet": known.wcet_us / 1e3 if known.wcet_us else None}
        return {"measured": MEASURED, "clock": clock, "runs": 1, "codels": codels,
                "not_run": sorted((n for n in self.codels if n not in ran), key=self._order)}

    def _order(self, name: str) -> tuple[int, str]:
        return self._index.get(name, len(self._index)), name


def merge(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """The figures of several runs as one: calls added, longest and mean exact, p99 the highest of the runs' p99.

    Codels keep the order of the runs (the description's): one first seen in a later run comes after the codel
    it follows there.
    """
    codels: dict[str, dict[str, Any]] = {}
    order: list[str] = []
    for run in runs:
        previous = None
        for name, got in run["codels"].items():
            have = codels.get(name)
            if have is None:
                codels[name] = {**got, "cpu": dict(got["cpu"]), "wall": dict(got["wall"])}
                order.insert(order.index(previous) + 1 if previous is not None else 0, name)
            else:
                calls = have["calls"] + got["calls"]
                for clock in ("cpu", "wall"):
                    a, b = have[clock], got[clock]
                    a["mean"] = round((a["mean"] * have["calls"] + b["mean"] * got["calls"]) / calls, 4)
                    a["max"], a["p99"] = max(a["max"], b["max"]), max(a["p99"], b["p99"])
                have["calls"] = calls
            previous = name
    not_run = sorted({n for run in runs for n in run["not_run"]} - set(codels))
    clocks = sorted({run["clock"] for run in runs})
    return {"measured": runs[0]["measured"] if runs else MEASURED, "clock": ", ".join(clocks),
            "runs": sum(run.get("runs", 1) for run in runs), "codels": {name: codels[name] for name in order},
            "not_run": not_run}


def table(data: dict[str, Any]) -> list[str]:
    """The figures as aligned lines: one codel a line, a mark where the CPU time passed the declared WCET."""
    head = ("codel", "task", "calls", "cpu max", "cpu p99", "cpu mean", "wall max", "wall p99", "wcet")
    rows = [head]
    over = []
    for name, c in data["codels"].items():
        wcet = c.get("wcet")
        rows.append((name, c.get("task") or "control", str(c["calls"]), _fmt(c["cpu"]["max"]), _fmt(c["cpu"]["p99"]),
                     _fmt(c["cpu"]["mean"]), _fmt(c["wall"]["max"]), _fmt(c["wall"]["p99"]),
                     _fmt(wcet) if wcet is not None else "-"))
        if wcet is not None and c["cpu"]["max"] > wcet:
            over.append(name)
    widths = [max(len(r[i]) for r in rows) for i in range(len(head))]
    lines = ["  ".join(cell.ljust(w) if i < 2 else cell.rjust(w) for i, (cell, w) in enumerate(zip(r, widths)))
             .rstrip() for r in rows]
    if over:
        lines.append("CPU time past the declared WCET: " + ", ".join(over))
    if data.get("not_run"):
        lines.append("not run: " + ", ".join(data["not_run"]))
    return lines


def _fmt(ms: float) -> str:
    return f"{ms:.3f} ms"


def unwritable(path: str | Path) -> str | None:
    """Why ``path`` cannot be written (checked before a run, so that its figures are not lost), or None."""
    target = Path(path)
    if target.is_dir():
        return "is a directory"
    folder = target.parent
    while not folder.exists() and folder != folder.parent:
        if folder.is_symlink():
            return f"{folder} is a broken link"
        folder = folder.parent
    if not folder.is_dir():
        return f"{folder} is not a directory"
    if not os.access(folder, os.W_OK | os.X_OK):
        return f"the directory {folder} is not writable"
    if target.exists() and not os.access(target, os.W_OK):
        return "the file is not writable"
    return None


def write_json(path: str | Path, data: dict[str, Any]) -> None:
    """Write ``data`` to ``path`` atomically (its folders made): a reader never sees half a file; OSError as is."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            json.dump(data, f, indent=1)
            f.write("\n")
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
