"""What an HTTP request carries, read within bounds: its body as JSON inputs, request ids, ``?wait=`` times.

Anything malformed or too large is a :class:`~runtime.controller.RequestError`
(400, 413, 422) naming what is wrong, never an exception of the server.
"""
from __future__ import annotations

import json
from typing import Any

from starlette.requests import ClientDisconnect, Request as HttpRequest

from runtime.controller import RequestError

#: Longest a client may wait for a report in one HTTP call (s); it asks again for longer waits.
MAX_WAIT = 60.0
#: Largest request body accepted (bytes): refused as it streams in, so memory stays bounded.
MAX_BODY = 1 << 20
#: Deepest nesting of arrays and objects accepted in a request body.
MAX_DEPTH = 64


async def read_body(request: HttpRequest, what: str) -> bytes:
    """The body, read as it streams in and refused (413) past :data:`MAX_BODY` bytes, whatever the client says."""
    declared = request.headers.get("content-length")
    if declared is not None:
        if not declared.isdigit():
            raise RequestError(400, f"Content-Length {declared!r} is not a number of bytes")
        if int(declared) > MAX_BODY:
            raise RequestError(413, f"request body of {declared} bytes to {what}: at most {MAX_BODY} accepted")
    chunks: list[bytes] = []
    size = 0
    try:
        async for chunk in request.stream():
            size += len(chunk)
            if size > MAX_BODY:
                raise RequestError(413, f"request body to {what} longer than {MAX_BODY} bytes: refused")
            chunks.append(chunk)
    except ClientDisconnect:
        raise RequestError(400, f"the client disconnected before sending the whole body to {what}") from None
    return b"".join(chunks)


def _depth(value: Any) -> int:
    """How deeply arrays and objects nest in ``value`` (without recursion: the value may come from anyone)."""
    deepest, todo = 0, [(value, 1)]
    while todo:
        v, d = todo.pop()
        if isinstance(v, (dict, list)):
            deepest = max(deepest, d)
            if d <= MAX_DEPTH:
                todo.extend((x, d + 1) for x in (v.values() if isinstance(v, dict) else v))
    return deepest


def parse_inputs(body: bytes, what: str) -> Any:
    """A request body as JSON data: 400 naming what is wrong, for anything the JSON parser or its limits refuse."""
    try:
        text = body.decode()
    except UnicodeDecodeError as err:
        raise RequestError(400, f"the body of the request to {what} is not UTF-8: {err}") from None
    if not text.strip():
        return {}
    try:
        value = json.loads(text)
    except json.JSONDecodeError as err:
        raise RequestError(400, f"malformed JSON in the body of the request to {what}: {err}") from None
    except RecursionError:
        raise RequestError(400, f"the body of the request to {what} nests arrays or objects too deeply "
                                f"(at most {MAX_DEPTH} levels)") from None
    except ValueError as err:  # e.g. an integer of more than 4300 digits
        raise RequestError(400, f"unreadable JSON in the body of the request to {what}: {err}") from None
    if _depth(value) > MAX_DEPTH:
        raise RequestError(400, f"the body of the request to {what} nests arrays or objects too deeply "
                                f"(at most {MAX_DEPTH} levels)")
    if value is None:
        raise RequestError(422, f"the parameters of {what} must be a JSON object, not null (send {{}} or "
                                "nothing for the defaults)")
    return value


def whole_number(text: str) -> int | None:
    """``text`` as the server writes a whole number (ASCII digits, no sign, space, ``_`` or leading zero), else None.

    ``int()`` also reads ``1_0``, `` 10``, ``+10`` and other scripts' digits: each would name request 10.
    """
    if not (text.isascii() and text.isdigit()) or len(text) > 18 or (text[0] == "0" and len(text) > 1):
        return None
    return int(text)


def request_id(text: str) -> int:
    number = whole_number(text)
    if number is None:
        raise RequestError(400, f"request id {text!r} is not a number as the server writes them "
                                "(digits 0-9, no sign, no leading zero)")
    return number


def wait_time(request: HttpRequest) -> float | None:
    """``?wait=SECONDS`` (``?wait`` alone: the longest), at most :data:`MAX_WAIT`; None when not asked."""
    text = request.query_params.get("wait")
    if text is None:
        return None
    try:
        value = float(text) if text not in ("", "true") else MAX_WAIT
    except ValueError:
        raise RequestError(400, f"wait={text!r}: a number of seconds expected") from None
    if not value >= 0:
        raise RequestError(400, f"wait={text!r}: a number of seconds >= 0 expected")
    return min(value, MAX_WAIT)
