"""``/events?types=report,poster``: server-sent events, fed by the hub, with a keep-alive every 15 s."""
from __future__ import annotations

import asyncio

from starlette.requests import Request as HttpRequest
from starlette.responses import Response, StreamingResponse

from runtime.controller import RequestError
from runtime.services.hub import EVENT_KINDS, Subscriber
from runtime.services.jsonio import dumps


async def events(request: HttpRequest) -> Response:
    """The stream: a ``hello`` with the controller's summary, then the events of the kinds asked for."""
    controller, hub = request.app.state.controller, request.app.state.hub
    wanted = request.query_params.get("types")
    kinds = set(EVENT_KINDS) if not wanted else set(wanted.split(","))
    unknown = kinds - set(EVENT_KINDS)
    if unknown:
        raise RequestError(400, f"unknown event type(s) {', '.join(sorted(unknown))} "
                                f"(types: {', '.join(EVENT_KINDS)})")
    sub = Subscriber(kinds)
    hub.subscribers.add(sub)

    async def stream():
        hub.streams += 1
        try:
            yield f"event: hello\ndata: {dumps(controller.summary())}\n\n"
            while True:
                try:
                    event = await asyncio.wait_for(sub.queue.get(), 15.0)
                except asyncio.TimeoutError:
                    yield ": keep-alive\n\n"
                    continue
                if event is None:
                    break
                yield f"event: {event['event']}\ndata: {dumps(event)}\n\n"
        finally:
            hub.subscribers.discard(sub)
            hub.streams -= 1

    return StreamingResponse(stream(), media_type="text/event-stream",
                             headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"})
