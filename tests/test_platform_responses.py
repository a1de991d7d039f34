"""Response times: every maximum reported is reached by its trace, clock zones and ticks agree, and what a run
without --platform assumes is said in one line."""
from __future__ import annotations

import json
import re

import pytest

from genom2bip.loading import TimeSettings
from genom2bip.verify import build_model
from genom2bip.verify.zones import ResponseResult, check_response_times, check_timing
from platformkit import (
    FIXTURES, FINALS, ROOT, observed_response, platform_file, printed_trace, response_ms, response_table, verify,
)
from runtime.explore import StateSpace

ZENO = FIXTURES / "Zeno.gen"
PAIR = FIXTURES / "Pair.gen"
SHARED = FIXTURES / "Shared.gen"
ANOMALY = FIXTURES / "Anomaly.gen"
AFTER = FIXTURES / "After.gen"
AFTER_BOTH = FIXTURES / "AfterBoth.gen"
OVERDUE = FIXTURES / "Overdue.gen"
OVERDUE_PLATFORM = ("cores: 1\npolicy: edf\nbest: wcet\ntasks:\n  Overdue.a:\n    delay: [1 ms, 1 ms]\n"
                    "  Overdue.b:\n    delay: [5 ms, 5 ms]\n")

#: (name, description, defines, platform file, mission): small models with every kind of response.
CASES = [
    ("pair-1-edf", PAIR, {}, "cores: 1\npolicy: edf\nbest: wcet\n", None),
    ("pair-1-fp", PAIR, {}, "cores: 1\npolicy: fixed-priority\n", None),
    ("shared-slow", SHARED, {"SLOW": "1"}, "cores: 2\npolicy: edf\n", None),
    ("anomaly", ANOMALY, {}, "cores: 1\npolicy: fixed-priority\nbest: wcet\n"
                             "execution:\n  Anomaly.mid.mid_step: [1 ms, 4 ms]\n", None),
    # the case whose zones merge (runtime/zones/search.py merge_into): merging is compared on it
    ("anomaly-edf", ANOMALY, {}, "cores: 1\npolicy: edf\nexecution:\n  Anomaly.mid.mid_step: [1 ms, 4 ms]\n", None),
    ("zeno-services", ZENO, {"PERIOD": "10"}, "cores: 1\n", None),
    ("zeno-client", ZENO, {"PERIOD": "10"}, "cores: 1\n", FIXTURES / "a_then_b.yaml"),
    ("endless", FIXTURES / "Endless.gen", {}, "cores: 1\npolicy: fixed-priority\nbest: wcet\n", None),
    ("catchup", FIXTURES / "Catchup.gen", {}, "cores: 1\ntasks:\n  Catchup.main:\n    delay: [0 ms, 2 ms]\n",
     FIXTURES / "run_once.yaml"),
    # a done flag that dies once the client has sent its last request reading it (runtime/explore/layout.py)
    ("after-client", AFTER, {}, "cores: 1\n", FIXTURES / "set_then_go.yaml"),
    # two done flags read only together: one is dead once the other is false for good (runtime/explore/conjunctions.py)
    ("after-both", AFTER_BOTH, {}, "cores: 1\n", FIXTURES / "set_both_then_go.yaml"),
    # a task with nothing to run in most periods: those close before the cores are granted (rests_first)
    ("spare", FIXTURES / "Spare.gen", {}, "cores: 2\nbest: 1 ms\n", FIXTURES / "run_then_help.yaml"),
    # two tasks waiting past their deadlines: EDF's time left below 0, the earlier deadline first
    ("overdue", OVERDUE, {}, OVERDUE_PLATFORM, None),
]
#: The cases whose tick model is small enough to explore state by state in a test (zeno-services is not).
SMALL = [c for c in CASES if c[0] != "zeno-services"]


def model_of(tmp_path, gen, defines, platform, mission):
    settings = TimeSettings(platform=platform_file(tmp_path, platform), client=mission, responses=True)
    return build_model([gen], defines={k: v for k, v in defines.items()}, time=settings)


def tick_maxima(model) -> dict[str, int]:
    """The largest value of every response observer's clock over the tick model's reachable states.

    An oracle independent of the zone explorer: the reference semantics explored state by state, every
    variable kept exact.
    """
    space = StateSpace(model.package, model.root, {}, None, False, ())
    atoms = [fa for fa in space.engine.flat.atoms if fa.type.name == "ResponseObserver"]
    k = 0
    while k < len(space):
        space.successors(k)
        k += 1
        assert k < 200_000, "the fixture is meant to be small"
    best = {fa.name: 0 for fa in atoms}
    for sid in range(len(space)):
        state = space.engine_state(sid)
        for fa in atoms:
            best[fa.name] = max(best[fa.name], state[fa.slot("c")])
    return best


@pytest.mark.parametrize("name,gen,defines,platform,mission", CASES, ids=[c[0] for c in CASES])
def test_every_maximum_is_reached_by_its_trace(tmp_path, name, gen, defines, platform, mission):
    model = model_of(tmp_path, gen, defines, platform, mission)
    results = [r for r in check_timing(model, (), responses=True) if isinstance(r, ResponseResult)]
    assert results
    for r in results:
        data = json.loads(json.dumps(r.to_json()))  # what a campaign records
        details = data["details"]
        if details["value_ms"] is None:
            continue
        trace = data["trace"]
        assert trace is not None and trace["timed"], data
        steps = [(s["time_ms"], s["label"]) for s in trace["steps"]]
        end = steps[-1][0] if steps else 0.0
        owner = details["owner"]
        seen = observed_response(owner, details["kind"], steps, end)
        assert seen == details["value_ms"], f"{owner}: the trace shows {seen} ms, the result says " \
                                            f"{details['value_ms']} ms\n{trace['steps']}"


@pytest.mark.parametrize("name,gen,defines,platform,mission", CASES, ids=[c[0] for c in CASES])
def test_every_overrun_trace_holds_a_period_open_longer_than_the_period(tmp_path, name, gen, defines, platform,
                                                                       mission):
    model = model_of(tmp_path, gen, defines, platform, mission)
    violated = [r.to_json() for r in check_timing(model, ("overrun",)) if r.verdict.value == "violated"]
    assert bool(violated) == (name in ("pair-1-edf", "pair-1-fp", "shared-slow", "zeno-services", "catchup",
                                       "overdue"))
    for data in violated:
        steps = [(s["time_ms"], s["label"]) for s in data["trace"]["steps"]]
        owner = data["details"]["observer"].rsplit(".", 1)[0]
        assert observed_response(owner, "task", steps, steps[-1][0]) > data["details"]["bound_ms"], data["trace"]


@pytest.mark.parametrize("name,gen,defines,platform,mission", SMALL, ids=[c[0] for c in SMALL])
def test_zones_and_ticks_agree_on_the_maxima(tmp_path, name, gen, defines, platform, mission):
    model = model_of(tmp_path, gen, defines, platform, mission)
    zones = {r.observer: r.value_ticks for r in check_timing(model, (), responses=True)
             if isinstance(r, ResponseResult) and not r.unbounded}
    ticks = tick_maxima(model_of(tmp_path, gen, defines, platform, mission))
    for observer, value in zones.items():
        if observer in ticks and value is not None:
            assert ticks[observer] == value, f"{observer}: zones {value} ticks, tick by tick {ticks[observer]}"
    assert {o for o, v in zones.items() if v is not None} <= set(ticks)


def test_merging_zones_changes_no_maximum_and_no_verdict(tmp_path):
    # Zones of one discrete state whose union is one zone are merged (runtime/zones/search.py); the maxima and
    # the observers in error must be those of the search that keeps every zone apart.
    from runtime.zones.search import ZoneExplorer

    merged = 0
    for name, gen, defines, platform, mission in CASES:
        model = model_of(tmp_path, gen, defines, platform, mission)
        apart = ZoneExplorer(model.package, model.root, merge=False).explore()
        one = ZoneExplorer(model.package, model.root).explore()
        assert apart.complete and one.complete, name
        assert {c: v for c, (v, _) in one.maxima.items()} == {c: v for c, (v, _) in apart.maxima.items()}, name
        assert set(one.violations) == set(apart.violations), name
        merged += one.merged
    assert merged, "no case merged a zone: the comparison says nothing"


def test_pruning_below_covered_nodes_changes_no_answer(tmp_path, monkeypatch):
    # A node expanded before a larger zone of its state came is covered then, and what lies below it is not
    # expanded further unless it covers a newcomer (ZoneExplorer.prune, on by default): every maximum, observer in
    # error, response time and lasso's verdict must be those of the search that expands every node it keeps.
    import genom2bip.verify.zones as zones
    from runtime.zones.search import ZoneExplorer

    def answers(model) -> list:
        return [(r.observer, r.verdict, getattr(r, "value_ticks", None), getattr(r, "unbounded", None))
                for r in check_timing(model, ("overrun", "latency"), responses=True)]

    seen = {"fewer": 0, "pruned": 0, "revived": 0}
    for name, gen, defines, platform, mission in CASES:
        model = model_of(tmp_path, gen, defines, platform, mission)
        full = ZoneExplorer(model.package, model.root, prune=False).explore()
        pruned = ZoneExplorer(model.package, model.root).explore()
        assert full.complete and pruned.complete, name
        assert full.pruned == full.revived == 0, name
        assert {c: v for c, (v, _) in pruned.maxima.items()} == {c: v for c, (v, _) in full.maxima.items()}, name
        assert set(pruned.violations) == set(full.violations), name
        assert pruned.discrete == full.discrete, name
        seen["fewer"] += pruned.states < full.states
        seen["pruned"] += pruned.pruned > 0
        seen["revived"] += pruned.revived > 0
        if pruned.states == full.states and not pruned.pruned:
            continue  # the same search: the same answers
        with_pruning = answers(model)
        with monkeypatch.context() as m:
            m.setattr(zones, "explorer", lambda model, options=None: ZoneExplorer(model.package, model.root,
                                                                               prune=False))
            assert answers(model) == with_pruning, name
    assert all(seen.values()), f"the cases say nothing of some part of pruning: {seen}"


def test_keeping_only_upper_bounds_of_watched_clocks_changes_no_maximum_and_no_verdict(tmp_path):
    # The observers' and response times' clocks, which no guard reads, keep their upper bounds only
    # (model.py's grow_only): the maxima and the observers in error must be those of the search that keeps
    # their lower bounds, and some case must store fewer zones for it.
    from runtime.zones.search import ZoneExplorer

    fewer = 0
    for name, gen, defines, platform, mission in CASES:
        model = model_of(tmp_path, gen, defines, platform, mission)
        exact = ZoneExplorer(model.package, model.root, grow_only=False).explore()
        z = ZoneExplorer(model.package, model.root)
        grown = z.explore()
        assert exact.complete and grown.complete, name
        assert {c: v for c, (v, _) in grown.maxima.items()} == {c: v for c, (v, _) in exact.maxima.items()}, name
        assert set(grown.violations) == set(exact.violations), name
        assert grown.discrete == exact.discrete, name
        watched = {c for _, c, _ in z.model.observers.values()} | {c for _, c in z.model.measures.values()}
        assert z.grow_only and set(z.grow_only) <= watched, name
        assert grown.states <= exact.states, name
        fewer += grown.states < exact.states
    assert fewer, "no case stored fewer zones: the comparison says nothing"


def test_response_times_by_ticks_are_printed_or_refused(tmp_path, capsys):
    # --time-search ticks with --response-times must not drop the response times without a word.
    path = platform_file(tmp_path, "cores: 1\npolicy: edf\nbest: wcet\n")
    code, out, err = verify(capsys, PAIR, "--timed", "--platform", path, "--response-times", "--time-search", "ticks")
    if code == 2:
        assert "--response-times" in err
    else:
        assert response_ms(out) == {"Pair.fast": 12, "Pair.slow": 12}, out


def test_a_platform_model_written_as_bip_is_verified_alike(tmp_path, capsys):
    # The scheduler's ports are BIP2 names (none is a reserved word), and --response-times at generation puts
    # the observers in the .bip, which verify then reads back with the verdicts and maxima of the descriptions.
    from genom2bip.cli import main

    path = platform_file(tmp_path, "cores: 1\npolicy: edf\nbest: wcet\n")
    assert main([str(PAIR), "--timed", "--platform", str(path), "--response-times", "-o", str(tmp_path)]) == 0
    bip = tmp_path / "pair" / "pair.bip"
    assert "ResponseObserver" in bip.read_text()
    capsys.readouterr()
    code, out, _ = verify(capsys, bip, "--timed", "--response-times")
    assert code == 4 and response_ms(out) == {"Pair.fast": 12, "Pair.slow": 12}, out


def test_response_times_of_a_bip_without_their_observers_say_so(tmp_path, capsys):
    from genom2bip.cli import main

    path = platform_file(tmp_path, "cores: 1\npolicy: edf\nbest: wcet\n")
    assert main([str(PAIR), "--timed", "--platform", str(path), "-o", str(tmp_path)]) == 0
    capsys.readouterr()
    code, out, _ = verify(capsys, tmp_path / "pair" / "pair.bip", "--timed", "--response-times")
    assert "response times: the model has no response-time observer (a .bip carries them when generated with " \
           "--timed --response-times)" in out.splitlines(), out
    assert "\nresponse times (" not in out
    assert code == 4  # the overrun verdicts are still given


# --------------------------------------------------------------------------- without --platform


def test_without_platform_one_line_says_each_task_has_its_core_and_exact_wcets(capsys):
    code, out, _ = verify(capsys, PAIR, "--timed", "--schedulability")
    lines = [line for line in out.splitlines() if line.startswith("platform: ")]
    assert lines == ["platform: a core per task, codels taking their WCET (no --platform)"], out
    assert code == 0  # a core each: 6 ms of 10


def test_without_platform_response_times_say_the_same_line(capsys):
    code, out, _ = verify(capsys, PAIR, "--timed", "--response-times")
    lines = [line for line in out.splitlines() if line.startswith("platform: ")]
    assert lines == ["platform: a core per task, codels taking their WCET (no --platform)"], out
    assert response_ms(out) == {"Pair.fast": 6, "Pair.slow": 6}
    assert code == 0


# --------------------------------------------------------------------------- responses without a bound

ENDLESS = FIXTURES / "Endless.gen"
STARVED = FIXTURES / "Starved.gen"
POLLING = FIXTURES / "Polling.gen"
FP1 = "cores: 1\npolicy: fixed-priority\nbest: wcet\n"
#: What the table says of a response without a bound: one that may go on for ever, one that only an interruption
#: ends (its codels never reach ether nor throw from its start).
NO_BOUND = "no bound: a request can wait for ever"
UNTIL_STOPPED = "runs until stopped: once started, no final report without an interruption"
#: ... and one whose lasso runs the service itself, period after period, though its codels could end it.
KEEPS_RUNNING = "runs until stopped: works every period once started, may go on for ever (not a fault)"
WAITING = FIXTURES / "Waiting.gen"


def lasso_of(out: str, owner: str, value: str = NO_BOUND) -> tuple[list[tuple[float, str]], list[str], int]:
    """The steps of ``owner``'s printed lasso (headed by its ``value``), its lines, and the step after which it
    loops."""
    block = out.split(f"\n{owner}: {value} (", 1)[1]
    loop = re.search(r"^    \.\.\. and back to the state after step (\d+), forever$", block, re.M)
    assert loop, block
    lines = block[:loop.start()].splitlines()[1:]
    return printed_trace(out, f"{owner}: {value}"), lines, int(loop.group(1))


def after_step(lines: list[str], n: int) -> list[str]:
    """The printed lines of a trace after its step ``n`` (0: all of them)."""
    numbers = [int(m.group(1)) if (m := re.match(r"^\s+(\d+)\s+\[", line)) else None for line in lines]
    assert n == 0 or n in numbers, (n, lines)
    return lines if n == 0 else lines[numbers.index(n) + 1:]


def test_a_service_that_only_an_interruption_ends_runs_until_stopped_shown_by_a_lasso_where_time_passes(
        tmp_path, capsys):
    code, out, _ = verify(capsys, ENDLESS, "--timed", "--platform", platform_file(tmp_path, FP1), "--response-times")
    table = response_table(out)
    assert table["Endless.Watch"] == UNTIL_STOPPED, out
    # Once: requested just after a period closed, it waits 10 ms, then Watch's two codels (1 ms each) may go first.
    assert table["Endless.Once"] == "14 ms"
    steps, lines, loop = lasso_of(out, "Endless.Watch", UNTIL_STOPPED)
    labels = [label for _, label in steps]
    assert "Endless.Watch:trigger" in labels
    assert not any(label.startswith("Endless.Watch:") and label.rsplit(":", 1)[1] in
                   ("finish", "fail", "interrupted", "reject") for label in labels)
    # The cycle lets time pass: a request waits for ever, not an infinity of steps at one instant.
    assert any("time passes" in line for line in after_step(lines, loop)), lines
    assert code == 0


@pytest.mark.parametrize("exceptions, stopped", [(True, ""), (False, "Polling.Track")],
                         ids=["exceptions", "no-exceptions"])
def test_the_model_names_the_services_that_only_an_interruption_ends(exceptions, stopped):
    """Read from the codels reached from ``start``: Poll yields ether; Track's stop codel does, but only an
    interruption leads there, so Track ends by itself only when its codel may throw."""
    settings = TimeSettings(responses=True, exceptions=exceptions)
    for gen, expected in ((POLLING, stopped), (ENDLESS, "Endless.Watch")):
        (timed,) = [a for a in build_model([gen], time=settings).package.annotations if a.name == "timed"]
        assert timed.arguments.get("until_stopped", "") == expected, gen


@pytest.mark.parametrize("options, track", [((), KEEPS_RUNNING), (("--no-exceptions",), UNTIL_STOPPED)],
                         ids=["exceptions", "no-exceptions"])
def test_a_service_that_works_every_period_runs_until_stopped_whether_or_not_its_codels_can_end_it(
        tmp_path, capsys, options, track):
    """Poll may yield ether; Track only pauses, and ends by itself only when its codel may throw e_lost.  Both
    lassos run the service's own codels every period: no request waits, so neither is worded as a fault."""
    code, out, _ = verify(capsys, POLLING, "--timed", "--platform", platform_file(tmp_path, FP1), "--response-times",
                          *options)
    table = response_table(out)
    assert (table["Polling.Poll"], table["Polling.Track"]) == (KEEPS_RUNNING, track), out
    for owner, value in (("Polling.Poll", KEEPS_RUNNING), ("Polling.Track", track)):
        steps, lines, loop = lasso_of(out, owner, value)  # each wording keeps its lasso
        labels = [label for _, label in steps]
        assert f"{owner}:trigger" in labels and f"{owner}:start" in labels
        assert not any(label.startswith(f"{owner}:") and label.rsplit(":", 1)[1] in FINALS for label in labels)
        assert any("time passes" in line for line in after_step(lines, loop)), lines
    assert code == 0


def test_a_service_that_runs_until_stopped_in_json(tmp_path):
    model = model_of(tmp_path, ENDLESS, {}, FP1, None)
    times = check_response_times(model)
    details = {r.owner: r.to_json()["details"] for r in times.responses}
    assert details["Endless.Watch"]["unbounded"] is True and details["Endless.Watch"]["until_stopped"] is True
    assert details["Endless.Once"]["unbounded"] is False and details["Endless.Once"]["until_stopped"] is False
    watch = next(r for r in times.responses if r.owner == "Endless.Watch")
    assert watch.message == UNTIL_STOPPED and watch.trace is not None and watch.trace.loop is not None
    values = times.values()
    assert (values["Endless.Watch"], values["Endless.Once"]) == ("until stopped", 14.0)


def test_a_service_that_can_end_by_itself_but_keeps_running_is_until_stopped_in_json(tmp_path):
    polling = check_response_times(model_of(tmp_path, POLLING, {}, FP1, None))
    details = {r.owner: r.to_json()["details"] for r in polling.responses}
    assert {o: d["until_stopped"] for o, d in details.items()} == \
        {"Polling.main": False, "Polling.Poll": False, "Polling.Track": False}
    assert {o: d["keeps_running"] for o, d in details.items()} == \
        {"Polling.main": False, "Polling.Poll": True, "Polling.Track": True}
    assert details["Polling.Poll"]["unbounded"] is True
    assert polling.values()["Polling.Poll"] == polling.values()["Polling.Track"] == "until stopped"
    assert polling.message == "run until stopped: Polling.Poll, Polling.Track"


def test_a_service_whose_codels_can_cycle_and_that_the_mission_never_sends_is_never_requested(tmp_path, capsys):
    """Track's observer only waits for a report (its codels may go round for ever, so there is no cap to measure
    against); with a mission that sends Poll alone, no state watches a Track request: "never requested", as for a
    measured service, not "every request ends"."""
    mission = tmp_path / "poll_only.yaml"
    mission.write_text("mission: poll-only\nsteps:\n  - send: Polling.Poll\n    until: started\n")
    code, out, _ = verify(capsys, POLLING, "--timed", "--platform", platform_file(tmp_path, FP1), "--client", mission,
                          "--response-times")
    table = response_table(out)
    assert table["Polling.Track"] == "never requested", out
    assert table["Polling.Poll"] == KEEPS_RUNNING, out
    times = check_response_times(model_of(tmp_path, POLLING, {}, FP1, mission))
    track = next(r for r in times.responses if r.owner == "Polling.Track")
    assert times.values()["Polling.Track"] == "never requested" and track.verdict.value == "holds"
    assert code == 0


def test_a_request_that_never_gets_its_core_has_no_bound_worded_as_a_wait(tmp_path, capsys):
    """Ping would end in one codel, but idle never gets the core: its lasso never runs Ping, a real wait."""
    code, out, _ = verify(capsys, WAITING, "--timed", "--platform", platform_file(tmp_path, FP1), "--response-times")
    table = response_table(out)
    assert table["Waiting.Ping"] == NO_BOUND, out
    steps, lines, loop = lasso_of(out, "Waiting.Ping")
    assert not any(label.startswith("Waiting.Ping:exec") for _, label in steps)
    times = check_response_times(model_of(tmp_path, WAITING, {}, FP1, None))
    ping = next(r for r in times.responses if r.owner == "Waiting.Ping")
    assert ping.unbounded and not ping.keeps_running and not ping.until_stopped
    assert times.values()["Waiting.Ping"] == "unbounded" and "no bound: " in times.message
    assert "Waiting.Ping" in times.message.split(";")[0]


def test_a_cycle_of_zones_no_run_goes_round_is_no_bound_shown_but_inconclusive(tmp_path, capsys, monkeypatch):
    """A cycle of zones that keeps a request open need not be one a run can take (it may close through a covering
    zone): when none of those tried replays on the tick model, the answer is not "no bound", nor a bound, but
    inconclusive, with the reason (here no trace of Waiting replays: idle's and Ping's lassos alike)."""
    from runtime.zones import trace

    def refuse(z, path, goal, space):
        raise trace.ConcretizeError("step 3 cannot be taken (made so by the test)")

    monkeypatch.setattr(trace, "replay", refuse)
    code, out, _ = verify(capsys, WAITING, "--timed", "--platform", platform_file(tmp_path, FP1), "--response-times")
    table = response_table(out)
    shown = "no bound shown: a cycle of zones keeps a request open, but no run found goes round one"
    assert table["Waiting.Ping"] == shown, out
    assert f"\nWaiting.Ping: {shown} (no concrete trace: step 3 cannot be taken (made so by the test))\n" in out, out
    assert "no bound: a request can wait for ever" not in out
    assert code == 4  # idle's overrun is found, its trace or not: a reachable state is one a run reaches
    times = check_response_times(model_of(tmp_path, WAITING, {}, FP1, None))
    ping = next(r for r in times.responses if r.owner == "Waiting.Ping")
    assert ping.verdict.value == "inconclusive" and not ping.unbounded and ping.trace is None
    assert times.values()["Waiting.Ping"] == "inconclusive" and times.verdict.value == "inconclusive"
    assert times.message.startswith("not decided: Waiting.idle, Waiting.Ping (") and "stopped by" not in times.message


def test_a_starved_task_has_no_bound_on_one_core_and_a_small_one_on_two(tmp_path, capsys):
    code, out, _ = verify(capsys, STARVED, "--timed", "--platform", platform_file(tmp_path, FP1), "--response-times")
    table = response_table(out)
    assert table["Starved.busy"] == "10 ms"
    assert table["Starved.idle"].startswith("no bound"), out
    steps, lines, loop = lasso_of(out, "Starved.idle")
    assert "Starved.idle:grant" not in [label for _, label in steps]
    assert any("time passes" in line for line in after_step(lines, loop)), lines
    assert code == 4  # idle overruns as well
    two = platform_file(tmp_path, "cores: 2\npolicy: fixed-priority\nbest: wcet\n", "two.yaml")
    code, out, _ = verify(capsys, STARVED, "--timed", "--platform", two, "--response-times")
    assert response_ms(out) == {"Starved.busy": 10, "Starved.idle": 1}
    assert code == 0


def test_a_lasso_no_clock_value_can_go_round_is_passed_over_for_one_that_can(capsys):
    """Whole DALA on one core, with throws: the first 160 cycles the search finds where a GoTo request never ends
    close through covering zones, and no clock value takes one round of them, counting how far time may pass in
    the covered zones a round steps into (the covering zone's invariants and urgent priorities, as the trace's
    times count them); a later one can be taken, and runs GoTo's codels every period.  GoTo keeps working
    (nddPlan may pause for ever), shown by its lasso, rather than "no concrete trace", which is what the first 20
    that passed without those bounds gave (and, without throws, the first 20 cycles alone)."""
    dala = ROOT / "descriptions/dala"
    code, out, _ = verify(capsys, dala, "--timed", "--platform", dala / "platforms/one-core.yaml",
                          "--client", dala / "missions/corridor.yaml", "--response-times")
    assert response_table(out)["NDD.GoTo"] == KEEPS_RUNNING, out
    assert "no concrete trace" not in out
    steps, lines, loop = lasso_of(out, "NDD.GoTo", KEEPS_RUNNING)
    assert any(line.split("] ", 1)[-1].startswith("NDD.GoTo:exec_plan") for line in after_step(lines, loop)), lines
    assert any("time passes" in line for line in after_step(lines, loop)), lines
    assert code == 0


def test_an_unbounded_response_in_json(tmp_path):
    model = model_of(tmp_path, STARVED, {}, FP1, None)
    found = {r.observer: r for r in check_timing(model, (), responses=True) if isinstance(r, ResponseResult)}
    data = found["Starved.idle.response"].to_json()
    assert data["details"]["unbounded"] is True and data["details"]["value_ms"] is None
    assert data["trace"]["loop"] is not None and data["trace"]["timed"]
    ticks = [s["tick"] for s in data["trace"]["steps"]]
    assert ticks[-1] > ticks[data["trace"]["loop"]]  # the loop lets time pass


def test_zones_asked_for_on_a_model_they_do_not_take_is_refused_without_exploring(capsys):
    # Without a platform the schedulers count busy ticks as data, which clock zones do not take.
    code, out, err = verify(capsys, PAIR, "--timed", "--schedulability", "--time-search", "zones")
    assert code == 2
    assert "--time-search zones: clock zones do not take this model (" in err
    assert "exploring tick by tick" not in err and "overrun" not in out


# --------------------------------------------------------------------------- overdue tasks under EDF


def test_of_two_overdue_tasks_the_one_whose_deadline_passed_first_goes_first(tmp_path, capsys):
    """a's deadline (11 ms) passed before b's (15 ms) while slow held the one core: a goes first at 30 ms."""
    code, out, _ = verify(capsys, OVERDUE, "--timed", "--platform", platform_file(tmp_path, OVERDUE_PLATFORM),
                          "--response-times", "--traces", "terminal")
    assert response_ms(out) == {"Overdue.slow": 30, "Overdue.a": 31, "Overdue.b": 29}, out
    model = model_of(tmp_path, OVERDUE, {}, OVERDUE_PLATFORM, None)
    assert tick_maxima(model) == {"Overdue.slow.response": 30, "Overdue.a.response": 31, "Overdue.b.response": 29}
    assert code == 4  # a and b overrun their periods


def overdue_bip(tmp_path):
    """Overdue written as a .bip with its response observers, for a test to edit."""
    from genom2bip.cli import main

    path = platform_file(tmp_path, OVERDUE_PLATFORM)
    assert main([str(OVERDUE), "--timed", "--platform", str(path), "--response-times", "-o", str(tmp_path)]) == 0
    return tmp_path / "overdue" / "overdue.bip"


def test_a_priority_comparing_a_capped_clock_with_another_is_refused_by_the_zones(tmp_path, capsys):
    """A tick that caps a clock (``if (x < k) x = x + 1``) stops it at k; a zone's clock goes on, and the two
    differ in how far the capped clock is from another one: the zones refuse the model rather than answer for
    another one."""
    bip = overdue_bip(tmp_path)
    text = bip.read_text()
    ready = re.search(r"on tick from READY to READY do \{ *x = x \+ 1; *\}", text)
    assert ready, text
    capped = text.replace(ready.group(0), "on tick from READY to READY do { if (x < 10) then x = x + 1; fi }")
    bip.write_text(capped)
    capsys.readouterr()
    code, out, err = verify(capsys, bip, "--timed", "--response-times")
    note = re.search(r"clock zones do not take this model \(priority \w+: compares Overdue\.\w+\.scheduler\.x, a clock "
                     r"its tick caps, with another clock \(past the cap their difference is not the zones'\)\)", out)
    assert note, out
    assert "--response-times: response times are measured with clock zones; this model is not one clock zones " \
           "take" in err
    assert code == 2 and "\nresponse times (" not in out, out
    assert bip.read_text() == capped


@pytest.mark.parametrize("guard,refused", [("c <= cap", True), ("c > cap", True), ("c >= 5", False)])
def test_a_capped_clock_read_past_its_cap_is_refused_by_the_zones(tmp_path, capsys, guard, refused):
    """The response observer's tick stops its clock at ``cap``: a guard reading it afterwards must read the same
    of ``cap`` and of any larger value, as ``c >= 5`` does and ``c <= cap`` (always true tick by tick, false in
    a zone past the cap) does not.  Zones are asked for (``--time-search zones``): a refusal ends the command before
    it explores (without it, verify says the same and explores tick by tick)."""
    bip = overdue_bip(tmp_path)
    text = bip.read_text()
    assert text.count("    on close from WATCH to IDLE\n") == 1, text
    edited = text.replace("    on close from WATCH to IDLE\n", f"    on close from WATCH to IDLE provided ({guard})\n")
    bip.write_text(edited)
    capsys.readouterr()
    code, out, err = verify(capsys, bip, "--timed", "--time-search", "zones")
    note = re.search(r"--time-search zones: clock zones do not take this model \(atom Overdue\.\w+\.response: clock "
                     r"c, which its tick stops at (\d+) in place WATCH, is then compared \((<=|>)\) with (\d+): past "
                     r"\1 the zones' clock is not the model's\); try --time-search ticks", err)
    if refused:
        assert note, err
        assert note.group(1) == note.group(3)
        assert code == 2 and "overrun" not in out and "explored" not in out, out
    else:
        assert note is None and "clock zones do not take" not in out + err, out + err
        assert "explored with clock zones" in out, out
    assert bip.read_text() == edited
