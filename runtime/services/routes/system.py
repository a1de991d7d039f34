"""``/``: the controller at a glance; ``/tasks``: periods, lateness and overruns; ``/openapi.json``."""
from __future__ import annotations

from starlette.requests import Request as HttpRequest
from starlette.responses import Response

from runtime.services.jsonio import JSONResponse
from runtime.services.openapi import openapi

LINKS = {"components": "/components", "requests": "/requests", "events": "/events", "tasks": "/tasks",
         "openapi": "/openapi.json"}


async def index(request: HttpRequest) -> Response:
    """The controller's summary, with the event streams at a glance (how many, how many behind, what they lost)."""
    return JSONResponse(request.app.state.controller.summary() | {"events": request.app.state.hub.stats(),
                                                                    "links": LINKS})


async def tasks(request: HttpRequest) -> Response:
    return JSONResponse(request.app.state.controller.timers.stats())


async def spec(request: HttpRequest) -> Response:
    return JSONResponse(openapi(request.app.state.controller.interface))
