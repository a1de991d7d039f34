"""Helpers for tests of the run-time controller: a model and its interface from a description text, DALA's."""
from __future__ import annotations

import sys
import time
from contextlib import contextmanager
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DALA_CODELS = ROOT / "tests" / "fixtures" / "dala_codels"
ORIGIN = {"x": 0.0, "y": 0.0, "theta": 0.0}


#: A component whose attribute's validate codel the test holds (a device that does not answer) while a 10 ms task runs.
HELD = """
component held {
  ids { long n; long seen; };
  task t {
    period 10 ms;
    codel <start> heldTick(ids inout n) yield pause::start;
  };
  attribute Set(in seen = 0 : "a value") {
    validate heldCheck(local in seen);
  };
};
"""


def tick_codels(clock=None, calls=None, slow=None):
    """Codels of the tick component; ``calls`` collects (codel, time); ``slow(seconds)`` runs in tickSlow."""
    calls = [] if calls is None else calls

    def now():
        return clock.now() if clock is not None else time.monotonic()

    def tickStart(n):
        calls.append(("tickStart", now()))
        n.value = 0
        return "count"

    def tickCount(n, Count):
        calls.append(("tickCount", now()))
        n.value += 1
        Count.value = n.value
        return "pause::count"

    def tickSlow(seconds):
        calls.append(("tickSlow", now()))
        if slow is not None:
            slow(seconds)
        return "ether"

    def tickWork(add, n, total):
        n.value += add
        total.value = n.value
        return "ether"

    return {"tick": {"tickStart": tickStart, "tickCount": tickCount, "tickSlow": tickSlow, "tickWork": tickWork}}


_UNTIMED: list[Path] = []


def dala_without_wcets() -> Path:
    """descriptions/dala (its .gen files, rules and observers) with every ``wcet`` taken out, made once a process.

    For the tests of the timed model's mechanics written on DALA's shape when its codels declared no WCET (each
    codel then takes ``--default-wcet``); DALA's measured WCETs and what the timed check makes of them are in
    docs/missions.md and docs/verification/localization.md.
    """
    import atexit
    import re
    import shutil
    import tempfile

    if not _UNTIMED:
        folder = Path(tempfile.mkdtemp(prefix="dala-without-wcets-"))
        atexit.register(shutil.rmtree, folder, True)
        target = folder / "dala"
        shutil.copytree(ROOT / "descriptions" / "dala", target,
                        ignore=shutil.ignore_patterns("codels", "worlds", "missions", "__pycache__"))
        for gen in target.glob("*.gen"):
            text = gen.read_text()
            gen.write_text(re.sub(r"\s+wcet\s+[0-9.]+\s*(?:ms|us|s)\b", "", text))
            assert " wcet " not in gen.read_text().split("*/", 1)[-1], gen
        _UNTIMED.append(target)
    return _UNTIMED[0]


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
def serving(controller, client_timeout: float = 10, stop_timeout: float | None = None):
    """``controller`` started, with its service server and a client of it (``client_timeout`` s a call); the server
    and the controller stopped after (the controller waiting up to ``stop_timeout`` s)."""
    from runtime.services.client import Client
    from runtime.services.server import ServiceServer

    controller.start()
    server = ServiceServer(controller).start()
    try:
        yield server, Client(server.url, timeout=client_timeout)
    finally:
        server.stop()
        controller.stop(timeout=stop_timeout)


@contextmanager
def serving_dala():
    """The generated DALA controller with the stub codels, running, its server and a client; stopped after."""
    from runtime.controller import Controller

    pkg = dala()
    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, str(DALA_CODELS))
    with serving(controller) as (server, client):
        yield controller, server, client
    assert controller.error is None


def import_generated(directory: Path, name: str):
    """The generated package in ``directory``/``name`` under a private module name (tests generate it again)."""
    import importlib.util

    alias = f"{name}_{abs(hash(str(directory)))}"
    spec = importlib.util.spec_from_file_location(alias, directory / name / "__init__.py",
                                                  submodule_search_locations=[str(directory / name)])
    module = importlib.util.module_from_spec(spec)
    sys.modules[alias] = module
    spec.loader.exec_module(module)
    return module


@contextmanager
def serving_package(pkg, codels: str, **controller):
    """A generated package's controller with ``codels``, running, and a client of its server; stopped after."""
    from runtime.controller import Controller

    running = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, codels, **controller)
    with serving(running, client_timeout=30, stop_timeout=30) as (_, client):
        yield running, client


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
