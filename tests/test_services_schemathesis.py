"""Schema-driven attacks on the services interface: schemathesis reads the OpenAPI document the server serves.

Every operation of ``/openapi.json`` (each service's POST with its inputs'
schema, the generic routes) gets examples that follow the schema and
examples that break it, sent to a live DALA controller: no answer may be a
5xx or an undocumented status, every error must be the JSON
``{"error", "status"}`` the document promises, the server must print no
traceback, and the controller must still be running at the end.

schemathesis is used through its Python API (the document, its operations,
each operation's hypothesis strategy), not its pytest plugin: the plugin
reaches into pytest's private attributes and broke with a new pytest
(docs/dependencies.md).  The document is the one the server builds from the
generated interface; the first test checks that the server serves exactly it.
"""
from __future__ import annotations

import json

import pytest
import schemathesis
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from schemathesis import GenerationMode

from runkit import dala, serving_dala
from runtime.services.openapi import openapi

#: Examples per operation, following or breaking its schemas: 47 operations, ~30 s on the development machine.
EXAMPLES = 10

DOCUMENT = openapi(dala().INTERFACE)
# the event stream never ends: it has its own tests (tests/test_services_http.py)
SCHEMA = schemathesis.openapi.from_dict(DOCUMENT).exclude(path="/events")
OPERATIONS = [result.ok() for result in SCHEMA.get_all_operations()]


@pytest.fixture(scope="module")
def served():
    with serving_dala() as running:
        yield running


def test_the_fuzzed_document_is_the_one_the_server_serves(served):
    _, _, client = served
    assert client.openapi() == DOCUMENT
    assert len(OPERATIONS) >= 40 and all(op.path != "/events" for op in OPERATIONS)


@pytest.mark.parametrize("operation", OPERATIONS, ids=lambda op: op.label)
def test_every_operation_of_the_openapi_document_answers_below_500_as_documented(operation, served, capfd):
    controller, server, _ = served
    cases = st.one_of([operation.as_strategy(generation_mode=mode) for mode in GenerationMode])

    @given(cases)
    @settings(max_examples=EXAMPLES, deadline=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
    def answers_as_documented(case):
        if case.query and "wait" in case.query:
            case.query["wait"] = 0  # an activity may never end: do not hold a worker for a minute
        response = case.call(base_url=server.url, timeout=20)
        assert response.status_code < 500, response.text[:300]
        if case.method.lower() == operation.method.lower():  # not a method the operation lacks (405 then)
            documented = operation.definition.raw.get("responses", {})
            assert str(response.status_code) in documented, (response.status_code, response.text[:300])
        if response.status_code >= 400:
            data = json.loads(response.content)
            assert data["status"] == response.status_code and data["error"], data
        assert controller.status == "running"

    answers_as_documented()
    err = capfd.readouterr().err
    assert "Traceback" not in err and "Exception in ASGI" not in err, err
