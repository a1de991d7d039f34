"""The routes of the services interface, one module per resource group (docs/runtime.md has the shapes).

Handlers find the controller and the event hub in ``request.app.state``.
"""
from __future__ import annotations

from starlette.routing import Route

from runtime.services.routes import components, events, live, requests, system


def routes() -> list[Route]:
    return [
        Route("/", system.index),
        Route("/openapi.json", system.spec),
        Route("/components", components.components),
        Route("/components/{component}", components.component),
        Route("/components/{component}/services/{service}", components.service, methods=["GET", "POST"]),
        Route("/components/{component}/ports/{port}", components.poster),
        Route("/requests", requests.requests_list),
        Route("/requests/{id}", requests.request_one),
        Route("/events", events.events),
        Route("/tasks", system.tasks),
        Route("/live", live.to_page),
        Route("/live/", live.page_file),
        Route("/live/{name}", live.page_file),
        Route("/pictures/level.svg", live.level_picture),
        Route("/pictures/modules/{module}.svg", live.module_picture),
        Route("/scene", live.scene),
    ]
