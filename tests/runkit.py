"""Helpers for tests of the run-time controller: a model and its interface from a description text, DALA's."""
from __future__ import annotations

import sys
import time
from contextlib import contextmanager
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DALA_CODELS = ROOT / "tests" / "fixtures" / "dala_codels"
ORIGIN = {"x": 0.0, "y": 0.0, "theta": 0.0}


def build(tmp_path: Path, text: str, name: str = "tick"):
    """(package, root, interface) of a GenoM3 description given as text, through the generator's back ends."""
    from genom2bip.back.interface import interface_data
    from genom2bip.generate import model_of
    from genom2bip.parser import parse_paths

    path = tmp_path / f"{name}.gen"
    path.write_text(text)
    description = parse_paths([path])
    package, root, _ = model_of(description, name)
    return package, root, interface_data(description, name, str(path))


@contextmanager
def serving_dala():
    """The generated DALA controller with the stub codels, running, its server and a client; stopped after."""
    from runtime.controller import Controller
    from runtime.services.client import Client
    from runtime.services.server import ServiceServer

    pkg = dala()
    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, str(DALA_CODELS))
    controller.start()
    server = ServiceServer(controller).start()
    try:
        yield controller, server, Client(server.url, timeout=10)
    finally:
        server.stop()
        controller.stop()
    assert controller.error is None


def dala():
    """The committed generated DALA package (gen/dala)."""
    if str(ROOT / "gen") not in sys.path:
        sys.path.insert(0, str(ROOT / "gen"))
    import dala as package

    return package


#: A component with a 10 ms task on a 4 ms clock, a slow activity and a function run by the control task.
TICK = """
component tick {
  clock-rate 4 ms;
  exception e_slow;
  ids { long n; double seconds; };
  port out long Count;

  task t {
    period 10 ms;
    codel <start> tickStart(ids out n) yield count;
    codel <count> tickCount(ids inout n, port out Count) yield pause::count;
  };

  activity Slow(in double seconds = 0.05 : "how long the codel takes") {
    task t;
    codel <start> tickSlow(local in seconds) yield ether;
    throw e_slow;
  };

  function Work(in long add = 1, out long total) {
    codel <start> tickWork(local in add, ids inout n, local out total) yield ether;
  };
};
"""


def navigation_ready(client):
    """Everything the rules ask before a GoTo, except NDD's own settings (rules.yaml next to the descriptions)."""
    assert client.call("POM", "Run", origin=ORIGIN, timeout=5)["status"] == "ok"
    assert client.call("LaserRF", "Init", timeout=5)["status"] == "ok"
    assert client.call("RFLEX", "Init", timeout=5)["status"] == "ok"
    for component, service in (("LaserRF", "Start"), ("Aspect", "Run"), ("RFLEX", "TrackSpeed")):
        rid = client.send(component, service)
        until(lambda: client.request(rid)["status"] == "running")


def until(predicate, timeout=60.0):
    """Poll ``predicate`` until it holds (the controller runs in real time).

    It returns as soon as it holds; ``timeout`` only keeps a condition that never comes from hanging the suite,
    so it stays far above what a loaded machine takes.
    """
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, "condition not reached in time"
        time.sleep(0.01)


def ndd_settings(client):
    for service in ("SetParams", "SetSpeed", "SetDataSource"):
        assert client.call("NDD", service, timeout=5)["status"] == "ok"
