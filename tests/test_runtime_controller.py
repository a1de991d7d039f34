"""The controller at run time, without HTTP: periods on a clock, codel calls, reports, stopping."""
from __future__ import annotations

import threading
import time

import pytest

from runkit import DALA_CODELS, HELD, ROOT, TICK, build, dala, tick_codels, until
from runtime.controller import Controller, RequestError, VirtualClock
from runtime.genom import Ref, Throw


@pytest.fixture
def tick(tmp_path):
    return build(tmp_path, TICK)


# --------------------------------------------------------------------------- time


def test_periods_start_on_the_clock_rate_grid_and_never_early(tick):
    package, root, interface = tick
    clock = VirtualClock()
    calls = []
    c = Controller(package, root, interface, tick_codels(clock, calls), clock=clock)
    assert [t.period for t in c.timers.timers] == [0.012]  # 10 ms on a 4 ms clock: 12 ms
    assert c.run(duration=0.5) == "stopped"
    times = [t for name, t in calls if name == "tickCount"]
    assert len(times) == 42  # at 0 (start, then count), 12, 24, ... 492 ms
    assert all(abs(t / 0.012 - round(t / 0.012)) < 1e-9 for t in times)
    assert c.timers.stats()[0]["overruns"] == 0
    assert c.data.poster("tick", "Count").value == 42


def test_a_period_longer_than_its_task_period_is_an_overrun(tick):
    package, root, interface = tick
    clock = VirtualClock()
    events = []
    c = Controller(package, root, interface, tick_codels(clock, slow=lambda s: clock.advance(clock.now() + s)),
                   clock=clock)
    c.subscribe(events.append)
    req = c.submit("tick", "Slow", {"seconds": 0.05})
    assert c.run(duration=0.5) == "stopped"
    assert req.status == "ok"
    overruns = [e for e in events if e["event"] == "overrun"]
    assert overruns and overruns[0]["task"] == "tick.t" and overruns[0]["took_ms"] > 12
    assert "overran its 12 ms period" in overruns[0]["message"]
    stats = c.timers.stats()[0]
    assert stats["overruns"] >= 1 and stats["missed"] >= 3  # the 50 ms codel swallowed whole periods


def test_the_engine_sleeps_between_periods_and_wakes_for_a_request(tick):
    package, root, interface = tick
    c = Controller(package, root, interface, tick_codels())
    cpu = time.process_time()
    c.start()
    time.sleep(0.3)
    steps = c.steps
    # 3 steps per 12 ms period (period, exec, sleep), no idle spinning of the untimed control task
    assert steps <= 3 * (0.3 / 0.012 + 2) + 4
    c.stop()
    assert time.process_time() - cpu < 0.25


def test_a_request_wakes_the_engine_sleeping_until_the_next_period(tmp_path):
    package, root, interface = build(tmp_path, TICK.replace("period 10 ms", "period 60 s"))
    c = Controller(package, root, interface, tick_codels())
    c.start()
    try:
        until(lambda: c.timers.stats()[0]["periods"] == 1)  # the first period ran: the engine sleeps for 60 s
        req = c.wait(c.submit("tick", "Work", {"add": 5}).id, timeout=50)
        assert req.final is not None and req.final["status"] == "ok" and req.final["outputs"]["total"] >= 5
        assert c.timers.stats()[0]["periods"] == 1  # answered before the next period, not at it
    finally:
        c.stop()


def test_full_collections_leave_the_model_out_while_the_controller_runs_in_real_time(tick):
    import gc

    package, root, interface = tick
    c = Controller(package, root, interface, tick_codels())
    c.start()
    try:
        # a full collection walking the model held the interpreter for up to 100 ms: periods were missed
        assert not any(o is c.engine for o in gc.get_objects())
    finally:
        c.stop()
    assert any(o is c.engine for o in gc.get_objects())  # given back to the collector once the run ended
    v = Controller(package, root, interface, tick_codels(), clock=VirtualClock())
    v.start(limit=10)
    v.stop()
    assert any(o is v.engine for o in gc.get_objects())  # not real time: nothing to protect


def test_stop_lets_the_running_codel_finish_and_reports_what_is_pending(tick):
    package, root, interface = tick
    entered, finished = threading.Event(), threading.Event()

    def slow(seconds):
        entered.set()
        time.sleep(seconds)
        finished.set()

    c = Controller(package, root, interface, tick_codels(slow=slow))
    c.start()
    req = c.submit("tick", "Slow", {"seconds": 0.3})
    assert entered.wait(2)
    queued = c.submit("tick", "Work", {})  # the engine thread is in the codel: this one waits in its queue
    c.stop()
    assert finished.is_set()
    assert c.status == "stopped"
    for r in (req, queued):
        assert r.final is not None and r.final["status"] == "interrupted" and r.final["by"] is None
        assert "controller stopped" in r.final["message"]
    with pytest.raises(RequestError) as err:
        c.submit("tick", "Work", {})
    assert err.value.status == 503


# --------------------------------------------------------------------------- codels


def test_codels_get_their_declared_arguments_and_write_back_holders():
    pkg = dala()
    seen = {}

    def nddStartGoTo(local_goal, ids_goal, navigating, Nav):
        seen["args"] = (dict(local_goal), type(ids_goal), type(navigating))
        local_goal["x"] = 99.0  # an `in` value is a copy: changing it changes nothing
        ids_goal.value = {"x": 1.5, "y": 2.5, "theta": 0.0}
        navigating.value = True
        return "plan"

    def nddPlan(goal, params, max_speed, Obs, Pos, Way, Speed, Nav):
        seen["plan"] = (goal, params, max_speed, Obs, Pos)
        Speed.value = {"v": 0.1, "w": 0.0}
        return "arrived"

    def nddArrived(navigating, Speed, Nav):
        seen["navigating"] = navigating.value
        navigating.value = False
        return "ether"

    codels = {"NDD": {"nddStartGoTo": nddStartGoTo, "nddPlan": nddPlan, "nddArrived": nddArrived,
                      "nddCheckGoal": lambda goal: None}}
    c = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, codels, clock=VirtualClock())
    c.data.write_poster("POM", "Pos", {"estimate": {"x": 0.0, "y": 0.0, "theta": 0.0}, "covariance": [0, 0, 0],
                                       "stamp": 1.0})
    svc = c.services["NDD.GoTo"]
    req = c.submit("NDD", "GoTo", {"goal": {"x": 1.5, "y": 2.5, "theta": 0.0}})
    # drive the GoTo by hand on the engine: accept, start, then its codels
    b = c.binder
    c.state = c.engine.initial_state()
    c.timers.start(0.0)
    svc.current = svc.queue.popleft()
    b.scope, b.locals = svc.scope, req.locals
    assert b.externs()["NDD_nddStartGoTo"]() == 0
    assert seen["args"] == ({"x": 1.5, "y": 2.5, "theta": 0.0}, Ref, Ref)
    assert req.locals["goal"]["x"] == 1.5
    assert c.data.ids["NDD"]["goal"] == {"x": 1.5, "y": 2.5, "theta": 0.0}
    assert c.data.ids["NDD"]["navigating"] is True
    assert b.externs()["NDD_nddPlan"]() == 1  # "arrived", the second yield
    goal, params, max_speed, obs, pos = seen["plan"]
    assert goal == {"x": 1.5, "y": 2.5, "theta": 0.0} and obs is None and pos["stamp"] == 1.0
    assert params == {"robot_radius": 0.0, "security_distance": 0.0, "goal_tolerance": 0.0}
    assert c.data.poster("NDD", "Speed").value == {"v": 0.1, "w": 0.0} and c.data.poster("NDD", "Speed").seq == 1
    assert c.data.read_input("RFLEX", "Speed") == {"v": 0.1, "w": 0.0}  # port in reads the poster of its name
    assert b.externs()["NDD_nddArrived"]() == 0 and seen["navigating"] is True
    assert b.failure is None


def test_codel_results_map_to_outcomes_and_failures_name_the_codel():
    pkg = dala()

    class e_no_goal(Throw):
        pass

    results = iter([e_no_goal(), Throw("NDD::e_blocked", where={"x": 1}), Throw("e_unheard_of"), "somewhere", 12,
                    KeyError("oops")])

    def nddPlan(**kw):
        r = next(results)
        if isinstance(r, Exception):
            raise r
        return r

    c = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, {"NDD": {"nddPlan": nddPlan}}, clock=VirtualClock())
    call = c.binder.externs()["NDD_nddPlan"]
    assert call() == 2 and c.binder.failure["exception"] == "NDD::e_no_goal"
    assert call() == 3 and c.binder.failure["detail"] == {"where": {"x": 1}}
    assert call() == -1 and "threw e_unheard_of, which is not declared" in c.binder.failure["message"]
    assert call() == -1 and "returned 'somewhere', not a declared yield" in c.binder.failure["message"]
    assert call() == -1 and "returned 12" in c.binder.failure["message"]
    assert call() == -1 and c.binder.failure["message"] == "codel nddPlan raised KeyError: 'oops'"
    assert c.binder.failure["where"].endswith("test_runtime_controller.py:" + c.binder.failure["where"].split(":")[-1])
    missing = c.binder.externs()["NDD_nddArrived"]
    assert missing() == -1 and c.binder.failure["message"].startswith("codel nddArrived is missing")


def test_a_codels_module_that_does_not_import_is_reported_per_codel(tmp_path):
    pkg = dala()
    (tmp_path / "NDD.py").write_text("import no_such_module_here\n")
    (tmp_path / "POM.py").write_text("def pomReset(initialised):\n    return 'ether'\n")
    c = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, str(tmp_path), clock=VirtualClock())
    assert "NDD.nddPlan" in c.binder.missing and "POM.pomReset" not in c.binder.missing
    c.binder.externs()["NDD_nddStop"]()
    assert "importing" in c.binder.failure["message"] and "No module named 'no_such_module_here'" in \
        c.binder.failure["message"]


def test_dala_stub_codels_are_all_found():
    pkg = dala()
    c = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, str(DALA_CODELS), clock=VirtualClock())
    assert c.binder.missing == ["POM.pomReset"]  # left out on purpose
    assert c.run(duration=3.0) == "stopped" and c.error is None  # 3 s: the Planner's 200 ms task, 15 periods
    assert all(t["periods"] > 10 and t["overruns"] == 0 for t in c.timers.stats())


# --------------------------------------------------------------------------- requests


@pytest.mark.parametrize("inputs, message", [
    ({"goal": {"x": 1, "y": 2}}, "goal: missing member 'theta'"),
    ({"goal": {"x": "far", "y": 0, "theta": 0}}, "goal.x: expected a number, got 'far'"),
    ({}, "missing parameter 'goal' (Goal in the world frame)"),
    ({"goal": {"x": 1, "y": 2, "theta": 0}, "speed": 3}, "unknown parameter 'speed' (parameters of NDD.GoTo: goal)"),
    ([1, 2], "must be a JSON object, not list"),
])
def test_bad_parameters_are_refused_with_the_path_of_the_problem(inputs, message):
    pkg = dala()
    c = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, {}, clock=VirtualClock())
    with pytest.raises(RequestError) as err:
        c.submit("NDD", "GoTo", inputs)
    assert err.value.status == 422 and message in err.value.message


def test_a_report_status_outside_the_published_list_is_refused_and_nothing_is_reported(tick):
    """The OpenAPI document lists ``REPORT_STATUSES``: a report with another status would break every client."""
    package, root, interface = tick
    c = Controller(package, root, interface, tick_codels(), clock=VirtualClock())
    heard = []
    c.subscribe(heard.append)
    req = c.submit("tick", "Work", {})
    heard.clear()
    with pytest.raises(ValueError, match="report status 'waiting' is not one of queued, held, started, ok, "):
        c.reports.report(req, "waiting")
    assert [r["status"] for r in req.reports] == ["queued"] and req.status == "queued" and heard == []


def test_partial_structs_take_the_default_members():
    pkg = dala()
    c = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, {}, clock=VirtualClock())
    req = c.submit("NDD", "SetSpeed", {"max_speed": {"v": 0.1}})
    assert req.inputs == {"max_speed": {"v": 0.1, "w": 0.5}}
    with pytest.raises(RequestError) as err:
        c.submit("NDX", "GoTo", {})
    assert err.value.status == 404 and "no component 'NDX'" in err.value.message
    with pytest.raises(RequestError) as err:
        c.submit("NDD", "Goto", {})
    assert err.value.status == 404 and "no service 'Goto'" in err.value.message and "GoTo" in err.value.message


def test_the_simulated_dala_codels_drive_the_robot_to_its_goal():
    pkg = dala()
    c = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, str(ROOT / "descriptions" / "dala" / "codels"),
                   clock=VirtualClock())
    assert c.binder.missing == []
    from genom2bip.mission.session import world_module

    world_module(c).load()  # the open field, the robot at its start
    c.start()

    def call(component, service, **inputs):  # the virtual clock runs as fast as the machine: no bound on time
        req = c.submit(component, service, inputs)
        c.wait(req.id, timeout=600)
        return req

    try:
        for component, service, inputs in [
                ("NDD", "SetParams", {}), ("NDD", "SetDataSource", {}), ("NDD", "SetSpeed", {"max_speed": {"v": 1.0}}),
                ("POM", "Run", {"origin": {"x": 0.0, "y": 0.0, "theta": 0.0}}), ("LaserRF", "Init", {}),
                ("RFLEX", "Init", {}), ("RFLEX", "SetAcceleration", {"acceleration_max": 1.0})]:
            assert call(component, service, **inputs).status == "ok", (component, service)
        running = [c.submit(m, s, {}) for m, s in (("LaserRF", "Start"), ("Aspect", "Run"), ("RFLEX", "TrackSpeed"))]
        until(lambda: all(r.status == "running" for r in running), timeout=600)
        goto = call("NDD", "GoTo", goal={"x": 3.0, "y": 2.0, "theta": 0.0})
        assert goto.final["status"] == "ok", goto.final
        where = c.data.poster("POM", "Pos").value["estimate"]
        assert abs(where["x"] - 3.0) < 0.15 and abs(where["y"] - 2.0) < 0.15
    finally:
        c.stop()
    assert c.error is None


def test_a_failing_task_codel_is_an_event_and_ends_the_permanent_activity(tick):
    package, root, interface = tick
    clock = VirtualClock()
    codels = tick_codels(clock)
    codels["tick"]["tickCount"] = lambda n, Count: "sideways"
    c = Controller(package, root, interface, codels, clock=clock)
    events = []
    c.subscribe(events.append)
    assert c.run(duration=0.1) == "stopped"
    errors = [e for e in events if e["event"] == "codel_error"]
    assert len(errors) == 1 and errors[0]["task"] == "tick.t" and errors[0]["codel"] == "tickCount"
    assert "returned 'sideways', not a declared yield (declared: pause::count)" in errors[0]["message"]
    assert c.timers.stats()[0]["periods"] == 9  # the task's periods go on, empty


# --------------------------------------------------------------------------- faults: nothing silent, nothing lost

#: A component whose attributes store into an ids struct member (p.a) and the whole struct.
STORE = """
component store {
  struct pair { double a; double b; };
  ids { pair p; };
  attribute SetA(in p.a = 1.0);
  attribute SetP(in p);
};
"""


@pytest.mark.parametrize("raised", [SystemExit(3), KeyboardInterrupt(), GeneratorExit()])
def test_a_codel_raising_a_base_exception_fails_its_service_and_the_controller_keeps_running(tick, raised):
    package, root, interface = tick
    codels = tick_codels()

    def tickWork(add, n, total):
        raise raised

    codels["tick"]["tickWork"] = tickWork
    c = Controller(package, root, interface, codels, clock=VirtualClock())
    first = c.submit("tick", "Work", {"add": 2})
    second = c.submit("tick", "Slow", {"seconds": 0.0})
    assert c.run(duration=0.2) == "stopped" and c.error is None
    assert first.status == "failed" and first.final["error"] == "python exception"
    assert first.final["message"] == f"codel tickWork raised {type(raised).__name__}" + (": 3" if raised.args else "")
    assert first.final["codel"] == "tickWork" and first.final["where"].endswith("test_runtime_controller.py:" +
                                                                                 first.final["where"].split(":")[-1])
    assert second.status == "ok"


def test_an_engine_thread_that_dies_says_so_on_the_interface_and_ends_every_request(tick):
    package, root, interface = tick
    c = Controller(package, root, interface, tick_codels())
    events = []
    c.subscribe(events.append)
    original = c._choose

    def dying(now):
        if c.requests and c.requests[1].status == "running":
            raise SystemExit("the engine's own code gave up")
        return original(now)

    c._choose = dying
    c.start()
    req = c.submit("tick", "Slow", {"seconds": 0.0})
    c.wait(req.id, timeout=5)
    c.stop(timeout=5)
    assert not c.alive()
    assert req.final is not None and req.final["status"] == "interrupted"
    assert "the engine stopped on SystemExit: the engine's own code gave up" in req.final["message"]
    summary = c.summary()
    assert summary["status"] == "error" and summary["error"] == "the engine stopped on SystemExit: " \
                                                                "the engine's own code gave up"
    assert events[-1] == {"event": "controller", "status": "error", "steps": c.steps, "error": summary["error"]}
    with pytest.raises(RequestError) as err:
        c.submit("tick", "Work")
    assert err.value.status == 503 and err.value.message == "the controller has stopped on an error (the engine " \
        "stopped on SystemExit: the engine's own code gave up); request to tick.Work not accepted"


def test_a_dead_engine_thread_is_seen_even_when_its_run_could_not_say_so(tick):
    package, root, interface = tick
    c = Controller(package, root, interface, tick_codels())
    c.status = "running"
    c._thread = threading.Thread(target=lambda: None)
    c._thread.start()
    c._thread.join()
    assert c.summary()["status"] == "error" and c.summary()["error"] == "the engine thread has died"


def test_an_input_that_cannot_be_stored_in_the_ids_is_refused_naming_it(tmp_path):
    package, root, interface = build(tmp_path, STORE, "store")
    c = Controller(package, root, interface, {}, clock=VirtualClock())
    c.data.ids["store"]["p"] = [0.0, 0.0]  # a codel left something else than the struct there
    with pytest.raises(RequestError) as err:
        c.submit("store", "SetA", {"a": 2.0})
    assert err.value.status == 422
    assert err.value.message == "bad request to store.SetA: parameter 'a' cannot be stored in ids member p.a: " \
                                "p is not a struct"
    assert c.requests == {} and c.data.ids["store"]["p"] == [0.0, 0.0]


def test_an_input_whose_ids_member_changed_shape_before_it_started_is_reported(tmp_path):
    package, root, interface = build(tmp_path, STORE, "store")
    c = Controller(package, root, interface, {}, clock=VirtualClock())
    events = []
    c.subscribe(events.append)
    req = c.submit("store", "SetA", {"a": 2.0})
    c.data.ids["store"]["p"] = 7  # changed between the request's acceptance and its start
    c.run(duration=1.0)
    errors = [e for e in events if e["event"] == "codel_error"]
    assert len(errors) == 1 and errors[0]["request"] == req.id and errors[0]["input"] == "a"
    assert errors[0]["message"] == f"store.SetA request {req.id}: parameter 'a' not stored in ids member p.a: " \
                                   "p is not a struct"
    assert req.failure["error"] == "bad input" and c.data.ids["store"]["p"] == 7


def test_a_poster_value_of_the_wrong_type_fails_its_writer_with_the_path(tick):
    package, root, interface = tick
    codels = tick_codels()

    def tickCount(n, Count):
        Count.value = "many"
        return "pause::count"

    codels["tick"]["tickCount"] = tickCount
    c = Controller(package, root, interface, codels, clock=VirtualClock())
    events = []
    c.subscribe(events.append)
    c.run(duration=0.05)
    errors = [e for e in events if e["event"] == "codel_error"]
    assert errors and errors[0]["codel"] == "tickCount" and errors[0]["error"] == "bad poster value"
    assert errors[0]["message"] == "codel tickCount wrote poster tick.Count (argument Count): " \
                                   "Count: expected an integer, got 'many'"
    assert c.data.poster("tick", "Count").seq == 0  # nothing published
    assert not [e for e in events if e["event"] == "poster"]


def test_requests_beyond_the_bound_of_waiting_ones_are_refused_with_429(tick):
    package, root, interface = tick
    c = Controller(package, root, interface, tick_codels(), clock=VirtualClock(), max_queued=2)
    first, second = c.submit("tick", "Work"), c.submit("tick", "Work")
    with pytest.raises(RequestError) as err:
        c.submit("tick", "Work")
    assert err.value.status == 429
    assert (
        err.value.message == "2 requests are waiting to be taken: request to tick.Work not accepted, send it again "
        "later"
    )
    assert sorted(c.requests) == [first.id, second.id]
    c.run(duration=0.1)
    assert first.status == second.status == "ok"


def test_a_codel_may_run_its_declared_wcet_else_its_task_period_else_the_default(tmp_path):
    from runtime.controller.stuck import DEFAULT_BOUND, Bound, bounds

    text = TICK.replace("yield pause::count;", "yield pause::count wcet 3 ms;")
    package, root, interface = build(tmp_path, text)
    assert interface["components"]["tick"]["tasks"]["t"]["codels"]["tick_tickCount"]["wcet_us"] == 3000
    got = bounds(interface)
    assert got["tick_tickCount"] == Bound(0.003, "its declared WCET")
    assert got["tick_tickStart"] == got["tick_tickSlow"] == Bound(0.01, "the period of task tick.t; no WCET declared")
    assert got["tick_tickWork"] == Bound(DEFAULT_BOUND, "the default for the control task; no WCET declared")


def test_a_stuck_validate_codel_is_reported_detached_and_its_step_fired_once_when_it_returns(tmp_path):
    package, root, interface = build(tmp_path, HELD, "held")
    release, calls = threading.Event(), []

    def heldTick(n):
        n.value += 1
        return "pause::start"

    def heldCheck(seen):
        calls.append(seen)
        if seen == 7:
            release.wait(30)

    c = Controller(package, root, interface, {"held": {"heldTick": heldTick, "heldCheck": heldCheck}})
    events, overrun = [], threading.Event()
    c.subscribe(lambda e: (events.append(e), e["event"] == "codel_overrun" and overrun.set()))
    c.start()
    try:
        req = c.submit("held", "Set", {"seen": 7})
        assert overrun.wait(30)
        stuck = next(e for e in events if e["event"] == "codel_overrun")
        assert (stuck["codel"], stuck["service"], stuck["request"], stuck["bound_ms"]) == \
            ("heldCheck", "held.Set", req.id, 100.0), stuck
        ticks = c.data.ids["held"]["n"]
        deadline = time.monotonic() + 30
        while c.data.ids["held"]["n"] < ticks + 5:  # the task goes on while the codel is held
            assert time.monotonic() < deadline
            time.sleep(0.01)
        assert req.final is None and c.detached
        release.set()
        assert c.wait(req.id, timeout=30).final["status"] == "ok"
        assert c.data.ids["held"]["seen"] == 7 and calls == [7]  # called once, its step fired once
        assert c.wait(c.submit("held", "Set", {"seen": 8}).id, timeout=30).final["status"] == "ok"
        assert calls == [7, 8] and not c.detached and not c.frozen
    finally:
        release.set()
        c.stop(timeout=30)
    assert c.status == "stopped" and c.error is None
