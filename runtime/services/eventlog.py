"""What the event streams read: one shared log of the controller's events, a cursor per stream.

Every event is kept once, in arrival order, in a log of the last :data:`RING`
events, and serialised once, when a stream first sends it.  A stream
(:class:`Subscriber`) only has a cursor in the log: publishing an event costs
the same whatever the number of streams and however far behind they are, and
a stream whose client does not read costs nothing but its place.  A stream
that falls more than :data:`RING` events behind loses the oldest: it gets a
``gap`` event saying how many of each kind it lost, then the final reports it
would have lost (kept apart, the last :data:`FINALS`), then the log from where
it stands.  Final reports are never dropped; a stream so far behind that even
those are gone is closed with an ``overflow`` event saying why.
"""
from __future__ import annotations

import asyncio
from collections import deque
from dataclasses import dataclass, field
from typing import Any

from runtime.services.jsonio import dumps

#: Events kept for the streams: a stream further behind than this gets a gap.
RING = 1024
#: Final reports kept for the streams that fell behind: never dropped unless a stream is further behind than this.
FINALS = 10_000
#: Most bytes one write of a stream carries (a client that reads slowly is not sent megabytes at once).
BATCH_BYTES = 64 * 1024
#: At the shutdown, a stream with more events than this left to send sends only what ends requests.
CLOSE_SLACK = 100
KINDS = ("report", "poster", "overrun", "codel_error", "controller", "observer", "codel_overrun", "service")
_INDEX = {kind: i for i, kind in enumerate(KINDS)}


def frame(kind: str, data: Any) -> bytes:
    """One server-sent event."""
    return f"event: {kind}\ndata: {dumps(data)}\n\n".encode()


@dataclass(eq=False)
class Entry:
    """One event of the log: ``counts`` are the events of each kind logged before it (to count a gap)."""

    seq: int
    event: dict[str, Any]
    kind: str
    final: bool
    counts: tuple[int, ...]
    _frame: bytes | None = None

    def frame(self) -> bytes:
        if self._frame is None:
            self._frame = frame(self.kind, self.event)
        return self._frame

    @property
    def ends_a_request(self) -> bool:
        """What a stream must get even at the shutdown: final reports and the controller's last word."""
        return self.kind not in ("poster", "report", "service") or self.final


class EventLog:
    """The last :data:`RING` events and, apart, the last :data:`FINALS` final reports, numbered from 0."""

    def __init__(self, ring: int = RING, finals: int = FINALS) -> None:
        self.ring, self.finals_kept = ring, finals
        self.entries: deque[Entry] = deque()
        self.finals: deque[Entry] = deque()
        self.next_seq = 0
        self.counts = [0] * len(KINDS)  # events of each kind logged so far
        self.finals_lost = -1  # seq of the newest final report no longer kept

    @property
    def first(self) -> int:
        """The oldest event still kept (``next_seq`` when none is)."""
        return self.entries[0].seq if self.entries else self.next_seq

    def counts_before(self, seq: int) -> tuple[int, ...]:
        """Events of each kind logged before ``seq`` (a kept one, or ``next_seq``)."""
        if seq >= self.next_seq or not self.entries:
            return tuple(self.counts)
        return self.entries[seq - self.first].counts

    def append(self, event: dict[str, Any]) -> None:
        kind = event.get("event", "")
        entry = Entry(self.next_seq, event, kind, bool(event.get("final")), tuple(self.counts))
        self.next_seq += 1
        if kind in _INDEX:
            self.counts[_INDEX[kind]] += 1
        self.entries.append(entry)
        if len(self.entries) > self.ring:
            self.entries.popleft()
        if entry.final:
            self.finals.append(entry)
            if len(self.finals) > self.finals_kept:
                self.finals_lost = self.finals.popleft().seq


@dataclass(eq=False)
class Subscriber:
    """One event stream: the kinds it asked for, where it stands in the log, what it lost."""

    kinds: set[str]
    cursor: int
    counts: tuple[int, ...]
    wake: asyncio.Event = field(default_factory=asyncio.Event)
    waiting: bool = False  # waiting for new events (not blocked sending to a client that does not read)
    dropped: int = 0  # events lost in gaps
    cut: bool = False  # closed: even its final reports were gone

    @classmethod
    def at_end(cls, log: EventLog, kinds: set[str]) -> "Subscriber":
        return cls(kinds, log.next_seq, tuple(log.counts))

    def behind(self, log: EventLog) -> int:
        """Events logged that this stream has not sent yet, at most the log's size."""
        return min(log.next_seq - self.cursor, len(log.entries))

    def take(self, log: EventLog, closing: bool = False) -> list[bytes]:
        """The frames to send next (at most about :data:`BATCH_BYTES`), a gap first if the stream fell behind."""
        out: list[bytes] = []
        if self.cursor < log.first:
            out += self._gap(log)
            if self.cut:
                return out
        start = self.cursor - log.first
        entries = log.entries
        urgent = closing and len(entries) - start > CLOSE_SLACK  # far behind at the shutdown: what ends requests
        size, i, skipped = 0, start, 0
        while i < len(entries) and size < BATCH_BYTES:
            entry = entries[i]
            i += 1
            if entry.kind not in self.kinds and entry.kind in _INDEX:
                continue
            if urgent and not entry.ends_a_request:
                skipped += 1
                continue
            out.append(entry.frame())
            size += len(out[-1])
        if skipped:
            self.dropped += skipped
            message = f"the controller is stopping: {skipped} events skipped so that the final reports arrive first"
            out.insert(0, frame("gap", {"event": "gap", "dropped": skipped, "message": message}))
        self.cursor = log.first + i
        self.counts = log.counts_before(self.cursor)
        return out

    def _gap(self, log: EventLog) -> list[bytes]:
        """The stream fell out of the log: what it lost, by kind, and the final reports it would have lost."""
        first = log.first
        if "report" in self.kinds and log.finals_lost >= self.cursor:
            self.cut = True
            message = f"this stream fell more than {log.finals_kept} final reports behind: it is closed " \
                      "(GET /requests has them)"
            return [frame("overflow", {"event": "overflow", "message": message})]
        finals = [e for e in log.finals if self.cursor <= e.seq < first] if "report" in self.kinds else []
        now = log.counts_before(first)
        lost = {k: now[i] - self.counts[i] for i, k in enumerate(KINDS) if k in self.kinds and now[i] > self.counts[i]}
        if finals:
            lost["report"] -= len(finals)
        lost = {k: n for k, n in lost.items() if n}
        dropped = sum(lost.values())
        self.dropped += dropped
        self.cursor, self.counts = first, now
        gap = {"event": "gap", "dropped": dropped, "by_kind": lost,
               "message": f"this stream fell behind: {dropped} events dropped (at most {log.ring} wait for a "
                          f"client); final reports are never dropped: the {len(finals)} it missed follow"}
        return [frame("gap", gap)] + [e.frame() for e in finals]
