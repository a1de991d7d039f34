"""Helpers for the bad-input tests: run genom2bip in a child process with its memory capped, and measure its peak.

The cap (``RLIMIT_AS``) keeps a runaway input from taking the machine: code
that needs gigabytes fails inside the child instead.  The peak is the child's
own ``ru_maxrss`` (``os.wait4``), not the largest of every child this process
ever waited for.
"""
from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DALA = ROOT / "descriptions" / "dala"
MB = 1024 * 1024
#: The address space a child may map: far above what reading any refused input needs, far below a runaway's need.
CAP = 2048 * MB
#: How long a child may take before it counts as hung: a safety net for a hang, never a measure of speed.
HANG = 300


@dataclass
class Done:
    """What a genom2bip child did: its exit status, its output and its peak resident memory."""

    code: int
    out: str
    err: str
    peak_mb: float


def _capped() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (CAP, CAP))


def genom2bip(*argv, cwd: Path | None = None) -> Done:
    """Run ``genom2bip ARGV`` in a child capped at :data:`CAP` bytes of address space; its status, output, peak."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        child = subprocess.Popen([sys.executable, "-m", "genom2bip", *map(str, argv)], cwd=cwd or ROOT,
                                 stdin=subprocess.DEVNULL, stdout=out, stderr=err, preexec_fn=_capped,
                                 env={**os.environ, "PYTHONPATH": str(ROOT)})
        hung = threading.Timer(HANG, child.kill)  # a hang fails the test; a child that ends needs no more time
        hung.start()
        try:
            _, status, usage = os.wait4(child.pid, 0)  # this child's own usage (Popen.wait would discard it)
        finally:
            hung.cancel()
        child.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        return Done(child.returncode, out.read().decode("utf-8", "replace"), err.read().decode("utf-8", "replace"),
                    usage.ru_maxrss / 1024)


def tree(directory: Path) -> list[str]:
    """Every path below ``directory`` (relative, sorted): what a refused input must leave unchanged."""
    return sorted(str(p.relative_to(directory)) for p in directory.rglob("*"))
