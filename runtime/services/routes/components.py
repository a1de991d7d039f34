"""``/components/...``: components, their services (GET one, POST a request to it) and their posters."""
from __future__ import annotations

from starlette.requests import Request as HttpRequest
from starlette.responses import Response

from runtime.controller import RequestError
from runtime.services.intake import parse_inputs, read_body, wait_time
from runtime.services.jsonio import JSONResponse
from runtime.services.views import component_view, components_view, service_view


async def components(request: HttpRequest) -> Response:
    return JSONResponse(components_view(request.app.state.controller.interface))


async def component(request: HttpRequest) -> Response:
    interface = request.app.state.controller.interface
    c = request.path_params["component"]
    if c not in interface["components"]:
        raise RequestError(404, f"no component {c!r} (components: {', '.join(interface['components'])})")
    return JSONResponse(component_view(interface, c))


async def service(request: HttpRequest) -> Response:
    """GET: the service; POST: a request to it, 202 with its URL, or its final report with ``?wait=``."""
    controller = request.app.state.controller
    c, s = request.path_params["component"], request.path_params["service"]
    controller.service(c, s)
    if request.method == "GET":
        return JSONResponse(service_view(controller.interface, c, s))
    inputs = parse_inputs(await read_body(request, f"{c}.{s}"), f"{c}.{s}")
    timeout = wait_time(request)
    req = controller.submit(c, s, inputs)
    if timeout is None:
        return JSONResponse({"id": req.id, "status": "queued", "url": f"/requests/{req.id}"}, status_code=202,
                            headers={"Location": f"/requests/{req.id}"})
    await request.app.state.hub.wait_final(controller, req.id, timeout)
    return JSONResponse(controller.snapshot(req.id))


async def poster(request: HttpRequest) -> Response:
    """The poster's last value, its age, and the failure that keeps it from being written, if any."""
    c, p = request.path_params["component"], request.path_params["port"]
    controller = request.app.state.controller
    controller.poster(c, p)  # 404 naming what exists
    return JSONResponse(controller.data.poster_view(c, p))
