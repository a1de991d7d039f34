"""Bad missions, worlds, rules, observers and properties: a located error (exit 1), nothing written, never a hang."""
from __future__ import annotations

import os

import pytest

from badinputkit import DALA, genom2bip

pytestmark = pytest.mark.reliability

CORRIDOR = (DALA / "worlds" / "corridor.yaml").read_text()
ONE_STEP = "mission: m\nsteps:\n  - send: NDD.SetSpeed\n    expect: ok\n"


def _mission(tmp_path, text: str, *more):
    """Run ``genom2bip mission`` on ``text``: exit 1, no output directory, never an internal error."""
    mission = tmp_path / "m.yaml"
    mission.write_text(text)
    done = genom2bip("mission", mission, "--out", tmp_path / "out", "--quiet", *more)
    assert done.code == 1, done.out + done.err
    assert "internal error" not in done.err and "Traceback" not in done.err
    assert not (tmp_path / "out").exists()
    return mission, done


@pytest.mark.parametrize("field, value, where", [
    ("timeout", ".nan", "6:14"), ("timeout", ".inf", "6:14"), ("timeout", "-.Inf", "6:14"),
    ("timeout", "1.0e+400", "6:14"),
])
def test_a_timeout_that_is_not_a_finite_number_is_refused_before_the_mission_starts(tmp_path, field, value, where):
    mission, done = _mission(tmp_path, f"{ONE_STEP}  - send: NDD.GoTo\n    {field}: {value}\n")
    assert done.err.startswith(f"{mission}:{where}: error: {value} is not a finite number\n"), done.err


def test_a_wait_of_a_million_seconds_is_refused(tmp_path):
    mission, done = _mission(tmp_path, f"{ONE_STEP}  - wait: 1000000\n")
    assert done.err.startswith(f"{mission}:5:11: error: wait: at most 86400 seconds (a day) expected, got "
                               "'1000000'\n"), done.err


def test_a_nan_among_the_inputs_of_a_request_is_refused(tmp_path):
    mission, done = _mission(tmp_path, "steps:\n  - send: NDD.SetSpeed\n    with: {max_speed: {v: .nan}}\n")
    assert done.err.startswith(f"{mission}:3:27: error: .nan is not a finite number\n"), done.err


def test_aliases_expanding_without_bound_are_refused(tmp_path):
    lines = ["a0: &a0 [1, 2]"] + [f"a{i}: &a{i} [*a{i - 1}, *a{i - 1}]" for i in range(1, 30)]
    mission, done = _mission(tmp_path, "x:\n" + "".join(f"  {line}\n" for line in lines) + ONE_STEP)
    assert f"{mission}:" in done.err and "error: more than 100,000 values once anchors and aliases are " \
                                         "expanded" in done.err, done.err
    assert done.peak_mb < 400


@pytest.mark.parametrize("world, where, message", [
    ("world: {width: 10\n", "2:1", "not valid YAML: expected ',' or '}', but got '<stream end>'"),
    ("world: 3\nrobot: {}\n", "1:8", "world: a mapping (width, height, step_time...) expected, got '3'"),
    ("world: {width: 10, height: 10}\nrobot: []\n", "2:8", "robot: a robot (a mapping, or a list of them) "
                                                         "expected, got a list"),
    (CORRIDOR.replace("width: 16", "width: .nan"), "3:10", ".nan is not a finite number"),
    (CORRIDOR.replace("width: 16", "width: -16"), "3:10", "world: width: a number above 0 and at most 10000 "
                                                          "expected, got '-16'"),
    (CORRIDOR.replace("step_time: 0.025", "step_time: 0"), "5:14", "world: step_time: a number above 0 and at "
                                                                   "most 10 expected, got '0'"),
    (CORRIDOR.replace("name: diff", "name: omni"), "11:24", "robot: kinematics: name: diff (DALA drives a "
                                                            "differential-drive base) expected, got 'omni'"),
    (CORRIDOR.replace("name: lidar2d", "name: camera"), "18:7", "robot: sensors: a list with a lidar2d (LaserRF "
                                                                "reads it) expected, got a list"),
    (CORRIDOR.replace("number: 181", "number: 1000000000"), "22:17", "lidar2d: number: an integer from 1 to 10000 "
                                                                    "expected, got '1000000000'"),
    (CORRIDOR.replace("radius: 0.4", "radius: 0"), "34:35", "obstacle[3]: shape: radius: a number above 0 and at "
                                                            "most 10000 expected, got '0'"),
    (CORRIDOR.replace("obstacle:", "obstacles:"), "23:1", "unknown key 'obstacles' (keys: world, gui, robot, "
                                                          "obstacle, custom)"),
    ("world: {width: 10}\nrobot: {kinematics: {name: diff}, sensors: [{name: lidar2d}]}\0\n", "2:62",
     "not valid YAML: the character U+0000 is not allowed"),
])
def test_a_bad_world_is_located_before_anything_runs(tmp_path, world, where, message):
    path = tmp_path / "w.yaml"
    path.write_text(world)
    _, done = _mission(tmp_path, ONE_STEP, "--world", path)
    assert done.err.startswith(f"{path}:{where}: error: {message}\n"), done.err


def test_each_dala_world_passes_the_checks():
    from genom2bip.mission.world import check_world

    for world in sorted((DALA / "worlds").glob("*.yaml")):
        check_world(world)


def test_a_nul_byte_in_a_rule_file_is_located(tmp_path):
    rules = tmp_path / "rules.yaml"
    rules.write_bytes(b"rules:\n  - id: a\x00b\n")
    done = genom2bip(DALA, "--rules", rules, "-o", tmp_path / "out")
    assert done.code == 1
    assert done.err.startswith(f"{rules}:2:10: error: not valid YAML: the character U+0000 is not allowed\n"), done.err
    assert not (tmp_path / "out").exists()


def test_a_nul_byte_in_an_observer_file_is_located(tmp_path):
    observers = tmp_path / "observers.yaml"
    observers.write_bytes(b"observers:\n  - name: a\x00\n")
    done = genom2bip("verify", DALA, "--timed", "--observers", observers)
    assert done.code == 1
    assert done.err.startswith(f"{observers}:2:12: error: not valid YAML: the character U+0000 is not "
                               "allowed\n"), done.err


def test_a_nul_byte_in_a_mission_is_located(tmp_path):
    mission = tmp_path / "m.yaml"
    mission.write_bytes(b"mission: x\x00\nsteps: []\n")
    done = genom2bip("mission", mission, "--out", tmp_path / "out")
    assert done.code == 1
    assert done.err.startswith(f"{mission}:1:11: error: not valid YAML: the character U+0000 is not "
                               "allowed\n"), done.err
    assert not (tmp_path / "out").exists()


def test_an_observer_bound_of_5000_digits_is_refused(tmp_path):
    observers = tmp_path / "observers.yaml"
    observers.write_text("observers:\n  - name: a\n    from: LaserRF.Scan:write\n    to: RFLEX.servo:exec\n"
                         f"    within: {'9' * 5000} s\n")
    done = genom2bip("verify", DALA, "--timed", "--observers", observers)
    assert done.code == 1
    assert done.err.startswith(f"{observers}:5:13: error: observer a: within is '{'9' * 37}...'; expected a "
                               "positive duration\n"), done.err[:300]


def test_a_property_file_in_a_loop_of_links_is_located(tmp_path):
    loop = tmp_path / "loop.mcl"
    os.symlink(loop.name, loop)
    done = genom2bip("verify", DALA / "NDD.gen", "--property", loop)
    assert done.code == 1
    assert done.err.startswith(f"{loop}: error: cannot read the property file: Too many levels of symbolic "
                               "links\n"), done.err


def test_a_number_of_5000_digits_in_a_property_is_located(tmp_path):
    prop = tmp_path / "big.mcl"
    prop.write_text(f'p: "NDD.SetSpeed:finish" leads to "NDD.GoTo:trigger" within {"9" * 5000} steps;\n')
    done = genom2bip("verify", DALA / "NDD.gen", "--property", prop)
    assert done.code == 1
    assert done.err.startswith(f"{prop}:1:61: error: 99999999999999999999... is out of range: a number has 64 "
                               "bits at most (from -2**63 to 2**63 - 1)\n"), done.err[:300]


def test_a_yaml_file_of_3_mb_is_refused_without_reading_it(tmp_path):
    rules = tmp_path / "rules.yaml"
    rules.write_text("rules:\n" + "# padding\n" * 300_000)
    done = genom2bip(DALA, "--rules", rules, "-o", tmp_path / "out")
    assert done.code == 1
    assert done.err.startswith(f"{rules}: error: not read: 2.9 MB is more than the 1 MB a rule file may hold\n"), \
        done.err
