"""The event loop's side of the controller: clients waiting for a final report, and the event streams.

The engine runs in its own thread; it hands its events to the loop through
:meth:`Hub.listener`, the only crossing between the two: the event is queued
and the loop woken once for whatever has queued meanwhile, so that the engine
never waits for the loop nor for any client.  In the loop the events go to
the shared log the streams read (runtime.services.eventlog), and a final
report wakes the clients long-polling its request.
"""
from __future__ import annotations

import asyncio
from collections import deque
from typing import Any

from runtime.controller import Controller
from runtime.services.eventlog import FINALS, KINDS, RING, EventLog, Subscriber

EVENT_KINDS = KINDS


class Hub:
    """Lives in the event loop: wakes the clients waiting for a request's final report, feeds the event streams."""

    def __init__(self) -> None:
        self.waiters: dict[int, list[asyncio.Future]] = {}
        self.log = EventLog()
        self.subscribers: set[Subscriber] = set()
        self.loop: asyncio.AbstractEventLoop | None = None
        self.closed = False
        self.cut = 0  # streams closed because even their final reports were gone
        self._pending: deque[dict[str, Any]] = deque()
        self._scheduled = False

    @property
    def streams(self) -> int:
        """Event streams still open."""
        return len(self.subscribers)

    def listener(self, event: dict[str, Any]) -> None:
        """Called in the engine thread: queue the event, wake the loop unless it is already due to look."""
        loop = self.loop
        if loop is None or self.closed:
            return
        self._pending.append(event)
        if not self._scheduled:
            self._scheduled = True
            try:
                loop.call_soon_threadsafe(self.drain)
            except RuntimeError:  # the loop has closed
                pass

    def drain(self) -> None:
        """In the loop: publish every event queued by the engine, then wake the streams waiting for news."""
        self._scheduled = False  # before taking them: an event queued from now on schedules another drain
        if not self._pending:
            return
        while self._pending:
            event = self._pending.popleft()
            if event.get("event") == "report" and event.get("final"):
                for fut in self.waiters.pop(event["request"], []):
                    if not fut.done():
                        fut.set_result(None)
            self.log.append(event)
        self._wake()

    def _wake(self) -> None:
        for sub in self.subscribers:
            if sub.waiting:
                sub.wake.set()

    def subscribe(self, kinds: set[str]) -> Subscriber:
        sub = Subscriber.at_end(self.log, kinds)
        self.subscribers.add(sub)
        return sub

    def unsubscribe(self, sub: Subscriber) -> None:
        self.subscribers.discard(sub)
        if sub.cut:
            self.cut += 1

    async def wait_final(self, controller: Controller, rid: int, timeout: float) -> None:
        """Return once request ``rid`` has its final report, ``timeout`` seconds have passed or the hub closes."""
        req = controller.get(rid)
        if req.final is not None or timeout <= 0 or self.closed:
            return
        fut = asyncio.get_running_loop().create_future()
        self.waiters.setdefault(rid, []).append(fut)
        try:
            await asyncio.wait_for(fut, timeout)
        except asyncio.TimeoutError:
            pass
        finally:
            futs = self.waiters.get(rid)
            if futs is not None and fut in futs:
                futs.remove(fut)
                if not futs:
                    del self.waiters[rid]

    def close(self) -> None:
        """The controller has stopped: publish its last events, answer the long polls, let the streams end."""
        self.drain()
        self.closed = True
        for futs in self.waiters.values():
            for fut in futs:
                if not fut.done():
                    fut.set_result(None)
        self.waiters.clear()
        for sub in self.subscribers:
            sub.wake.set()

    def stats(self) -> dict[str, Any]:
        """The streams at a glance: how many, how many behind (their clients do not read), what they lost."""
        subs, first = list(self.subscribers), self.log.first
        # dropped: what the streams skipped in gaps, and what has already left the log before they sent it
        dropped = sum(s.dropped + max(0, first - s.cursor) for s in subs)
        return {"streams": len(subs), "behind": sum(1 for s in subs if not s.waiting and s.behind(self.log) > 0),
                "most_behind": max((s.behind(self.log) for s in subs), default=0), "queue_bound": RING,
                "finals_kept": FINALS, "dropped": dropped, "cut": self.cut, "events": self.log.next_seq}
