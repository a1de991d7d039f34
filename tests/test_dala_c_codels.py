"""DALA with POM's and RFLEX's codels in C (descriptions/dala/codels_c) beside the others in Python: the corridor
mission, and RFLEX's C codels driving the simulated base through the device the Python codels offer."""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import threading

import pytest

from genom2bip.cli import main
from runkit import ROOT

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc compiles POM's C codels "
                                                                    "(Debian: apt-get install gcc)")


@pytest.fixture(scope="module")
def c_package(tmp_path_factory):
    out = tmp_path_factory.mktemp("dala_c")
    here = os.getcwd()
    os.chdir(ROOT)
    try:
        assert main(["descriptions/dala", "-o", str(out), "--c-codels", "descriptions/dala/codels_c"]) == 0
    finally:
        os.chdir(here)
    return out / "dala"


def _import(package):
    import importlib.util

    alias = f"dala_c_{abs(hash(str(package)))}"
    spec = importlib.util.spec_from_file_location(alias, package / "__init__.py",
                                                  submodule_search_locations=[str(package)])
    module = importlib.util.module_from_spec(spec)
    sys.modules[alias] = module
    spec.loader.exec_module(module)
    return module


def test_the_corridor_mission_gives_the_same_report_with_pom_and_rflex_in_c(c_package, tmp_path):
    package = c_package
    assert (package / "libPOM_codels.so").is_file() and (package / "libRFLEX_codels.so").is_file()
    assert not (package / "libNDD_codels.so").exists()  # the other modules keep their Python codels
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


def _controller(c_package):
    from runtime.controller import Controller
    from runtime.controller.timing import VirtualClock

    pkg = _import(c_package)
    return Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, str(ROOT / "descriptions" / "dala" / "codels"),
                      clock=VirtualClock())


def test_rflexs_c_codels_drive_the_simulated_base_through_its_device(c_package):
    controller = _controller(c_package)
    rflex = controller.codels.modules["RFLEX"]
    assert rflex["rflexOdometry"].__qualname__ == "RFLEX.rflexOdometry"  # the library's, not RFLEX.py's
    world = sys.modules[controller.codels.modules["NDD"].__name__.rsplit(".", 1)[0] + ".world"]
    world.load(ROOT / "descriptions" / "dala" / "worlds" / "open_field.yaml")
    controller.start()
    try:
        opened = controller.wait(controller.submit("RFLEX", "Init", {"device": "/dev/base0"}).id, 60).final
        assert opened["status"] == "ok", opened
        assert controller.data.ids["RFLEX"]["device"] == "/dev/base0"
        tracking = controller.submit("RFLEX", "TrackSpeed")
        with controller._lock:  # what NDD asks for while it navigates (idle, its task would publish a null speed)
            controller.data.ids["NDD"]["navigating"] = True
            controller.data.write_poster("NDD", "Speed", {"v": 0.3, "w": 0.0})
        sim = world.sim()
        start = controller.clock.now()
        moved = threading.Event()  # the odometry the C codels published says two seconds of simulation
        seen = {}

        def heard(event):  # in the engine thread, as the poster is written: the robot where the odometry is
            if event.get("event") == "poster" and event.get("port") == "Odo" and event["value"]["stamp"] >= 2.0 \
                    and not moved.is_set():
                seen.update(odo=event["value"], x=sim.trajectory[-1].x - sim.trajectory[0].x)
                moved.set()

        controller.subscribe(heard)
        assert moved.wait(120)
        odo = seen["odo"]
        assert tracking.final is None and tracking.status == "running", tracking.as_json()
    finally:
        controller.stop(timeout=30)
    assert controller.error is None and controller.clock.now() - start > 1.0
    # the C servo loop: speeding up by at most 0.5 m/s2 to 0.3 m/s, then holding it; the odometry integrates it
    assert odo["velocity"]["v"] == pytest.approx(0.3, abs=1e-6) and odo["velocity"]["w"] == pytest.approx(0.0)
    assert odo["position"]["x"] > 0.3 and abs(odo["position"]["y"]) < 1e-6 and odo["stamp"] > 1.0
    assert controller.data.ids["RFLEX"]["command"] == {"v": pytest.approx(0.3), "w": 0.0}
    assert seen["x"] == pytest.approx(odo["position"]["x"], abs=0.01)  # dead reckoning follows the true path


def test_without_the_device_rflexs_init_says_so(c_package, monkeypatch):
    """In a process of their own the codels get no device: Init fails with e_base, saying which."""
    monkeypatch.setenv("GENOM2BIP_CODELS_PROCESS", "1")
    controller = _controller(c_package)
    controller.start()
    try:
        final = controller.wait(controller.submit("RFLEX", "Init", {"device": "/dev/base0"}).id, 60).final
    finally:
        controller.stop(timeout=30)
    assert final["status"] == "failed" and final["exception"] == "RFLEX::e_base"
    assert final["detail"] == {"what": "no base device dala_base for /dev/base0"}
