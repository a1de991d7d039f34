"""The event loop's side of the controller: clients waiting for a final report, and the event streams.

The engine runs in its own thread; it tells the event loop about reports
through ``loop.call_soon_threadsafe`` (:meth:`Hub.listener`), the only
crossing between the two.
"""
from __future__ import annotations

import asyncio
from typing import Any

from runtime.controller import Controller

#: Events kept for a slow event-stream client before it is cut off.
QUEUE_SIZE = 10_000
EVENT_KINDS = ("report", "poster", "overrun", "codel_error", "controller", "observer", "codel_overrun")


class Subscriber:
    """One event-stream client: a bounded queue of events of the kinds it asked for."""

    def __init__(self, kinds: set[str]) -> None:
        self.kinds = kinds
        self.queue: asyncio.Queue = asyncio.Queue(maxsize=QUEUE_SIZE)


class Hub:
    """Lives in the event loop: wakes the clients waiting for a request's final report, feeds the event streams."""

    def __init__(self) -> None:
        self.waiters: dict[int, list[asyncio.Future]] = {}
        self.subscribers: set[Subscriber] = set()
        self.streams = 0  # event streams still sending
        self.loop: asyncio.AbstractEventLoop | None = None
        self.closed = False

    def listener(self, event: dict[str, Any]) -> None:
        """Called in the engine thread: hand the event to the loop."""
        loop = self.loop
        if loop is not None and not self.closed:
            try:
                loop.call_soon_threadsafe(self.publish, event)
            except RuntimeError:  # the loop has closed
                pass

    def publish(self, event: dict[str, Any]) -> None:
        if event.get("event") == "report" and event.get("final"):
            for fut in self.waiters.pop(event["request"], []):
                if not fut.done():
                    fut.set_result(None)
        for sub in list(self.subscribers):
            if event["event"] not in sub.kinds:
                continue
            try:
                sub.queue.put_nowait(event)
            except asyncio.QueueFull:
                self.subscribers.discard(sub)
                while not sub.queue.empty():
                    sub.queue.get_nowait()
                sub.queue.put_nowait({"event": "overflow", "message": f"more than {QUEUE_SIZE} events unread: "
                                                                       "this stream is closed"})
                sub.queue.put_nowait(None)

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
        """End every event stream and long poll (the server is stopping)."""
        self.closed = True
        for sub in list(self.subscribers):
            try:
                sub.queue.put_nowait(None)
            except asyncio.QueueFull:
                pass
        self.subscribers.clear()
        for futs in self.waiters.values():
            for fut in futs:
                if not fut.done():
                    fut.set_result(None)
        self.waiters.clear()
