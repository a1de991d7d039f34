"""``genom2bip mission`` finds the generated package its components live in, from any working directory."""
from __future__ import annotations

import shutil

from genom2bip.cli import main
from genom2bip.mission.package import NoPackage, find_package
from genom2bip.mission.spec import read_mission
from runkit import ROOT

MISSION = "mission: switch\nsteps:\n  - send: counter.SetRunning\n    with: {running: false}\n    expect: ok\n"


def _robot(tmp_path):
    """A project of its own: descriptions/counter/{counter.gen, missions/switch.yaml} and gen/counter."""
    robot = tmp_path / "robot"
    (robot / "descriptions" / "counter" / "missions").mkdir(parents=True)
    shutil.copy(ROOT / "tests/fixtures/genom3/counter.gen", robot / "descriptions/counter/counter.gen")
    mission = robot / "descriptions/counter/missions/switch.yaml"
    mission.write_text(MISSION)
    assert main([str(robot / "descriptions/counter"), "-o", str(robot / "gen")]) == 0
    return robot, mission


def test_the_mission_runs_on_the_package_of_its_descriptions_from_another_directory(tmp_path, monkeypatch, capsys):
    robot, mission = _robot(tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    capsys.readouterr()
    assert main(["mission", str(mission), "--out", str(tmp_path / "out"), "--quiet"]) == 0, capsys.readouterr().err
    shown = capsys.readouterr().out
    assert "counter.SetRunning" in shown and (tmp_path / "out" / "switch.jsonl").is_file()


def test_find_package_prefers_the_system_of_the_mission_and_checks_its_components(tmp_path, monkeypatch):
    robot, mission = _robot(tmp_path)
    assert find_package(read_mission(mission), cwd=tmp_path) == robot / "gen" / "counter"
    # a mission kept elsewhere finds a package that holds its components in the working directory's gen/
    loose = tmp_path / "loose.yaml"
    loose.write_text(MISSION)
    assert find_package(read_mission(loose), cwd=robot) == robot / "gen" / "counter"


def test_no_package_with_the_components_is_one_clear_error_and_nothing_is_written(tmp_path, monkeypatch, capsys):
    robot, _ = _robot(tmp_path)
    mission = tmp_path / "other.yaml"
    mission.write_text("steps:\n  - send: NDD.Stop\n    expect: ok\n")
    monkeypatch.chdir(robot)  # robot/gen holds counter only
    capsys.readouterr()
    assert main(["mission", str(mission), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert f"{mission}: no generated package holds the mission's components (NDD)" in err
    assert "gen/counter has no NDD" in err and "--package DIR" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()
    try:
        find_package(read_mission(mission), cwd=tmp_path / "nowhere")
    except NoPackage as exc:
        assert "no generated package in" in str(exc)
    else:
        raise AssertionError("a mission without a package was given one")
