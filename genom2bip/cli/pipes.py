"""Standard output whose reader may go away (``genom2bip verify ... | head -1``): printing stops quietly, the
command goes on, and its exit status stays its own.

A closed pipe used to end the command with status 0, whatever it had found:
a CI job with ``pipefail`` read "violated" as "holds".  Now the first write
that meets the closed pipe points the descriptor at ``/dev/null`` (so that no
later write, nor the interpreter's last flush, complains) and marks the
stream :attr:`ClosedAware.closed_by_reader`; a verb that must not go on
unseen (a campaign) looks at it and stops, saying so on stderr.
"""
from __future__ import annotations

import os
from typing import Any, TextIO


class ClosedAware:
    """A text stream (stdout) that swallows writes once its reader has closed the pipe, and remembers it."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self.closed_by_reader = False

    def write(self, text: str) -> int:
        if not self.closed_by_reader:
            try:
                return self.stream.write(text)
            except BrokenPipeError:
                self._gone()
        return len(text)

    def flush(self) -> None:
        if not self.closed_by_reader:
            try:
                self.stream.flush()
            except BrokenPipeError:
                self._gone()

    def _gone(self) -> None:
        self.closed_by_reader = True
        try:
            fd = self.stream.fileno()
        except (AttributeError, OSError, ValueError):  # not a file (a test's capture): nothing to redirect
            return
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(devnull, fd)
        finally:
            os.close(devnull)

    def __getattr__(self, name: str) -> Any:  # isatty, fileno, encoding... as the stream has them
        return getattr(self.stream, name)


def output_closed(stream: Any) -> bool:
    """Whether ``stream`` (stdout, as :func:`~genom2bip.cli.command.main` wraps it) has lost its reader."""
    return bool(getattr(stream, "closed_by_reader", False))
