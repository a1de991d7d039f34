"""A generated controller in a process of its own, started as a user does: its URL, its output, a stop by a signal.

``ControllerProcess()`` runs ``python -m dala run`` (gen/dala) with DALA's real codels
(descriptions/dala/codels, the ir-sim world) unless told otherwise; its stdout and stderr are read by
threads of their own, so that a test sees the lines as they come, or stops reading stdout to leave it
undrained.
"""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
REAL_CODELS = ROOT / "descriptions" / "dala" / "codels"
URL = re.compile(r"services interface on (http://127\.0\.0\.1:\d+)/")


@dataclass
class Stopped:
    """How a controller process ended: its exit status, everything it printed, how long it took after the signal."""

    status: int
    out: str
    err: str
    took: float


class ControllerProcess:
    """``python -m PACKAGE run --codels CODELS ARGS`` from ``cwd``; ``read_stdout=False`` leaves stdout undrained.

    Used as a context manager, the process is killed on the way out if a test left it running.
    """

    def __init__(self, *args: str, codels: Path | str = REAL_CODELS, package: str = "dala",
                 cwd: Path = ROOT / "gen", read_stdout: bool = True, env: dict[str, str] | None = None) -> None:
        self.argv = [sys.executable, "-m", package, "run", "--codels", str(codels), *map(str, args)]
        self.cwd = cwd
        self.read_stdout = read_stdout
        self.env = dict(os.environ, PYTHONUNBUFFERED="1", **(env or {}))
        self.out: list[str] = []
        self.err: list[str] = []
        self.url: str | None = None
        self.proc: subprocess.Popen | None = None
        self._readers: list[threading.Thread] = []
        self._printed = threading.Condition()

    def __enter__(self) -> "ControllerProcess":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.kill()

    def start(self, timeout: float = 60.0) -> "ControllerProcess":
        """Start it and return once it has printed its URL."""
        self.proc = subprocess.Popen(self.argv, cwd=self.cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     env=self.env, bufsize=0)
        self._reader(self.proc.stderr, self.err, until_url=False)
        self._reader(self.proc.stdout, self.out, until_url=not self.read_stdout)
        found = self.wait_for(lambda: self.url is not None or self.proc.poll() is not None, timeout)
        if not found or self.url is None:
            self.kill()
            raise RuntimeError(f"no URL printed: {''.join(self.out)}{''.join(self.err)}")
        return self

    def _reader(self, stream, lines: list[str], until_url: bool) -> None:
        def read() -> None:
            for raw in iter(stream.readline, b""):
                line = raw.decode("utf-8", "replace")
                with self._printed:
                    lines.append(line)
                    found = URL.search(line)
                    if found and self.url is None:
                        self.url = found.group(1)
                    self._printed.notify_all()
                if until_url and self.url is not None:
                    return  # from now on nobody reads: the pipe fills
            with self._printed:
                self._printed.notify_all()
        thread = threading.Thread(target=read, daemon=True)
        thread.start()
        self._readers.append(thread)

    def wait_for(self, predicate, timeout: float = 60.0) -> bool:
        """Wait until ``predicate()`` holds (checked whenever a line is printed, and every 50 ms); its last value."""
        deadline = time.monotonic() + timeout
        while not predicate():
            left = deadline - time.monotonic()
            if left <= 0:
                return False
            with self._printed:
                self._printed.wait(min(left, 0.05))
        return True

    def printed(self, text: str) -> bool:
        """Whether a line of stdout or stderr so far contains ``text``."""
        return any(text in line for line in self.out + self.err)

    def client(self, timeout: float = 30.0):
        from runtime.services.client import Client

        return Client(self.url, timeout=timeout)

    def wait_ready(self, timeout: float = 60.0) -> None:
        """Wait until every task has run a few periods (the world is loaded, the level is up)."""
        client = self.client()
        ok = self.wait_for(lambda: all(t["periods"] >= 3 for t in client.tasks()), timeout)
        assert ok, f"the tasks did not start: {client.tasks()}"

    def send_signal(self, sig: int = signal.SIGINT) -> None:
        self.proc.send_signal(sig)

    def stop(self, sig: int = signal.SIGINT, timeout: float = 60.0, signal_sent: bool = False) -> Stopped:
        """Send ``sig`` (unless already sent), wait for the process to end (killed after ``timeout`` s): how it ended.

        An undrained stdout is read again from the signal on, so that the process can say its last words.
        """
        t0 = time.monotonic()
        if not signal_sent:
            self.send_signal(sig)
        if not self.read_stdout:
            self._reader(self.proc.stdout, self.out, until_url=False)
        try:
            self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.kill()
            raise AssertionError(f"still running {timeout} s after signal {sig}: {''.join(self.err)[-2000:]}")
        took = time.monotonic() - t0
        for thread in self._readers:
            thread.join(10)
        return Stopped(self.proc.returncode, "".join(self.out), "".join(self.err), took)

    def kill(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(10)
