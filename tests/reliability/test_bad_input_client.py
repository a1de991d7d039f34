"""``verify --client MISSION``: the inputs of the mission's requests (``with:``) get the check ``genom2bip mission``
gives them, located the same: one mission file means one thing to both."""
from __future__ import annotations

import pytest

from badinputkit import DALA, genom2bip

pytestmark = pytest.mark.reliability

BAD = "mission: c\nsteps:\n  - send: NDD.GoTo\n    with: {goal: {x: fast}, bogus: 1}\n"


def test_inputs_the_controller_would_refuse_make_verify_client_fail_where_mission_does(tmp_path):
    mission = tmp_path / "c.yaml"
    mission.write_text(BAD)
    verify = genom2bip("verify", DALA / "NDD.gen", "--no-rules", "--timed", "--client", mission)
    assert verify.code == 1, verify.out + verify.err
    assert "no overrun" not in verify.out and "internal error" not in verify.err
    first = verify.err.splitlines()[0]
    assert first == f"{mission}:4:11: error: with: the controller would refuse this request to NDD.GoTo: unknown " \
                    "parameter 'bogus' (parameters of NDD.GoTo: goal); goal.x: expected a number, got 'fast'; " \
                    "goal: missing member 'y'; goal: missing member 'theta'", verify.err
    run = genom2bip("mission", mission, "--out", tmp_path / "out", "--quiet")
    assert run.code == 1 and run.err.splitlines()[0] == first, run.err
    assert not (tmp_path / "out").exists()


def test_inputs_the_controller_takes_are_taken_by_verify_client(tmp_path):
    mission = tmp_path / "c.yaml"
    mission.write_text("mission: c\nsteps:\n  - send: NDD.SetSpeed\n    with: {max_speed: {v: 0.4, w: 0.1}}\n")
    verify = genom2bip("verify", DALA / "NDD.gen", "--no-rules", "--timed", "--client", mission)
    assert "with:" not in verify.err and "internal error" not in verify.err, verify.err
    assert verify.code in (0, 4), verify.out + verify.err  # a verdict, whichever it is
