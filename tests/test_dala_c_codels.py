"""DALA with POM's codels in C (descriptions/dala/codels_c) beside the others in Python: the corridor mission."""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys

import pytest

from genom2bip.cli import main
from runkit import ROOT

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc compiles POM's C codels "
                                                                    "(Debian: apt-get install gcc)")


def test_the_corridor_mission_gives_the_same_report_with_poms_codels_in_c(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(ROOT)
    assert main(["descriptions/dala", "-o", str(tmp_path / "gen"), "--c-codels", "descriptions/dala/codels_c"]) == 0
    package = tmp_path / "gen" / "dala"
    assert (package / "libPOM_codels.so").is_file() and not (package / "libRFLEX_codels.so").exists()
    done = subprocess.run([sys.executable, "-m", "genom2bip", "mission", "descriptions/dala/missions/corridor.yaml",
                           "--package", str(package), "--out", str(tmp_path / "out"), "--quiet"], cwd=ROOT,
                          capture_output=True, text=True, timeout=600, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert done.returncode == 0, done.stdout + done.stderr
    report = done.stdout
    # what the Python codels' run says too (runs differ in when the goals are reached, not in what happens)
    requests = re.findall(r"^    \[\d+\] .*$", report, re.M)
    assert requests == [
        "    [1] RFLEX.Init: ok", "    [2] RFLEX.TrackSpeed: started (ran until the controller stopped)",
        "    [3] LaserRF.Init: ok", "    [4] LaserRF.Start: started (ran until the controller stopped)",
        "    [5] Aspect.SetParams: ok", "    [6] Aspect.Run: started (ran until the controller stopped)",
        "    [7] NDD.SetParams: ok", "    [8] NDD.SetDataSource: ok", "    [9] NDD.SetSpeed: ok",
        "    [10] NDD.GoTo: rejected goto-after-pom-run", "    [11] POM.Run: ok", "    [12] NDD.GoTo: ok",
        "    [13] NDD.GoTo: ok"]
    assert "goal (7, 2.4): reached" in report and "goal (14.5, 2): reached" in report
    assert "collisions: 0" in report and "every expectation met" in report


def test_c_codels_that_are_not_a_folder_are_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(ROOT)
    assert main(["descriptions/dala", "-o", str(tmp_path / "gen"), "--c-codels", str(tmp_path / "nowhere")]) == 1
    assert f"--c-codels {tmp_path / 'nowhere'}: no such directory" in capsys.readouterr().err
    assert not (tmp_path / "gen").exists()
