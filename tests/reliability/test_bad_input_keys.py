"""YAML keys that no reader can use: a list or a mapping as a key, a key given twice, two steps of a mission with
one name.  Each is located (exit 1) in every kind of file, and nothing is written."""
from __future__ import annotations

import pytest

from badinputkit import DALA, ROOT, genom2bip

pytestmark = pytest.mark.reliability

PAIR = ROOT / "tests" / "fixtures" / "platform" / "Pair.gen"
LIST_KEY = "? [a]\n: 1\n"
MAP_KEY = "? {a: 1}\n: 1\n"


def _refused(done, path, where: str, message: str) -> None:
    assert done.code == 1, done.out + done.err
    assert "internal error" not in done.err and "Traceback" not in done.err, done.err
    assert done.err.startswith(f"{path}:{where}: error: {message}\n"), done.err


@pytest.mark.parametrize("key, kind", [(LIST_KEY, "a list"), (MAP_KEY, "a mapping")])
def test_a_collection_as_a_key_of_a_platform_file_is_located(tmp_path, key, kind):
    platform = tmp_path / "p.yaml"
    platform.write_text("cores: 1\n" + key)
    done = genom2bip("verify", PAIR, "--timed", "--platform", platform)
    _refused(done, platform, "2:3", f"a key is a single value (a name), not {kind}")


@pytest.mark.parametrize("key, kind", [(LIST_KEY, "a list"), (MAP_KEY, "a mapping")])
def test_a_collection_as_a_key_of_a_rule_file_is_located_and_nothing_is_generated(tmp_path, key, kind):
    rules = tmp_path / "rules.yaml"
    rules.write_text("rules: []\n" + key)
    done = genom2bip(DALA, "--rules", rules, "-o", tmp_path / "out")
    _refused(done, rules, "2:3", f"a key is a single value (a name), not {kind}")
    assert not (tmp_path / "out").exists()


def test_a_collection_as_a_key_of_an_observer_file_is_located(tmp_path):
    observers = tmp_path / "observers.yaml"
    observers.write_text("observers:\n  - name: a\n    ? [from]\n    : LaserRF.Scan:write\n")
    done = genom2bip("verify", DALA, "--timed", "--observers", observers)
    _refused(done, observers, "3:7", "a key is a single value (a name), not a list")


@pytest.mark.parametrize("text, where", [
    ("mission: m\nsteps:\n  - ? [send]\n    : NDD.Stop\n", "3:7"),  # a step's key
    ("mission: m\n" + LIST_KEY + "steps: []\n", "2:3"),  # the file's key
    ("mission: m\nsteps:\n  - send: NDD.SetSpeed\n    with: {? [max_speed] : 1}\n", "4:14"),  # among the inputs
])
def test_a_collection_as_a_key_of_a_mission_is_located_before_it_runs(tmp_path, text, where):
    mission = tmp_path / "m.yaml"
    mission.write_text(text)
    done = genom2bip("mission", mission, "--out", tmp_path / "out", "--quiet")
    _refused(done, mission, where, "a key is a single value (a name), not a list")
    assert not (tmp_path / "out").exists()


def test_a_collection_as_a_key_of_a_world_is_located_before_the_mission_runs(tmp_path):
    world = tmp_path / "w.yaml"
    world.write_text((DALA / "worlds" / "corridor.yaml").read_text() + MAP_KEY)
    mission = tmp_path / "m.yaml"
    mission.write_text("mission: m\nsteps:\n  - send: NDD.Stop\n")
    done = genom2bip("mission", mission, "--world", world, "--out", tmp_path / "out", "--quiet")
    _refused(done, world, "36:3", "a key is a single value (a name), not a mapping")
    assert not (tmp_path / "out").exists()


def test_a_collection_as_a_key_of_a_campaign_file_is_located_in_the_same_words(tmp_path):
    campaign = tmp_path / "c.yaml"
    campaign.write_text("models: {}\nchecks: []\n" + LIST_KEY)
    done = genom2bip("campaign", campaign, "-o", tmp_path / "out")
    _refused(done, campaign, "3:3", "a key is a single value (a name), not a list")
    assert not (tmp_path / "out").exists()


def test_a_key_given_twice_in_a_mission_step_is_located_not_merged(tmp_path):
    mission = tmp_path / "m.yaml"
    mission.write_text("mission: m\nsteps:\n  - send: RFLEX.Init\n    send: NDD.Stop\n")
    done = genom2bip("mission", mission, "--out", tmp_path / "out", "--quiet")
    _refused(done, mission, "4:5", "step: key 'send' given twice (first at line 3)")
    assert not (tmp_path / "out").exists()


def test_a_key_given_twice_in_a_world_is_located(tmp_path):
    world = tmp_path / "w.yaml"
    world.write_text((DALA / "worlds" / "corridor.yaml").read_text() + "world: {width: 3, height: 3}\n")
    mission = tmp_path / "m.yaml"
    mission.write_text("mission: m\nsteps:\n  - send: NDD.Stop\n")
    done = genom2bip("mission", mission, "--world", world, "--out", tmp_path / "out", "--quiet")
    assert done.code == 1 and "internal error" not in done.err, done.err
    assert done.err.startswith(f"{world}:36:1: error: a world file: key 'world' given twice (first at line 2)\n"), \
        done.err
    assert not (tmp_path / "out").exists()


def test_a_key_given_twice_among_the_inputs_of_a_request_is_located(tmp_path):
    mission = tmp_path / "m.yaml"
    mission.write_text("mission: m\nsteps:\n  - send: NDD.GoTo\n    with:\n      goal: {x: 1, y: 2, x: 3}\n")
    done = genom2bip("mission", mission, "--out", tmp_path / "out", "--quiet")
    _refused(done, mission, "5:26", "with: key 'x' given twice (first at line 5)")
    assert not (tmp_path / "out").exists()


def test_two_steps_named_alike_are_located(tmp_path):
    mission = tmp_path / "m.yaml"
    mission.write_text("mission: m\nsteps:\n  - send: NDD.Stop\n    as: a\n  - send: NDD.Stop\n    as: a\n"
                       "  - await: a\n")
    done = genom2bip("mission", mission, "--out", tmp_path / "out", "--quiet")
    _refused(done, mission, "6:9", "as: 'a' names an earlier step already: await would not know which")
    assert not (tmp_path / "out").exists()
