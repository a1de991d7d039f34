"""A variable only connectors read is dead once none of them can fire again: with a mission as client, a service's
``done`` flag is dead once the mission can no longer send a request that reads it (runtime/explore/layout.py)."""
from __future__ import annotations

import dataclasses

import pytest

import runtime.explore.conjunctions as conjunctions
import runtime.explore.layout as layout
from genom2bip.verify.options import SearchOptions
from platformkit import FIXTURES
from runtime.engine.defines import required
from runtime.model.expressions import Unary
from runtime.zones.search import ZoneExplorer
from test_platform_responses import AFTER, AFTER_BOTH, model_of

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


BOTH = FIXTURES / "set_both_then_go.yaml"


def explore_both(tmp_path, reduce_conjunctions=True, monkeypatch=None):
    if not reduce_conjunctions:
        monkeypatch.setattr(layout, "dead_with", lambda flat: {})
    model = model_of(tmp_path, AFTER_BOTH, {}, "cores: 1\n", BOTH)
    z = ZoneExplorer(model.package, model.root, SearchOptions().externs, engine="c")
    return z, z.explore()


def _frozen_false(z, state, service: str, past: list[str]) -> bool:
    """``service``'s done flag is false, its control idle and the mission past the steps that send it."""
    flag = next(s for s in z.space.slots if s.title == f"AfterBoth.{service}.control.done")
    control = next(fa for fa in z.flat.atoms if fa.name == f"AfterBoth.{service}.control")
    client = next(fa for fa in z.flat.atoms if fa.name == "client")
    return (not state[flag.index] and bool(state[control.offset] & control.place_mask(["IDLE"]))
            and bool(state[client.offset] & client.place_mask(past)))


def test_flags_read_only_together_are_each_dead_once_the_other_is_false_for_good(tmp_path):
    """Go's requests read SetA's and SetB's done flags only together (its ``after``): one is dead where the other is
    false, its service idle and the mission past the step that sends it, and nowhere else."""
    z, result = explore_both(tmp_path)
    assert result.complete
    slots = {s.title: s for s in z.space.slots}
    a, b = slots["AfterBoth.SetA.control.done"], slots["AfterBoth.SetB.control.done"]
    assert [g for g, _, _ in a.void] == [b.index] and [g for g, _, _ in b.void] == [a.index]
    assert not any(s.void for t, s in slots.items() if t not in (a.title, b.title))
    after_b = ["WAIT1", "STEP2", "WAIT2", "STEP3", "WAIT3", "DONE"]
    after_a = ["WAIT0", "STEP1"] + after_b
    states = [n.state for n in z.nodes]
    assert all(not s[a.index] for s in states if _frozen_false(z, s, "SetB", after_b))
    assert all(not s[b.index] for s in states if _frozen_false(z, s, "SetA", after_a))
    assert any(_frozen_false(z, s, "SetB", after_b) for s in states)  # the case happens
    assert any(s[a.index] for s in states)  # and SetA's flag is kept elsewhere


def test_the_conjunction_reduction_stores_fewer_states_and_changes_no_maximum_and_no_verdict(tmp_path, monkeypatch):
    z, on = explore_both(tmp_path)
    z_off, off = explore_both(tmp_path, False, monkeypatch)
    a = next(s for s in z_off.space.slots if s.title == "AfterBoth.SetA.control.done")
    assert not a.void and a.alive  # without it, the flag is dead only once no Go can come
    assert any(_frozen_false(z_off, n.state, "SetB", ["WAIT1", "STEP2", "WAIT2", "STEP3", "WAIT3", "DONE"])
               and n.state[a.index] for n in z_off.nodes)  # what the reduction merges
    assert on.complete and off.complete
    assert (on.states, on.discrete) == (166, 116) and (off.states, off.discrete) == (190, 132)
    assert {k: v[0] for k, v in on.maxima.items()} == {k: v[0] for k, v in off.maxima.items()}
    assert on.violations.keys() == off.violations.keys()


def test_a_flag_read_alone_or_outside_a_conjunction_is_not_a_conjunctions(tmp_path):
    """After's Go reads Setup's flag alone: no other flag can make it dead.  A flag some guard reads outside a
    conjunction is not either, nor are the flags read with it."""
    model = model_of(tmp_path, AFTER, {}, "cores: 1\n", MISSION)
    flat = ZoneExplorer(model.package, model.root, SearchOptions().externs).flat
    assert conjunctions.dead_with(flat) == {}
    model = model_of(tmp_path, AFTER_BOTH, {}, "cores: 1\n", BOTH)
    z = ZoneExplorer(model.package, model.root, SearchOptions().externs)
    found = conjunctions.dead_with(z.flat)
    a, b = (z.flat.atoms[i].slot("done") for i in (next(fa.index for fa in z.flat.atoms if fa.name == n)
                                                   for n in ("AfterBoth.SetA.control", "AfterBoth.SetB.control")))
    assert set(found) == {a, b}
    refuse, k = next((fc, k) for fc in z.flat.connectors for k, spec in enumerate(fc.type.interactions)
                     if isinstance(spec.guard, Unary))  # Go refused: !(SetA done && SetB done)
    specs = list(refuse.type.interactions)
    specs[k] = dataclasses.replace(specs[k], guard=specs[k].guard.operand.left)  # one flag read on its own
    refuse.type = dataclasses.replace(refuse.type, interactions=specs)
    assert conjunctions.dead_with(z.flat) == {}
