"""The DALA rules (descriptions/dala/rules.yaml) at run time, through the services interface."""
from __future__ import annotations

import pytest
import requests
import schemathesis

from runkit import DALA_CODELS, ORIGIN, dala, ndd_settings, serving_dala, until
from runtime.controller import Controller, VirtualClock

GOAL = {"x": 1000.0, "y": 0.0, "theta": 0.0}  # far away: GoTo keeps running until something stops it


@pytest.fixture
def client():
    with serving_dala() as (_, _, running_client):
        yield running_client


def running(client, component, service, **inputs):
    rid = client.send(component, service, **inputs)
    until(lambda: client.request(rid)["status"] == "running")
    return rid


def sensors_and_settings(client):
    """Everything a GoTo needs except POM.Run and the base tracking."""
    assert client.call("LaserRF", "Init", timeout=5)["status"] == "ok"
    assert client.call("RFLEX", "Init", timeout=5)["status"] == "ok"
    running(client, "LaserRF", "Start")
    running(client, "Aspect", "Run")
    ndd_settings(client)


def test_a_refusing_rule_is_named_in_the_rejection(client):
    sensors_and_settings(client)
    running(client, "RFLEX", "TrackSpeed")
    report = client.call("NDD", "GoTo", goal=GOAL, timeout=5)
    assert report["status"] == "rejected" and report["rule"] == "goto-after-pom-run"
    assert report["status_of"] == {"POM.Run": {"done": False, "ok": False, "running": False}}
    assert client.call("POM", "Run", origin=ORIGIN, timeout=5)["status"] == "ok"
    goto = running(client, "NDD", "GoTo", goal=GOAL)
    assert [r["status"] for r in client.request(goto)["reports"]] == ["queued", "started"]


def test_a_waiting_rule_holds_the_request_then_lets_it_proceed(client):
    sensors_and_settings(client)
    assert client.call("POM", "Run", origin=ORIGIN, timeout=5)["status"] == "ok"
    goto = client.send("NDD", "GoTo", goal=GOAL)
    until(lambda: any(r["status"] == "held" for r in client.request(goto)["reports"]))
    held = next(r for r in client.request(goto)["reports"] if r["status"] == "held")
    assert held["rules"] == ["goto-waits-for-base"] and not held["final"]
    assert held["message"] == "NDD.GoTo held by rule goto-waits-for-base until it allows the request"
    assert held["status_of"]["RFLEX.TrackSpeed"]["running"] is False
    running(client, "RFLEX", "TrackSpeed")
    until(lambda: client.request(goto)["status"] == "running")
    assert [r["status"] for r in client.request(goto)["reports"]] == ["queued", "held", "started"]


def test_a_held_request_is_answered_as_the_published_openapi_document_says(client):
    """The document served at /openapi.json lists every report status the controller emits, ``held`` included."""
    sensors_and_settings(client)
    assert client.call("POM", "Run", origin=ORIGIN, timeout=5)["status"] == "ok"
    goto = client.send("NDD", "GoTo", goal=GOAL)
    until(lambda: any(r["status"] == "held" for r in client.request(goto)["reports"]))
    operation = schemathesis.openapi.from_dict(client.openapi())["/requests/{id}"]["GET"]
    response = requests.get(f"{client.url}/requests/{goto}", timeout=10)
    assert response.status_code == 200 and "held" in [r["status"] for r in response.json()["reports"]]
    operation.validate_response(response)  # raises, naming the field, where the document disagrees


def test_a_request_that_arrives_while_the_next_step_is_chosen_is_not_reported_held():
    """A request queued after the ready interactions were listed, before the look for held ones, is not held.

    On a loaded machine the services thread often queues a request at that moment: POM.Reset, which
    ``no-reset-while-navigating`` allows when no GoTo runs, was reported held by that rule.
    """
    pkg = dala()
    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, str(DALA_CODELS), clock=VirtualClock())
    choose, sent = controller.choice.choose, {}

    def choose_then_receive(*args):
        chosen = choose(*args)
        if not sent:
            sent["reset"] = controller.submit("POM", "Reset")
        return chosen

    controller.choice.choose = choose_then_receive
    controller.run(duration=0.5)
    # the stub codels leave pomReset out: Reset starts, then fails naming it
    assert [r["status"] for r in sent["reset"].reports] == ["queued", "started", "failed"]

def test_stopping_the_base_interrupts_the_navigation_in_another_module(client):
    sensors_and_settings(client)
    assert client.call("POM", "Run", origin=ORIGIN, timeout=5)["status"] == "ok"
    running(client, "RFLEX", "TrackSpeed")
    goto = running(client, "NDD", "GoTo", goal=GOAL)
    stop = client.call("RFLEX", "Stop", timeout=5)
    assert stop["status"] == "ok"
    report = client.wait(goto, timeout=5)
    assert report["status"] == "interrupted" and report["by"] == "RFLEX.Stop"
    assert report["by_request"] == stop["request"]


def test_mutual_exclusion_holds_reset_while_goto_runs(client):
    sensors_and_settings(client)
    assert client.call("POM", "Run", origin=ORIGIN, timeout=5)["status"] == "ok"
    running(client, "RFLEX", "TrackSpeed")
    goto = running(client, "NDD", "GoTo", goal=GOAL)
    reset = client.send("POM", "Reset")
    until(lambda: client.request(reset)["status"] == "queued"
          and any(r["status"] == "held" for r in client.request(reset)["reports"]))
    assert client.request(goto)["status"] == "running"
    assert client.call("NDD", "Stop", timeout=5)["status"] == "ok"
    assert client.wait(goto, timeout=5)["status"] == "interrupted"
    # Reset starts once GoTo has ended; the stub codels leave pomReset out, so it then fails naming it.
    final = client.wait(reset, timeout=5)
    assert [r["status"] for r in client.request(reset)["reports"]] == ["queued", "held", "started", "failed"]
    assert final["codel"] == "pomReset"


CANCEL = """
component cx {
  task t { period 10 ms; };
  activity Move() {
    task t;
    validate check();
    codel <start> mv() yield pause::start, ether;
  };
  function Halt() {
    interrupts Move;
  };
};
"""


def test_a_request_accepted_but_not_started_is_interrupted_too(tmp_path):
    """Halt queued while Move is being validated: Move ends interrupted whichever of the two goes first."""
    from runkit import build
    from runtime.controller import VirtualClock

    package, root, interface = build(tmp_path, CANCEL, "cx")
    seen = set()
    for seed in range(1, 30):
        holder = {}

        def check():
            holder["halt"] = holder["controller"].submit("cx", "Halt")  # arrives while Move is validated
            return "ok"

        codels = {"cx": {"check": check, "mv": lambda: "pause::start"}}
        controller = Controller(package, root, interface, codels, clock=VirtualClock(), seed=seed)
        holder["controller"] = controller
        move = controller.submit("cx", "Move")
        controller.run(duration=0.2)
        assert move.final["status"] == "interrupted" and move.final["by"] == "cx.Halt", move.final
        assert move.final["by_request"] == holder["halt"].id
        seen.add(tuple(r["status"] for r in move.reports))
        if len(seen) == 2:
            break
    assert seen == {("queued", "started", "interrupted"), ("queued", "interrupted")}
