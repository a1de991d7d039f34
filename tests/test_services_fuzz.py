"""Property-based attacks on the services interface: whatever the path, query, headers or body, a 4xx at worst.

One DALA controller serves every example (module fixture); each answer must
be below 500 and, when it is an error, the JSON ``{"error", "status"}`` the
interface promises; nothing may print a traceback, and the controller must
still be running at the end.
"""
from __future__ import annotations

import http.client
import json
from urllib.parse import quote

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from runkit import serving_dala

SERVICES = [f"/components/{c}/services/{s}" for c, s in (
    ("NDD", "SetSpeed"), ("NDD", "GoTo"), ("NDD", "SetParams"), ("NDD", "SetDataSource"), ("POM", "Run"),
    ("LaserRF", "SetConfig"), ("RFLEX", "Init"), ("RFLEX", "SetAcceleration"), ("Aspect", "SetParams"))]
GETS = ["/", "/components", "/components/NDD", "/components/NDD/ports/Speed", "/requests", "/requests/1",
        "/tasks", "/openapi.json", "/components/NDD/services/GoTo"]

json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-2 ** 70, 2 ** 70) | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=20),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.sampled_from(
        ["max_speed", "v", "w", "goal", "x", "y", "theta", "obs", "device", "beams", "acceleration_max", "z"])
        | st.text(max_size=8), inner, max_size=4),
    max_leaves=20)


def _body(value) -> bytes:
    return json.dumps(value, allow_nan=True).encode()


bodies = st.one_of(json_values.map(_body), st.binary(max_size=200),
                   st.sampled_from([b"", b"{", b"[" * 5000, b'{"max_speed": 1e999}', b"-" + b"9" * 5000]))
queries = st.one_of(st.just(""), st.builds(lambda k, v: f"?{k}={quote(v)}",
                                           st.sampled_from(["wait", "limit", "status", "types", "x"]),
                                           st.text(max_size=12)))
paths = st.one_of(st.sampled_from(GETS + SERVICES),
                  st.text(alphabet="/abcNDGoT0123%.-_", max_size=30).map(lambda t: "/" + t.lstrip("/")))
headers = st.fixed_dictionaries({}, optional={
    "Content-Type": st.sampled_from(["application/json", "text/plain", "application/json; charset=utf-8", "", "x"]),
    "Origin": st.sampled_from(["http://evil.example", "null", ""]),
    "Authorization": st.text(alphabet=st.characters(min_codepoint=32, max_codepoint=126), max_size=10)})


@pytest.fixture(scope="module")
def served():
    with serving_dala() as running:
        yield running


def _answer(server, method: str, path: str, body: bytes | None, extra: dict) -> tuple[int, bytes, str]:
    conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=20)
    try:
        conn.request(method, path, body=body, headers=extra)
        response = conn.getresponse()
        return response.status, response.read(), response.getheader("Content-Type") or ""
    finally:
        conn.close()


def _check(status: int, raw: bytes, kind: str) -> None:
    assert status < 500, raw[:300]
    if status >= 400 and kind.startswith("application/json") and raw:  # HEAD: no body
        data = json.loads(raw)
        assert data["status"] == status and isinstance(data["error"], str) and data["error"]


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                   HealthCheck.too_slow])
@given(path=st.sampled_from(SERVICES), query=st.sampled_from(["", "?wait=0.2"]), body=bodies, extra=headers)
def test_posts_of_anything_to_a_service_get_an_answer_below_500(served, path, query, body, extra):
    controller, server, _ = served
    _check(*_answer(server, "POST", path + query, body, extra))
    assert controller.status == "running"


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                   HealthCheck.too_slow])
@given(method=st.sampled_from(["GET", "POST", "PUT", "DELETE", "HEAD"]), path=paths, query=queries, extra=headers)
def test_any_method_path_and_query_get_an_answer_below_500(served, method, path, query, extra):
    controller, server, _ = served
    if path == "/events" or path.startswith("/events?"):
        return  # a stream, not an answer
    body = b"{}" if method in ("POST", "PUT") else None
    _check(*_answer(server, method, quote(path, safe="/%") + query, body, extra))
    assert controller.status == "running"


def test_the_fuzzing_printed_no_traceback(served, capfd):
    _, server, _ = served
    for body in (b"[" * 100_000, b'{"max_speed": {"v": ' + b"7" * 5000 + b"}}", b"null", b"\x00\xff"):
        _check(*_answer(server, "POST", SERVICES[0], body, {"Content-Type": "application/json"}))
    err = capfd.readouterr().err
    assert "Traceback" not in err and "Exception in ASGI" not in err, err
