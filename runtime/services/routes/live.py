"""The live page (``/live/``) and what only it asks for: the pictures of the model, the mission's scene.

The page's files (runtime/services/page/) are the same for every controller
and hold no data of it: they are served without the token, so that a browser,
which cannot add a header to a navigation, can load the page that asks for
it.  Everything the page then shows comes from routes behind the token, this
module's pictures and scene included (docs/live.md).
"""
from __future__ import annotations

import asyncio
from pathlib import Path

from starlette.requests import Request as HttpRequest
from starlette.responses import RedirectResponse, Response

from runtime.controller import RequestError
from runtime.services.jsonio import JSONResponse

PAGE = Path(__file__).resolve().parents[1] / "page"
#: The page's files by the name the page uses, with their media type; nothing else is served from PAGE.
FILES = {"": ("index.html", "text/html; charset=utf-8"), "live.js": ("live.js", "text/javascript; charset=utf-8"),
         "live.css": ("live.css", "text/css; charset=utf-8")}
#: The page runs only its own scripts and talks only to its own server; no other site may frame it.
PAGE_HEADERS = {
    "Content-Security-Policy": "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data:; "
                               "connect-src 'self'; frame-ancestors 'none'; base-uri 'none'; form-action 'none'",
    "X-Content-Type-Options": "nosniff", "Referrer-Policy": "no-referrer", "Cache-Control": "no-cache",
}
SVG = "image/svg+xml"


async def page_file(request: HttpRequest) -> Response:
    """``/live/`` and its scripts; an unknown name is a 404 like any route's."""
    name = request.path_params.get("name", "")
    if name not in FILES:
        raise RequestError(404, f"no file {name!r} in the live page (files: {', '.join(n for n in FILES if n)})")
    file, media = FILES[name]
    return Response((PAGE / file).read_bytes(), media_type=media, headers=PAGE_HEADERS)


async def to_page(request: HttpRequest) -> Response:
    return RedirectResponse("/live/", status_code=303)


async def level_picture(request: HttpRequest) -> Response:
    """The functional level as ``genom2bip graph`` draws it, as SVG (laid out once, then kept)."""
    return Response(await _picture(request, None), media_type=SVG)


async def module_picture(request: HttpRequest) -> Response:
    """One module as a compound (Fig. 7), as SVG."""
    module = request.path_params["module"]
    modules = _structure(request.app.state).modules
    if module not in modules:
        raise RequestError(404, f"no module {module!r} (modules: {', '.join(modules)})")
    return Response(await _picture(request, module), media_type=SVG)


async def scene(request: HttpRequest) -> Response:
    """The world of a mission run with ``--view`` (obstacles, bounds, goals, the pose poster), else 404."""
    found = request.app.state.scene
    if found is None:
        raise RequestError(404, "no scene: this controller is not running a mission (genom2bip mission --view)")
    return JSONResponse(found)


def _structure(state):
    """What the pictures draw, derived once from the controller's flat model and interface."""
    from runtime.pictures import structure

    if state.structure is None:
        controller = state.controller
        state.structure = structure(controller.engine.flat, controller.interface)
    return state.structure


async def _picture(request: HttpRequest, module: str | None) -> bytes:
    """The SVG of the level (``module`` None) or of a module, laid out in a worker thread and kept."""
    from runtime.pictures import PictureError, functional_level, layout
    from runtime.pictures import module as module_dot

    state = request.app.state
    kept = state.pictures.get(module)
    if kept is None:
        def draw() -> bytes:
            s = _structure(state)
            text = functional_level(s) if module is None else module_dot(s, module)
            return layout(text, "svg", what=f"the picture of {module or 'the functional level'}")
        kept = state.pictures[module] = asyncio.get_running_loop().run_in_executor(None, draw)
    try:
        return await kept
    except PictureError as exc:
        state.pictures.pop(module, None)
        raise RequestError(503, str(exc)) from None
