"""A variable only connectors read is dead once none of them can fire again: with a mission as client, a service's
``done`` flag is dead once the mission can no longer send a request that reads it (runtime/explore/layout.py)."""
from __future__ import annotations

import pytest

import runtime.explore.layout as layout
from genom2bip.verify.options import SearchOptions
from platformkit import FIXTURES
from runtime.engine.defines import required
from runtime.zones.search import ZoneExplorer
from test_platform_responses import AFTER, model_of

MISSION = FIXTURES / "set_then_go.yaml"


def explore(tmp_path, mission=MISSION):
    model = model_of(tmp_path, AFTER, {}, "cores: 1\n", mission)
    z = ZoneExplorer(model.package, model.root, SearchOptions().externs, engine="c")
    return z, z.explore()


def test_required_ports_are_those_in_every_interaction_of_a_define():
    p, q, r = ("p", 1), ("p", 2), ("p", 4)
    assert required(("g", ((p, False), (q, False), (r, False)))) == 7  # a rendezvous: every port
    assert required(("g", ((p, True), (q, False), (r, False)))) == 1  # one trigger: only it
    assert required(("g", ((p, True), (q, True), (r, False)))) == 0  # two triggers: either one alone
    assert required(("g", ((("g", ((p, False), (q, False))), False), (r, True)))) == 4  # the group is optional
    assert required(("g", ((("g", ((p, False), (q, False))), False), (r, False)))) == 7


def test_the_done_flag_is_live_only_while_the_mission_can_still_send_go(tmp_path):
    z, result = explore(tmp_path)
    assert result.complete
    slot = next(s for s in z.space.slots if s.title == "After.Setup.control.done")
    client = next(fa for fa in z.flat.atoms if fa.name == "client")
    assert slot.live == 0  # no transition of its own atom reads it: only the requests to Go do
    assert slot.alive == ((client.offset, client.place_mask([f"STEP{k}" for k in range(3)] +
                                                         [f"WAIT{k}" for k in range(2)])),)
    last_sent = client.place_mask(["WAIT2", "DONE"])
    seen = {(bool(n.state[client.offset] & last_sent), n.state[slot.index]) for n in z.nodes}
    assert seen == {(False, False), (False, True), (True, False)}  # past the last Go, never its success


def test_the_reduction_stores_fewer_states_and_changes_no_maximum_and_no_verdict(tmp_path, monkeypatch):
    z, on = explore(tmp_path)
    monkeypatch.setattr(layout, "connector_alive", lambda *a: None)  # every connector may always fire again
    z_off, off = explore(tmp_path)
    flag = next(s for s in z_off.space.slots if s.title == "After.Setup.control.done")
    assert flag.live is None and not flag.alive
    assert on.complete and off.complete
    assert on.discrete < off.discrete and on.states < off.states
    assert on.maxima.keys() == off.maxima.keys()
    assert {k: v[0] for k, v in on.maxima.items()} == {k: v[0] for k, v in off.maxima.items()}
    assert on.violations.keys() == off.violations.keys()


@pytest.mark.parametrize("engine", ["python", "c"])
def test_both_searches_reset_the_flag_alike(tmp_path, engine):
    model = model_of(tmp_path, AFTER, {}, "cores: 1\n", MISSION)
    z = ZoneExplorer(model.package, model.root, SearchOptions().externs, engine=engine)
    result = z.explore()
    assert (result.states, result.discrete) == (94, 68)
    every = ZoneExplorer(model.package, model.root, SearchOptions().externs, engine=engine, prune=False).explore()
    assert (every.states, every.discrete) == (98, 68)  # every node expanded: the covered ones' subtrees too
