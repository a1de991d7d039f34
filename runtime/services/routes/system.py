"""``/``: the controller at a glance (a browser is sent to the live page); ``/tasks``; ``/openapi.json``."""
from __future__ import annotations

from starlette.requests import Request as HttpRequest
from starlette.responses import Response

from runtime.services.jsonio import JSONResponse
from runtime.services.guard import is_page
from runtime.services.routes.live import to_page
from runtime.services.openapi import openapi

LINKS = {"components": "/components", "requests": "/requests", "events": "/events", "tasks": "/tasks",
         "openapi": "/openapi.json", "page": "/live/"}


async def index(request: HttpRequest) -> Response:
    """The controller's summary, with the event streams at a glance; a browser opening it is sent to the page."""
    if is_page(request.method, "/", request.headers.get("accept", "")):
        return await to_page(request)
    return JSONResponse(request.app.state.controller.summary() | {"events": request.app.state.hub.stats(),
                                                                    "links": LINKS})


async def tasks(request: HttpRequest) -> Response:
    return JSONResponse(request.app.state.controller.timers.stats())


async def spec(request: HttpRequest) -> Response:
    return JSONResponse(openapi(request.app.state.controller.interface))
