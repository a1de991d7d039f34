"""The console of ``run``: lines written by a thread of their own, so that an output nobody reads stalls nothing.

``run ... | sleep 1000`` leaves stdout undrained: once the pipe is full, a
write blocks.  Printed from the engine thread, a report would stop the
engine (and the server waiting on its lock).  Here the engine only queues
the line: at most :data:`MAX_LINES` wait; beyond, lines are dropped and
counted, said once on stderr when it starts, marked in the output where they
went missing, and counted in the last line.
"""
from __future__ import annotations

import os
import sys
import threading
import time
from collections import deque
from typing import TextIO

#: Lines waiting to be written before new ones are dropped.
MAX_LINES = 1000
#: Seconds the writer lets lines gather before a write: one write (and one wake-up) for many lines.
GATHER = 0.01
NOTICE = "the output is not being read: lines are dropped from now on (their number comes at the end)"


class Console:
    """Lines for ``stream`` (stdout), written in order by a writer thread; :meth:`line` never waits for the reader."""

    def __init__(self, stream: TextIO | None = None, max_lines: int = MAX_LINES, prog: str = "controller",
                 warn: TextIO | None = None) -> None:
        self.stream = stream or sys.stdout
        self.max_lines = max_lines
        self.prog = prog
        self.warn = warn or sys.stderr
        self.dropped = 0  # lines dropped since the start
        self._gap = 0  # lines dropped since the last line queued: marked where they went missing
        self._lines: deque[str] = deque()
        self._cond = threading.Condition()
        self._closed = False
        self._broken = False  # the reader has gone (EPIPE): nothing more is written
        try:
            self._fd: int | None = self.stream.fileno()
        except (AttributeError, OSError, ValueError):  # a stream without a file descriptor (captured output)
            self._fd = None
        self._writer = threading.Thread(target=self._write_all, name="console", daemon=True)
        self._writer.start()

    def line(self, text: str) -> None:
        """Queue one line (any thread); dropped and counted when :data:`MAX_LINES` are already waiting."""
        with self._cond:
            if self._closed:
                return
            if len(self._lines) < self.max_lines:
                if self._gap:
                    self._lines.append(f"... {self._gap} lines dropped: the output was not read")
                    self._gap = 0
                self._lines.append(text)
                if len(self._lines) == 1:
                    self._cond.notify()  # the writer was waiting for a first line
                return
            self.dropped += 1
            self._gap += 1
            first = self.dropped == 1
        if first:  # said once, from a thread of its own: stderr may be a pipe nobody reads too
            threading.Thread(target=self._say, args=(f"{self.prog}: warning: {NOTICE}\n",), daemon=True).start()

    def close(self, timeout: float) -> bool:
        """No more lines; wait up to ``timeout`` s for those queued to be written.  True when all were."""
        with self._cond:
            if self._gap:
                self._lines.append(f"... {self._gap} lines dropped: the output was not read")
                self._gap = 0
            self._closed = True
            self._cond.notify()
        self._writer.join(timeout)
        return not self._writer.is_alive()

    def _say(self, text: str) -> None:
        try:
            self.warn.write(text)
            self.warn.flush()
        except (OSError, ValueError):
            pass

    def _write_all(self) -> None:
        """The writer thread: everything queued, in order, as one write per batch."""
        while True:
            with self._cond:
                self._cond.wait_for(lambda: self._lines or self._closed)
                if not self._lines:
                    return
                closed = self._closed
            if not closed:
                time.sleep(GATHER)
            with self._cond:
                batch = list(self._lines)
                self._lines.clear()
            if not self._broken:
                self._write("\n".join(batch) + "\n")

    def _write(self, text: str) -> None:
        try:
            if self._fd is None:
                self.stream.write(text)
                self.stream.flush()
                return
            data = text.encode("utf-8", "replace")
            while data:
                data = data[os.write(self._fd, data):]
        except BrokenPipeError:
            self._broken = True  # nobody will read again: the rest is dropped silently
        except (OSError, ValueError):
            self._broken = True
