"""A component whose codels are C (and one in C++) generated, compiled and run under the controller, through HTTP."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys

import pytest

from genom2bip.cli import main
from runkit import ROOT, import_generated, serving_package

FIXTURE = ROOT / "tests" / "fixtures" / "ccodels" / "cdemo"
pytestmark = pytest.mark.skipif(shutil.which("gcc") is None or shutil.which("g++") is None,
                                reason="gcc and g++ are needed to compile C and C++ codels (Debian: apt-get install "
                                       "gcc g++)")


@pytest.fixture(scope="module")
def cdemo(tmp_path_factory):
    out = tmp_path_factory.mktemp("cgen")
    assert main([str(FIXTURE), "-o", str(out)]) == 0
    return out, import_generated(out, "cdemo")


@pytest.fixture
def serving(cdemo):
    _, pkg = cdemo
    codels = str(FIXTURE / "codels")  # the Python codels of pywatch (the C ones are in the package's libraries)
    with serving_package(pkg, codels, times=True) as (controller, client):
        yield controller, client
    assert controller.error is None


def test_the_package_holds_the_header_and_the_libraries(cdemo):
    out, pkg = cdemo
    names = sorted(p.name for p in (out / "cdemo").iterdir())
    assert {"cdemo_c_types.h", "cwatch_c_types.h", "libcdemo_codels.so", "libcwatch_codels.so"} <= set(names)
    spec = pkg.INTERFACE["components"]["cdemo"]["c"]
    assert spec["library"] == "libcdemo_codels.so" and set(spec["codels"]) >= {"cdInit", "cdStep", "cdFail"}
    assert pkg.INTERFACE["where"] == str(out / "cdemo")
    assert "codels" not in pkg.INTERFACE["components"]["cdemo"]["c"]["codels"]["cdStep"][0]


def test_every_service_runs_its_c_codels_through_http(serving):
    controller, client = serving
    assert controller.binder.missing == []
    bad = client.call("cdemo", "SetLimit", {"limit": -1.0})
    assert bad["status"] == "rejected" and bad["exception"] == "cdemo::e_range" and bad["codel"] == "cdCheckLimit"
    assert bad["detail"] == {"limit": -1.0, "what": "limit -1.0"}  # the detail decoded by its IDL type
    assert client.call("cdemo", "SetLimit", {"limit": 5.0})["status"] == "ok"
    moved = client.call("cdemo", "MoveTo", {"x": 1.0, "y": 1.0})
    assert moved["status"] == "ok" and moved["outputs"] == {"steps": 6}  # 0.25 m a period over 1.41 m
    state = client.call("cdemo", "GetState")["outputs"]
    assert state["pose"] == {"x": 1.0, "y": 1.0} and state["name"] == "origin" and state["mood"] == "busy"
    assert len(state["trail"]) == 6 and state["trail"][-1] == 1.0  # a sequence the codel grew
    poster = client.poster("cdemo", "Pose")
    assert poster["written"] and poster["value"] == {"x": 1.0, "y": 1.0}
    seen = client.call("cwatch", "Look")  # C++ codels of another component read the port
    assert seen["status"] == "ok" and seen["outputs"] == {"seen": {"x": 1.0, "y": 1.0}, "reads": 1}
    python = client.call("pywatch", "Look")  # and a Python codel in the same level
    assert python["status"] == "ok" and python["outputs"] == {"seen": {"x": 1.0, "y": 1.0}}
    failed = client.call("cdemo", "Fail", {"name": "bob"})
    assert failed["status"] == "failed" and failed["detail"] == {"limit": -1.0, "what": "bob"}
    far = client.call("cdemo", "MoveTo", {"x": 9.0, "y": 9.0})
    assert far["status"] == "rejected" and far["detail"] == {"limit": 5.0, "what": "goal too far"}
    times = controller.codel_times()["codels"]
    assert times["cdemo.MoveTo.cdStep"]["calls"] == 6 and times["cwatch.Look.cwLook"]["calls"] == 1


def test_a_new_move_interrupts_the_running_one_which_runs_its_c_stop_codel(serving):
    controller, client = serving
    assert client.call("cdemo", "SetLimit", {"limit": 100.0})["status"] == "ok"
    first = client.send("cdemo", "MoveTo", {"x": 50.0, "y": 0.0})
    while client.request(first, wait=1)["status"] != "running":
        pass
    second = client.send("cdemo", "MoveTo", {"x": 0.0, "y": 0.5})
    ended = client.wait(first, timeout=60)
    assert ended["status"] == "interrupted" and ended["by_request"] == second
    assert client.wait(second, timeout=60)["status"] == "ok"
    assert client.call("cdemo", "GetState")["outputs"]["pose"] == {"x": 0.0, "y": 0.5}


def test_the_package_runs_from_another_directory_with_its_libraries(cdemo, tmp_path):
    out, _ = cdemo
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(out), str(ROOT)]))
    done = subprocess.run([sys.executable, "-m", "cdemo", "run", "--duration", "0.3", "--quiet"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120, env=env)
    assert done.returncode == 0, done.stderr
    codels = done.stdout.split("codels: ", 1)[1].split(";")[0]
    assert str(out / "cdemo" / "libcdemo_codels.so") in codels and str(out / "cdemo" / "libcwatch_codels.so") in codels


def test_a_library_that_cannot_be_loaded_is_reported_for_each_of_its_codels(cdemo, tmp_path):
    from runtime.controller import Controller

    out, pkg = cdemo
    interface = dict(pkg.INTERFACE, where=str(tmp_path))  # a folder without the libraries
    controller = Controller(pkg.package(), pkg.ROOT, interface, None)
    assert "cdemo.cdStep" in controller.binder.missing and "cwatch.cwLook" in controller.binder.missing
    why = controller.codels.why_missing("cdemo", "cdStep")
    assert f"{tmp_path / 'libcdemo_codels.so'}: cannot load the C codels of cdemo" in why


def test_a_codel_that_does_not_compile_is_reported_at_its_line_and_nothing_is_written(tmp_path, capsys):
    copy = tmp_path / "cdemo"
    shutil.copytree(FIXTURE, copy)
    source = copy / "codels" / "cdemo" / "cdemo_codels.c"
    lines = source.read_text().splitlines()
    at = next(k for k, x in enumerate(lines) if "(*steps)++;" in x)
    lines[at] = "  (*steps)++ oops;"
    source.write_text("\n".join(lines) + "\n")
    out = tmp_path / "out"
    assert main([str(copy), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"{source}:{at + 1}:" in err and "error" in err and "the codels of cdemo do not compile" in err
    assert "Traceback" not in err and not (out / "cdemo").exists()


def test_a_missing_compiler_is_one_clear_line(tmp_path, capsys, monkeypatch):
    import genom2bip.ccompile as ccompile

    monkeypatch.setattr(ccompile.shutil, "which", lambda tool: None)
    assert main([str(FIXTURE), "-o", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "need gcc, which is not installed (Debian: apt-get install gcc)" in err[0]
    assert not (tmp_path / "out" / "cdemo").exists()


def test_a_codel_that_crashes_in_its_own_process_fails_its_request_and_the_level_goes_on(cdemo, monkeypatch):
    from runtime.controller import Controller
    from runtime.services.client import Client
    from runtime.services.server import ServiceServer

    monkeypatch.setenv("GENOM2BIP_CODELS_PROCESS", "1")
    _, pkg = cdemo
    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, None)
    controller.start()
    server = ServiceServer(controller).start()
    client = Client(server.url, timeout=30)
    try:
        crashed = client.call("cdemo", "Crash", timeout=60)
        assert crashed["status"] == "failed" and crashed["codel"] == "cdCrash"
        assert "codel cdCrash of cdemo crashed: its process ended on signal SIGSEGV" in crashed["message"]
        moved = client.call("cdemo", "MoveTo", {"x": 0.5, "y": 0.0}, timeout=60)  # a new process serves it
        assert moved["status"] == "ok" and moved["outputs"] == {"steps": 2}
        assert client.call("cwatch", "Look", timeout=60)["outputs"]["seen"] == {"x": 0.5, "y": 0.0}
    finally:
        server.stop()
        controller.stop(timeout=30)
    assert controller.error is None


def test_codels_reading_the_wall_clock_see_the_controllers_virtual_clock(cdemo):
    import time

    from runtime.controller import Controller, VirtualClock

    _, pkg = cdemo
    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, None, clock=VirtualClock())
    controller.start()
    try:
        first = controller.wait(controller.submit("cdemo", "Stamp").id, timeout=60).final
        assert controller.wait(controller.submit("cdemo", "SetLimit", {"limit": 100.0}).id, timeout=60).final[
            "status"] == "ok"
        wall = time.monotonic()
        moved = controller.wait(controller.submit("cdemo", "MoveTo", {"x": 20.0, "y": 0.0}).id, timeout=60).final
        wall = time.monotonic() - wall
        second = controller.wait(controller.submit("cdemo", "Stamp").id, timeout=60).final
    finally:
        controller.stop(timeout=30)
    assert moved["outputs"] == {"steps": 80}  # 80 periods of 10 ms: 0.8 s on the controller's clock
    read = second["outputs"]["stamp"] - first["outputs"]["stamp"]
    assert abs(read - (second["time"] - first["time"])) < 0.02  # what gettimeofday said is the controller's time
    assert read > 0.8, f"the codel read {read:.3f} s on the wall clock over a 0.8 s move ({wall:.3f} s of real time)"
