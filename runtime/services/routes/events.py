"""``/events?types=report,poster``: server-sent events from the hub's log, with a keep-alive every 15 s.

A stream sends what its cursor has not sent yet (runtime.services.eventlog),
in batches, and otherwise waits for the hub to wake it.  Its client going
away is heard at once, even while a write to it waits for room: the stream
ends and leaves the hub.  When the controller has stopped, the stream sends
what it has left (only what ends requests, if it is far behind) and ends.
"""
from __future__ import annotations

import asyncio

from starlette.requests import Request as HttpRequest
from starlette.responses import Response

from runtime.controller import RequestError
from runtime.services.eventlog import frame
from runtime.services.hub import EVENT_KINDS, Hub, Subscriber

#: Seconds without an event after which a stream sends a comment, so that proxies and clients see it alive.
KEEP_ALIVE = 15.0
HEADERS = {"Cache-Control": "no-cache", "X-Accel-Buffering": "no"}


class EventStream(Response):
    """The response of one ``/events`` request: the ASGI side of a :class:`~runtime.services.eventlog.Subscriber`."""

    media_type = "text/event-stream"

    def __init__(self, hub: Hub, sub: Subscriber, hello: dict) -> None:
        self.hub, self.sub, self.hello = hub, sub, hello
        self.status_code = 200
        self.background = None
        self.init_headers(HEADERS)

    async def __call__(self, scope, receive, send) -> None:
        """Send the hello, then batches of events as they come, until the client goes or the hub closes."""
        hub, sub = self.hub, self.sub
        gone = asyncio.Event()
        watcher = asyncio.ensure_future(self._watch(receive, gone))
        try:
            await send({"type": "http.response.start", "status": 200, "headers": self.raw_headers})
            await self._body(send, frame("hello", self.hello))
            while not gone.is_set() and not sub.cut:
                frames = sub.take(hub.log, closing=hub.closed)
                if frames:
                    await self._body(send, b"".join(frames))
                    await asyncio.sleep(0)  # a disconnection heard while the write waited is seen before the next
                    continue
                if hub.closed:
                    break
                if not await self._wait(sub) and not gone.is_set():
                    await self._body(send, b": keep-alive\n\n")
            if not gone.is_set():
                await send({"type": "http.response.body", "body": b"", "more_body": False})
        finally:
            watcher.cancel()
            hub.unsubscribe(sub)

    @staticmethod
    async def _body(send, data: bytes) -> None:
        await send({"type": "http.response.body", "body": data, "more_body": True})

    async def _wait(self, sub: Subscriber) -> bool:
        """Wait for the hub to wake this stream (True) or for the keep-alive time (False)."""
        sub.wake.clear()
        sub.waiting = True
        timer = asyncio.get_running_loop().call_later(KEEP_ALIVE, sub.wake.set)
        try:
            await sub.wake.wait()
        finally:
            sub.waiting = False
            timer.cancel()
        return sub.behind(self.hub.log) > 0 or self.hub.closed

    async def _watch(self, receive, gone: asyncio.Event) -> None:
        """Hear the client go away (``http.disconnect``) and wake the stream so that it ends at once."""
        while (await receive())["type"] != "http.disconnect":
            pass
        gone.set()
        self.sub.wake.set()


async def events(request: HttpRequest) -> Response:
    """The stream: a ``hello`` with the controller's summary, then the events of the kinds asked for."""
    controller, hub = request.app.state.controller, request.app.state.hub
    wanted = request.query_params.get("types")
    kinds = set(EVENT_KINDS) if not wanted else set(wanted.split(","))
    unknown = kinds - set(EVENT_KINDS)
    if unknown:
        raise RequestError(400, f"unknown event type(s) {', '.join(sorted(unknown))} "
                                f"(types: {', '.join(EVENT_KINDS)})")
    return EventStream(hub, hub.subscribe(kinds), controller.summary())
