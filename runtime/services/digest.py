"""Overruns on ``run``'s console: the first one as it comes, then at most one line a second that counts the rest.

A loaded machine makes a 25 ms task overrun forty times a second; a line each buries the reports.  The controller's
events and the live page keep every overrun; the console says how many there were, where, and the longest.
"""
from __future__ import annotations

import time
from collections import Counter
from typing import Any, Callable

#: The events summed up instead of printed one by one.
KINDS = ("overrun", "codel_overrun")


class OverrunDigest:
    """``take(event)`` -> the lines to print now; ``flush()`` -> what is still counted (at the end of the run)."""

    def __init__(self, every: float = 1.0, clock: Callable[[], float] = time.monotonic) -> None:
        self.every, self.clock = every, clock
        self.last: float | None = None  # when a line about overruns was last printed
        self.counts: Counter[tuple[str, str]] = Counter()  # (kind, task or codel) -> overruns not yet said
        self.longest: dict[tuple[str, str], float] = {}

    def take(self, event: dict[str, Any]) -> list[str]:
        """The lines ``event`` gives: itself when it is the first overrun for a second, else a count when due."""
        kind = event.get("event")
        now = self.clock()
        if kind not in KINDS:
            return self._due(now)
        if self.last is None or (not self.counts and now - self.last >= self.every):
            self.last = now
            return [f"{kind}: {event.get('message')}"]
        key = (kind, str(event.get("task") if kind == "overrun" else event.get("codel") or "?"))
        self.counts[key] += 1
        took = event.get("took_ms") or event.get("running_ms")
        if isinstance(took, (int, float)):
            self.longest[key] = max(self.longest.get(key, 0.0), float(took))
        return self._due(now)

    def _due(self, now: float) -> list[str]:
        if self.counts and self.last is not None and now - self.last >= self.every:
            lines = self.flush(now - self.last)
            self.last = now
            return lines
        return []

    def flush(self, seconds: float | None = None) -> list[str]:
        """One line counting the overruns not said yet (none when there are none)."""
        if not self.counts:
            return []
        parts = []
        for (kind, what), n in sorted(self.counts.items(), key=lambda item: -item[1]):
            longest = self.longest.get((kind, what))
            word = "overran" if kind == "overrun" else "codel late"
            parts.append(f"{what} {word} {n}x" + (f" (longest {longest:g} ms)" if longest is not None else ""))
        total = sum(self.counts.values())
        self.counts.clear()
        self.longest.clear()
        span = f" in the last {seconds:.1f} s" if seconds is not None else " since the last line"
        return [f"overruns: {total} more{span}: {', '.join(parts)} (every one: the live page, GET /events)"]
