"""Online monitoring: the model's observers measured on the controller's clock, events on the services interface."""
from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

from genom2bip.back.interface import interface_data
from genom2bip.build.timed import LatencySpec, TimeOptions
from genom2bip.generate import model_of
from genom2bip.parser import parse_paths
from runtime.controller import Controller
from runtime.controller.recovery import RecoveryError, on_violation
from runtime.controller.timing import VirtualClock
from runkit import until

#: A 10 ms task whose codel sleeps when asked to, and a Stop that interrupts the activity.
WATCHED = """
component watched {
  ids { double delay; };
  port out long Beat;

  task loop {
    period 10 ms;
    codel <start> beat(ids inout delay, port out Beat) yield pause::start;
  };

  activity Hold() {
    task loop;
    codel <start> hold() yield pause::start;
  };

  function Slow(in double seconds = 0.03 : "how long the next beat takes") {
    codel <start> slow(local in seconds, ids out delay) yield ether;
  };

  function Stop() {
    codel <start> stop() yield ether;
    interrupts Hold;
  };
};
"""


def codels(sleeps: list[float], clock=None, slow_beat: int | None = None):
    """Codels of ``watched``; ``slow_beat``: the beat (1, 2...) that takes 30 ms, besides those Slow asks for."""
    beats = []

    def beat(delay, Beat):
        beats.append(1)
        if len(beats) == slow_beat:
            delay.value = 0.03
        if delay.value:
            sleeps.append(delay.value)
            if clock is None:
                time.sleep(delay.value)
            else:
                clock.advance(clock.now() + delay.value)
            delay.value = 0.0
        return "pause::start"

    def slow(seconds, delay):
        delay.value = seconds
        return "ether"

    return {"watched": {"beat": beat, "hold": lambda: "pause::start", "slow": slow, "stop": lambda: "ether"}}


@pytest.fixture
def watched(tmp_path: Path):
    path = tmp_path / "watched.gen"
    path.write_text(WATCHED)
    description = parse_paths([path])
    latency = LatencySpec("slow-answered", "watched.Slow:start", "watched.Slow:finish", 5_000)
    package, root, _ = model_of(description, "watched", None, TimeOptions(latencies=[latency], ticks=False))
    return package, root, interface_data(description, "watched", str(path))


def test_the_monitored_model_has_observers_but_no_tick(watched):
    package, _, _ = watched
    assert package.annotations[0].name == "monitored"
    assert {"PeriodObserver", "LatencyObserver"} <= {a.name for a in package.atom_types}
    assert package.atom_type("Timer").port("tick") is None  # the controller's own timers, untouched
    labels = [a.arguments.get("name") for c in package.compound_types for k in c.connectors for a in k.annotations]
    assert "tick" not in labels


def test_a_codel_sleeping_past_its_period_raises_an_observer_event(watched):
    package, root, interface = watched
    clock = VirtualClock()
    sleeps: list[float] = []
    c = Controller(package, root, interface, codels(sleeps, clock, slow_beat=5), clock=clock)
    events = []
    c.subscribe(lambda e: events.append(e) if e["event"] == "observer" else None)
    c.run(duration=0.2)
    overruns = [e for e in events if e["kind"] == "overrun"]
    assert sleeps == [0.03]
    assert len(overruns) == 1
    e = overruns[0]
    assert e["observer"] == "watched.loop.overrun"
    assert e["bound_ms"] == 10.0 and e["took_ms"] >= 30.0
    labels = [x["label"] for x in e["events"]]
    assert labels[0] == "watched.loop:period" and "watched.loop:exec_start" in labels
    assert e["events"][0]["at_ms"] == pytest.approx(40.0)  # the fifth period opens at 40 ms
    assert "violated: period overran after" in e["message"]


def test_the_event_reaches_an_http_client_and_the_recovery_service_is_requested(watched):
    from runtime.services.client import Client
    from runtime.services.server import ServiceServer

    package, root, interface = watched
    sleeps: list[float] = []
    c = Controller(package, root, interface, codels(sleeps))
    on_violation(c, ["watched.loop.overrun=watched.Stop"])
    c.start()
    server = ServiceServer(c).start()
    client = Client(server.url, timeout=10)
    got: list[dict] = []
    ready = threading.Event()

    def listen() -> None:
        stream = client.events(types="observer", timeout=10)
        ready.set()
        for event in stream:
            got.append(event)
            return

    listener = threading.Thread(target=listen, daemon=True)
    listener.start()
    try:
        hold = client.send("watched", "Hold")
        until(lambda: server.app.state.hub.streams == 1)  # the stream is open
        time.sleep(0.3)  # and the task runs quietly: no event for that while
        assert got == []
        client.call("watched", "Slow", {"seconds": 0.05})
        listener.join(5)
        assert got, "no observer event reached the client"
        event = got[0]
        assert event["event"] == "observer" and event["observer"] == "watched.loop.overrun"
        assert event["took_ms"] >= 50.0 and event["bound_ms"] == 10.0
        assert event["events"][0]["label"] == "watched.loop:period"
        assert event["action"]["service"] == "watched.Stop"
        stop = client.wait(event["action"]["request"], timeout=5)
        assert stop["status"] == "ok"
        assert client.wait(hold, timeout=5)["status"] == "interrupted"
    finally:
        server.stop()
        c.stop()
    assert c.error is None


def test_a_latency_observer_measures_real_time(watched):
    package, root, interface = watched
    clock = VirtualClock()
    c = Controller(package, root, interface, codels([], clock), clock=clock)
    events = []
    c.subscribe(lambda e: events.append(e) if e["event"] == "observer" else None)
    c.submit("watched", "Slow", {"seconds": 0.0})
    c.run(duration=0.05)
    assert [e for e in events if e["kind"] == "latency"] == []  # answered at once
    watch = next(w for w in c.monitor.watches if w.kind == "latency")
    assert watch.name == "slow_answered" and watch.bound == 0.005


@pytest.mark.parametrize("item,message", [
    ("nobody=watched.Stop", "no observer 'nobody' in the model (observers: watched.loop.overrun, slow_answered)"),
    ("watched.loop.overrun=watched.Halt", "component watched has no service 'Halt'"),
    ("watched.loop.overrun", "'watched.loop.overrun' is not OBSERVER=Component.Service"),
])
def test_bad_recovery_bindings_are_refused(watched, item, message):
    package, root, interface = watched
    c = Controller(package, root, interface, codels([]))
    with pytest.raises(RecoveryError, match=message.replace("(", r"\(").replace(")", r"\)")):
        on_violation(c, [item])
    assert c.monitor.actions == {}


def test_a_violation_is_a_line_of_the_runs_output():
    from runtime.services.run import _line

    assert _line({"event": "observer", "message": "observer x violated: period overran after 31.0 ms"}) == \
        "observer: observer x violated: period overran after 31.0 ms"


def test_the_generated_package_keeps_the_models_annotations(tmp_path):
    import subprocess
    import sys

    from genom2bip.cli import main

    assert main([str(Path(__file__).parent / "fixtures/timed/Cruise.gen"), "-o", str(tmp_path), "--monitor"]) == 0
    code = ("import cruise; p = cruise.package(); "
            "print([(a.name, a.arguments) for a in p.annotations], sorted(a.name for a in p.atom_types))")
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, check=True,
                         env={**__import__("os").environ, "PYTHONPATH": f"{tmp_path}:{Path(__file__).parents[1]}"})
    assert "[('monitored', {'tick_us': '1'})]" in out.stdout
    assert "'PeriodObserver'" in out.stdout


def test_a_timed_package_is_refused_by_run(tmp_path):
    import os
    import subprocess
    import sys

    from genom2bip.cli import main

    assert main([str(Path(__file__).parent / "fixtures/timed/Cruise.gen"), "-o", str(tmp_path), "--timed"]) == 0
    out = subprocess.run([sys.executable, "-m", "cruise", "run", "--duration", "1"], cwd=tmp_path,
                         capture_output=True, text=True,
                         env={**os.environ, "PYTHONPATH": f"{tmp_path}:{Path(__file__).parents[1]}"})
    assert out.returncode == 1
    assert "this model is timed (generated with --timed) for verification" in out.stderr
