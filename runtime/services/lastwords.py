"""The last words of a ``run`` that ends abruptly: what ran, what was left without a final report.

A codel may end the process without Python seeing it go: ``os._exit()``
runs no ``finally``, no handler, no print.  While the controller runs,
``os._exit`` called from a codel first says, on stderr, which codel of which
service or task called it, which requests it leaves without a final report
and the summary, then exits with the status the codel asked for.  A crash of
the interpreter itself (a segmentation fault in an extension) prints the
Python stack of every thread (:mod:`faulthandler`), the codel's among them.
Nothing here can speak for a process killed by SIGKILL.
"""
from __future__ import annotations

import faulthandler
import os
import sys
import threading
from typing import Any, Callable


def pending_line(controller: Any) -> str:
    """``2 request(s) left without a final report: 4, 7`` (at most 20 ids listed)."""
    pending = sorted(r.id for r in list(controller.requests.values()) if r.final is None)
    listed = ", ".join(map(str, pending[:20])) + (" ..." if len(pending) > 20 else "")
    return f"{len(pending)} request(s) left without a final report{': ' + listed if pending else ''}"


def summary_line(controller: Any) -> str:
    """``after 812 steps; requests: 3 ok, 1 running``."""
    counts = controller.summary()["requests"]
    done = ", ".join(f"{n} {s}" for s, n in sorted(counts.items())) or "none"
    return f"after {controller.steps} steps; requests: {done}"


def guard_exit(controller: Any, prog: str) -> Callable[[], None]:
    """Make ``os._exit`` from a codel say its last words; returns what undoes it.  Also enables faulthandler."""
    real_exit = os._exit
    main = threading.main_thread()

    def exit_with_words(status: int) -> None:
        calling = controller.codel_of(threading.current_thread()) if threading.current_thread() is not main else None
        if calling is not None:
            try:
                sys.stderr.write(f"{prog}: {calling} called os._exit({status}): the controller exits now; "
                                 f"{pending_line(controller)}; {summary_line(controller)}\n")
                sys.stderr.flush()
            except (OSError, ValueError):
                pass
        real_exit(status)

    os._exit = exit_with_words
    faulthandler.enable(all_threads=True)

    def undo() -> None:
        os._exit = real_exit
    return undo
