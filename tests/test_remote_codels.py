"""Remote services: a codel calls a service of the component that provides an interface, through the controller."""
from __future__ import annotations

import shutil

import pytest

from genom2bip.cli import main
from runkit import ROOT, import_generated, serving_package

FIXTURE = ROOT / "tests" / "fixtures" / "ccodels" / "remote"
pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc compiles the fixture's C codels "
                                                                    "(Debian: apt-get install gcc)")


@pytest.fixture(scope="module")
def level(tmp_path_factory):
    out = tmp_path_factory.mktemp("remote")
    assert main([str(FIXTURE), "-o", str(out)]) == 0
    return out, import_generated(out, "remote")


@pytest.fixture
def serving(level):
    _, pkg = level
    with serving_package(pkg, str(FIXTURE / "codels")) as (controller, client):
        yield controller, client
    assert controller.error is None


def test_the_header_declares_each_remote_as_genom3_does(level):
    out, _ = level
    header = (out / "remote" / "asker_c_types.h").read_text()
    # genom3 2.99's own mapping of this fixture (genom3 mappings --signature -l c asker.gen), spacing aside
    assert "typedef struct asker_Divide {\n  genom_event (*call)(double num, double den, double *quotient, " \
           "genom_context self);\n} asker_Divide;" in header
    assert "typedef struct asker_Sum {\n  genom_event (*call)(const sequence8_double *values, char text[32], " \
           "double *total, genom_context self);\n} asker_Sum;" in header
    assert "akAsk(double num, double den, const asker_Divide *Divide, double *kept, double *answer, " \
           "const genom_context self);" in header
    # the provider declares none: it serves them
    assert "call)" not in (out / "remote" / "divider_c_types.h").read_text()


def test_a_c_codels_remote_call_reaches_the_other_component_and_its_result_comes_back(serving):
    controller, client = serving
    assert controller.binder.missing == []
    assert client.call("divider", "GetCalls")["outputs"] == {"calls": 0, "last": 0.0}
    asked = client.call("asker", "Ask", {"num": 7.0, "den": 2.0})
    assert asked["status"] == "ok", asked
    # Divide's quotient, then Sum's string and total over a bounded sequence the codel filled
    assert asked["outputs"] == {"answer": 3.5, "text": "3 values", "total": 10.5}
    # the divider ran both services: its own codels counted them and kept the quotient
    assert client.call("divider", "GetCalls")["outputs"] == {"calls": 2, "last": 3.5}
    served = [r for r in controller.requests.values() if r.component == "divider" and r.service != "GetCalls"]
    assert [(r.service, r.inputs, r.final["status"]) for r in served] == [
        ("Divide", {"num": 7.0, "den": 2.0}, "ok"), ("Sum", {"values": [7.0, 2.0, 1.5]}, "ok")]
    assert served[0].final["outputs"] == {"quotient": 3.5}


def test_the_servers_exception_reaches_the_calling_codel_with_its_detail(serving):
    controller, client = serving
    failed = client.call("asker", "Ask", {"num": 1.0, "den": 0.0})
    # akAsk compared the answer with calc_e_div_id, read the detail from its context and threw it again
    assert failed["status"] == "failed" and failed["exception"] == "calc::e_div" and failed["codel"] == "akAsk"
    assert failed["detail"] == {"num": 1.0, "why": "1 / 0"}
    assert client.call("asker", "Ask", {"num": 9.0, "den": 3.0})["outputs"]["answer"] == 3.0  # and it goes on


def test_a_python_codel_calls_the_same_remote(serving):
    controller, client = serving
    assert client.call("pyasker", "PyAsk", {"num": 6.0, "den": 4.0})["outputs"] == {"answer": 1.5}
    failed = client.call("pyasker", "PyAsk", {"num": 2.0, "den": 0.0})
    assert failed["exception"] == "calc::e_div" and failed["detail"] == {"num": 2.0, "why": "2 / 0"}


def test_remote_calls_on_a_virtual_clock(level):
    from runtime.controller import Controller
    from runtime.controller.timing import VirtualClock

    _, pkg = level
    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, str(FIXTURE / "codels"), clock=VirtualClock())
    controller.start()
    try:
        finals = [controller.wait(controller.submit("asker", "Ask", {"num": float(k), "den": 2.0}).id, 60).final
                  for k in range(3)]
    finally:
        controller.stop(timeout=30)
    assert [f["outputs"]["answer"] for f in finals] == [0.0, 0.5, 1.0]


def test_a_remote_no_component_serves_fails_the_request_saying_so(tmp_path):
    from runtime.controller import Controller

    assert main([str(FIXTURE / "asker.gen"), "-o", str(tmp_path)]) == 0  # the asker alone: nobody provides calc
    pkg = import_generated(tmp_path, "asker")
    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, None)
    assert controller.remotes.target("asker", "Divide") is None
    controller.start()
    try:
        final = controller.wait(controller.submit("asker", "Ask", {"num": 1.0, "den": 1.0}).id, 60).final
    finally:
        controller.stop(timeout=30)
    assert final["status"] == "failed" and final["exception"] == "genom::no_such_remote"
    assert final["detail"] == {"what": "remote Divide of asker is connected to no service: no single other "
                                       "component provides calc with a service Divide"}
    assert "threw genom::no_such_remote, which is not declared" in final["message"]


def test_connecting_a_remote_checks_both_names(level):
    from runtime.controller import Controller

    _, pkg = level
    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, None)
    controller.remotes.connect("asker", "Divide", "divider.Sum")
    assert controller.remotes.target("asker", "Divide") == ("divider", "Sum")
    with pytest.raises(KeyError, match=r"asker has no remote named 'Times' \(remotes: Divide, Sum\)"):
        controller.remotes.connect("asker", "Times", "divider.Divide")
    with pytest.raises(KeyError, match=r"no service 'divider.Times' to connect asker.Divide to"):
        controller.remotes.connect("asker", "Divide", "divider.Times")


def test_in_a_process_of_their_own_the_codels_call_remotes_through_their_pipe(level, monkeypatch):
    from runtime.controller import Controller

    monkeypatch.setenv("GENOM2BIP_CODELS_PROCESS", "1")
    _, pkg = level
    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, None)
    controller.start()
    try:
        asked = controller.wait(controller.submit("asker", "Ask", {"num": 1.0, "den": 4.0}).id, 60).final
        failed = controller.wait(controller.submit("asker", "Ask", {"num": 3.0, "den": 0.0}).id, 60).final
        calls = controller.wait(controller.submit("divider", "GetCalls").id, 60).final
    finally:
        controller.stop(timeout=30)
    assert asked["status"] == "ok" and asked["outputs"] == {"answer": 0.25, "text": "3 values", "total": 6.5}
    assert failed["exception"] == "calc::e_div" and failed["detail"] == {"num": 3.0, "why": "3 / 0"}
    assert calls["outputs"]["calls"] == 3  # Divide, Sum, Divide: served by the divider in its own process too


@pytest.mark.parametrize("codel, message", [
    ("codel <start> akAsk(local in num, local in den, remote in Times, ids out answer::kept, local out answer) "
     "yield sum;", "unknown remote 'Times' in codel 'akAsk'"),
])
def test_a_remote_the_component_does_not_use_is_located(tmp_path, capsys, codel, message):
    text = (FIXTURE / "asker.gen").read_text()
    start = text.index("codel <start> akAsk")
    end = text.index("yield sum;", start) + len("yield sum;")
    (tmp_path / "calc.idl").write_text((FIXTURE / "calc.idl").read_text())
    (tmp_path / "asker.gen").write_text(text[:start] + codel + text[end:])
    assert main([str(tmp_path / "asker.gen"), "-o", str(tmp_path / "out"), "--no-rules"]) == 1
    err = capsys.readouterr().err
    line = text[:start].count("\n") + 1
    column = start - text.rfind("\n", 0, start) + codel.index("remote in Times")
    assert f"asker.gen:{line}:{column}: error: {message}" in err, err
    assert "did you mean 'Times'" not in err and "known remote services: Divide, Sum" in err
    assert not (tmp_path / "out").exists()


def test_a_remote_in_a_functions_codel_is_refused_as_genom3_does(tmp_path, capsys):
    (tmp_path / "calc.idl").write_text((FIXTURE / "calc.idl").read_text())
    (tmp_path / "fn.gen").write_text('#include "calc.idl"\ncomponent fn {\n  uses calc;\n'
                                     '  function Ask(in double x) {\n'
                                     '    codel fnAsk(local in x, remote in Divide);\n  };\n};\n')
    assert main([str(tmp_path / "fn.gen"), "-o", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert "fn.gen:5:29: error: remote 'Divide' is not allowed in simple codel 'fnAsk'" in err, err
    assert not (tmp_path / "out").exists()


def test_an_interface_file_two_descriptions_include_is_read_once(tmp_path):
    """The provider's and the user's .gen both include calc.idl: one interface, each service once."""
    from genom2bip.loading import read_description

    description = read_description([FIXTURE / "divider.gen", FIXTURE / "asker.gen"])
    calc = description.interfaces["calc"]
    assert [s.name for s in calc.services] == ["Divide", "Sum"]
    assert [s.name for s in description.component("divider").services] == ["Divide", "Sum", "GetCalls"]


def test_a_controller_run_in_its_callers_thread_refuses_remote_calls_saying_why(level):
    from runtime.controller import Controller
    from runtime.controller.timing import VirtualClock

    _, pkg = level
    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, None, clock=VirtualClock())
    req = controller.submit("asker", "Ask", {"num": 1.0, "den": 1.0})
    controller.run(duration=1.0)  # here, not in a thread: nothing can go on while a codel waits
    assert req.final["status"] == "failed" and req.final["exception"] == "genom::remote_io"
    assert req.final["detail"] == {"what": "divider.Divide: a remote call needs the controller's engine in a thread "
                                           "of its own (Controller.start()), which it leaves while the codel waits"}
    assert not [r for r in controller.requests.values() if r.component == "divider"]  # nothing was sent


def test_a_codel_the_watchdog_went_on_without_then_calling_a_remote_leaves_one_engine_thread(level):
    """The watchdog detaches a slow codel; its remote call then must not start a second engine thread."""
    import threading
    import time

    from runtime.controller import Controller

    _, pkg = level
    seen: dict[str, object] = {}
    holder: dict[str, Controller] = {}

    def paAsk(num, den, answer, Divide):
        record = holder["c"].binder.call  # this call, as the watchdog sees it
        deadline = time.monotonic() + 60
        while not record.detached and time.monotonic() < deadline:  # past its bound, the engine goes on
            time.sleep(0.005)
        seen["detached"] = record.detached
        answer.value = Divide(num=num, den=den)["quotient"]
        seen["engines"] = sum(1 for t in threading.enumerate() if t.name == "bip-controller" and t.is_alive())
        return "ether"

    controller = holder["c"] = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, {"pyasker": {"paAsk": paAsk}})
    controller.start()
    try:
        final = controller.wait(controller.submit("pyasker", "PyAsk", {"num": 3.0, "den": 2.0}).id, 60).final
        after = controller.wait(controller.submit("divider", "GetCalls").id, 60).final
    finally:
        controller.stop(timeout=30)
    assert seen["detached"] is True
    assert seen["engines"] == 2  # the engine going on, and this codel's thread (the old engine), waiting
    assert final["status"] == "ok" and final["outputs"] == {"answer": 1.5}
    assert after["outputs"]["calls"] == 1 and controller.error is None


def test_run_connects_a_remote_with_connect_as_it_does_a_port(level):
    import argparse

    from runtime.services.run import UsageError, _build, add_arguments

    _, pkg = level
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    args = parser.parse_args(["--connect", "asker.Divide=divider.Sum", "--port", "0"])
    controller, server = _build(pkg.package(), pkg.ROOT, pkg.INTERFACE, args, None)
    server.socket.close()  # never served
    assert controller.remotes.target("asker", "Divide") == ("divider", "Sum")
    assert controller.remotes.target("asker", "Sum") == ("divider", "Sum")
    bad = parser.parse_args(["--connect", "asker.Divide=divider.Times"])
    with pytest.raises(UsageError, match=r"^--connect: no service 'divider.Times' to connect asker.Divide to$"):
        _build(pkg.package(), pkg.ROOT, pkg.INTERFACE, bad, None)
