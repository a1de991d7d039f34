"""Schema-driven attacks on the services interface: schemathesis reads the OpenAPI document the server serves.

Every operation of ``/openapi.json`` (each service's POST with its inputs'
schema, the generic routes) gets examples that follow the schema and
examples that break it, sent to a live DALA controller: no answer may be a
5xx or an undocumented status, every error must be the JSON
``{"error", "status"}`` the document promises, the server must print no
traceback, and the controller must still be running at the end.
"""
from __future__ import annotations

import json

import pytest
import schemathesis
from hypothesis import HealthCheck, settings

from runkit import serving_dala

#: Examples per operation: 47 operations, ~30 s on the development machine.
EXAMPLES = 10


@pytest.fixture(scope="module")
def served():
    with serving_dala() as running:
        yield running


@pytest.fixture(scope="module")
def api(served):
    _, server, client = served
    return schemathesis.openapi.from_dict(client.openapi())


# the event stream never ends: it has its own tests (tests/test_services_http.py)
schema = schemathesis.pytest.from_fixture("api").exclude(path="/events")


@schema.parametrize()
@settings(max_examples=EXAMPLES, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                                 HealthCheck.filter_too_much])
def test_every_operation_of_the_openapi_document_answers_below_500_as_documented(case, served, capfd):
    controller, server, _ = served
    if case.query and "wait" in case.query:
        case.query["wait"] = 0  # an activity may never end: do not hold a worker for a minute
    response = case.call(base_url=server.url, timeout=20)
    assert response.status_code < 500, response.text[:300]
    if case.method.lower() == case.operation.method.lower():  # not a method the operation lacks (405 then)
        documented = case.operation.definition.raw.get("responses", {})
        assert str(response.status_code) in documented, (response.status_code, response.text[:300])
    if response.status_code >= 400:
        data = json.loads(response.content)
        assert data["status"] == response.status_code and data["error"], data
    assert controller.status == "running"
    err = capfd.readouterr().err
    assert "Traceback" not in err and "Exception in ASGI" not in err, err
