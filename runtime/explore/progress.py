"""A one-line progress display on stderr for long explorations, rewritten in place on a terminal.

Shown only once a run has lasted a second, and only on a terminal unless
forced (``--progress``): a stream that is not a terminal (a log file) gets
one line per report, ended by a newline, about once a second.
"""
from __future__ import annotations

import shutil
import sys
import time
from typing import Callable, TextIO

#: Seconds before the first line appears, and between updates.
DELAY = 1.0
PERIOD = 0.25
#: Seconds between lines when the stream is not a terminal.
LOG_PERIOD = 1.0


def human_bytes(n: float) -> str:
    for unit in ("B", "KB", "MB", "GB"):
        if n < 1024 or unit == "GB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} GB"


class Progress:
    """Call :meth:`tick` often; it redraws ``states, transitions, states/s, frontier, memory`` when due."""

    def __init__(self, stream: TextIO | None = None, force: bool = False, enabled: bool = True,
                 delay: float = DELAY) -> None:
        self.stream = stream or sys.stderr
        isatty = getattr(self.stream, "isatty", lambda: False)()
        self.on = enabled and (force or isatty)
        self.tty = isatty
        self.delay = delay
        self.start = time.monotonic()
        self.next = self.start + delay
        self.shown = False
        self.width = 0

    def tick(self, states: int, transitions: int, frontier: int, memory: Callable[[], int],
             depth: int | None = None) -> None:
        if not self.on:
            return
        now = time.monotonic()
        if now < self.next:
            return
        self.next = now + (PERIOD if self.tty else LOG_PERIOD)
        rate = states / max(now - self.start, 1e-9)
        line = (f"states {states:,}  transitions {transitions:,}  {rate:,.0f} states/s  "
                + (f"depth {depth:,}  " if depth is not None else "")
                + f"frontier {frontier:,}  memory {human_bytes(memory())}")
        if not self.tty:
            self.stream.write(line + "\n")
            self.stream.flush()
            return
        line = line[:max(20, shutil.get_terminal_size().columns - 1)]  # one row: a wrapped line cannot be redrawn
        pad = " " * max(0, self.width - len(line))
        self.stream.write("\r" + line + pad)
        self.stream.flush()
        self.width = len(line)
        self.shown = True

    def done(self) -> None:
        """Clear the line so that results print on a clean one."""
        if self.shown:
            self.stream.write("\r" + " " * self.width + "\r")
            self.stream.flush()
            self.shown = False


def null_progress() -> Progress:
    return Progress(enabled=False)
