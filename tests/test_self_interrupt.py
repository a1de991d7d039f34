"""An activity that interrupts itself (GenoM3): a new request interrupts the running one, which runs its stop codel
and ends ``interrupted``, then the new one starts; at run time and in the model that exploration walks."""
from __future__ import annotations

import threading

import pytest

from runkit import build
from runtime.controller import Controller, VirtualClock
from runtime.explore import StateSpace, explore
from runtime.genom import Throw

TRACK = """
component track {
  exception e_far;
  ids { long target; long steps; long stopped; };
  task t { period 10 ms; };
  activity Go(in long goal = 0 : "where to go") {
    task t;
    interrupts Go;
    validate trackCheck(local in goal);
    codel <start> trackStart(local in goal, ids out target) yield run;
    codel <run> trackRun(ids in target, ids inout steps) yield pause::run, ether;
    codel <stop> trackStop(ids inout stopped) yield ether;
    throw e_far;
  };
};
"""


def codels(log: list):
    def trackCheck(goal):
        if goal < 0:
            raise Throw("e_far")

    def trackStart(goal, target):
        log.append(("start", goal))
        target.value = goal
        return "run"

    def trackRun(target, steps):
        steps.value += 1
        return "pause::run"  # it runs until something interrupts it

    def trackStop(stopped):
        log.append(("stop", None))
        stopped.value += 1
        return "ether"

    return {"track": {"trackCheck": trackCheck, "trackStart": trackStart, "trackRun": trackRun,
                      "trackStop": trackStop}}


@pytest.fixture
def running(tmp_path):
    package, root, interface = build(tmp_path, TRACK, "track")
    log: list = []
    c = Controller(package, root, interface, codels(log), clock=VirtualClock())
    started: dict[int, threading.Event] = {}
    lock = threading.Lock()

    def heard(event):
        if event["event"] == "report" and event["status"] == "started":
            with lock:
                started.setdefault(event["request"], threading.Event()).set()

    def was_started(rid: int) -> bool:
        with lock:
            event = started.setdefault(rid, threading.Event())
        return event.wait(60)

    c.subscribe(heard)
    c.start()
    try:
        yield c, log, was_started
    finally:
        c.stop(timeout=60)


def test_a_second_request_interrupts_the_running_one_which_stops_then_the_new_one_starts(running):
    c, log, was_started = running
    first = c.submit("track", "Go", {"goal": 1})
    assert was_started(first.id)
    second = c.submit("track", "Go", {"goal": 2})  # 409 "busy" before: an activity took one request at a time
    ended = c.wait(first.id, timeout=60).final
    assert ended["status"] == "interrupted" and ended["by"] == "track.Go" and ended["by_request"] == second.id
    assert was_started(second.id)
    assert log == [("start", 1), ("stop", None), ("start", 2)]  # the old one's stop codel, then the new start
    assert c.data.ids["track"]["stopped"] == 1 and c.data.ids["track"]["target"] == 2
    assert c.get(second.id).status == "running"


def test_a_new_request_its_validate_codel_refuses_leaves_the_running_one_alone(running):
    c, log, was_started = running
    first = c.submit("track", "Go", {"goal": 1})
    assert was_started(first.id)
    refused = c.wait(c.submit("track", "Go", {"goal": -1}).id, timeout=60).final
    assert refused["status"] == "rejected" and refused["exception"].endswith("e_far")
    assert c.get(first.id).status == "running" and ("stop", None) not in log
    third = c.submit("track", "Go", {"goal": 3})
    assert c.wait(first.id, timeout=60).final["by_request"] == third.id
    assert was_started(third.id)


def test_the_model_interrupts_the_running_request_before_the_new_one_starts(tmp_path):
    package, root, _ = build(tmp_path, TRACK, "track")
    space = StateSpace(package, root, requests=2, keep_edges=True)
    result = explore(space)
    assert not result.deadlocks
    labels = space.labels
    edges = {sid: space.successors(sid) for sid in range(len(space.packed))}
    preempted = [dst for src, out in edges.items() for lab, dst in zip(out[::2], out[1::2])
                 if labels[lab] == "track.Go:preempt"]
    assert preempted, "a second request to Go never interrupts the running one"
    trace = [s.label for s in space.trace_to(preempted[0])]
    assert trace.count("track.Go:trigger") == 2 and trace.index("track.Go:start") < trace.index("track.Go:trigger", 2)
    # from there, the new request starts only once the old one has ended, and it does start
    ends = {"track.Go:interrupted", "track.Go:finish", "track.Go:fail"}
    seen, todo, started_after_end = {preempted[0]}, [preempted[0]], False
    while todo:
        sid = todo.pop()
        out = edges[sid]
        for lab, dst in zip(out[::2], out[1::2]):
            assert labels[lab] != "track.Go:start", "the new request started while the old one ran"
            if labels[lab] in ends:
                started_after_end |= any(labels[x] == "track.Go:start" for x in edges[dst][::2])
                continue
            if dst not in seen:
                seen.add(dst)
                todo.append(dst)
    assert started_after_end


def test_an_activity_that_does_not_interrupt_itself_still_takes_one_request_at_a_time(tmp_path):
    from runtime.controller.requests import RequestError

    package, root, interface = build(tmp_path, TRACK.replace("    interrupts Go;\n", ""), "track")
    log: list = []
    c = Controller(package, root, interface, codels(log), clock=VirtualClock())
    c.start()
    try:
        first = c.submit("track", "Go", {"goal": 1})
        with pytest.raises(RequestError) as err:
            c.submit("track", "Go", {"goal": 2})
        assert err.value.status == 409 and f"track.Go is busy with request {first.id}" in err.value.message
    finally:
        c.stop(timeout=60)
    assert c.get(first.id).final["status"] == "interrupted"  # by the stop, not by another request
