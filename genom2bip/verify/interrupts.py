"""Ctrl-C during a long check: the first press asks the check to stop and report what it found, the second stops
at once.

The first press only sets a flag that the check reads between its steps.  Python's own handler raises
KeyboardInterrupt wherever the interpreter is, and while C calls back into Python (the zone search's programs, the
SMC runs' interactions) that is inside a ctypes callback, where the exception is printed and lost: the check then
went on to its end as if nothing had been pressed.
"""
from __future__ import annotations

import contextlib
import signal
import sys
import threading
from typing import Iterator

STOPPING = "genom2bip: stopping: what was found so far follows (Ctrl-C again stops at once)"


class CtrlC:
    """Whether Ctrl-C was pressed while :meth:`watching` (``pressed``); a second press raises KeyboardInterrupt."""

    def __init__(self) -> None:
        self.pressed = False

    @contextlib.contextmanager
    def watching(self) -> Iterator[CtrlC]:
        if threading.current_thread() is not threading.main_thread():  # signals reach the main thread only
            yield self
            return

        def handler(signum, frame) -> None:
            if self.pressed:
                raise KeyboardInterrupt
            self.pressed = True
            print("\n" + STOPPING, file=sys.stderr, flush=True)

        previous = signal.signal(signal.SIGINT, handler)
        try:
            yield self
        finally:
            signal.signal(signal.SIGINT, previous)
