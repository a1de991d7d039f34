"""``/requests``: recent requests (``?status=``, ``?limit=``); ``/requests/{id}``: one, waiting with ``?wait=``."""
from __future__ import annotations

from starlette.requests import Request as HttpRequest
from starlette.responses import Response

from runtime.controller import REQUEST_STATUSES, RequestError
from runtime.services.intake import request_id, wait_time, whole_number
from runtime.services.jsonio import JSONResponse


async def requests_list(request: HttpRequest) -> Response:
    controller = request.app.state.controller
    status = request.query_params.get("status")
    if status is not None and status not in REQUEST_STATUSES:
        raise RequestError(400, f"status={status!r}: one of {', '.join(REQUEST_STATUSES)} expected")
    text = request.query_params.get("limit", "100")
    limit = whole_number(text) or 0 if len(text) < 10 else 0
    if limit < 1:
        raise RequestError(400, f"limit={text!r}: a number of requests from 1 to 999999999 expected")
    ids = sorted(controller.requests, reverse=True)
    rows = []
    for rid in ids:
        req = controller.requests.get(rid)
        if req is None or (status and req.status != status):
            continue
        rows.append({"id": req.id, "component": req.component, "service": req.service, "status": req.status})
        if len(rows) >= limit:
            break
    return JSONResponse(rows)


async def request_one(request: HttpRequest) -> Response:
    controller = request.app.state.controller
    rid = request_id(request.path_params["id"])
    controller.get(rid)
    timeout = wait_time(request)
    if timeout:
        await request.app.state.hub.wait_final(controller, rid, timeout)
    return JSONResponse(controller.snapshot(rid))
