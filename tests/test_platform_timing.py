"""Timing verdicts on a platform: a non-Zeno environment, cores and policies, blocking, anomalies, a client mission.

Every fixture is small (tests/fixtures/platform/*.gen, each says what it
shows) and every expected figure is worked out by hand in the fixture's
comment, not read back from the tool.
"""
from __future__ import annotations

import re

import pytest

from platformkit import (
    FIXTURES, platform_file, printed_trace, response_ms, response_table, verdicts, verify,
)

ZENO = FIXTURES / "Zeno.gen"
PAIR = FIXTURES / "Pair.gen"
SHARED = FIXTURES / "Shared.gen"
ANOMALY = FIXTURES / "Anomaly.gen"
CATCHUP = FIXTURES / "Catchup.gen"

ONE_CORE = "cores: 1\npolicy: {policy}\nbest: wcet\n"


# --------------------------------------------------------------------------- the environment is not Zeno


@pytest.mark.parametrize("platform", [None, "cores: 1\n"], ids=["core-per-task", "one-core"])
def test_two_6ms_activities_keep_a_20ms_period_under_the_default_environment(tmp_path, capsys, platform):
    # Each service is requested at most once per period: A and B take 12 ms of the 20 ms period.
    args = [ZENO, "--timed", "--schedulability"]
    if platform:
        args += ["--platform", platform_file(tmp_path, platform)]
    code, out, _ = verify(capsys, *args)
    assert verdicts(out) == {"Zeno.main": "none"}, out
    assert code == 0


def test_two_6ms_activities_overrun_a_10ms_period_with_a_trace(capsys):
    code, out, _ = verify(capsys, ZENO, "-DPERIOD=10", "--timed", "--schedulability")
    assert code == 4
    assert verdicts(out) == {"Zeno.main": "overrun"}
    steps = printed_trace(out, "period of Zeno.main (10 ms): overrun reachable")
    labels = [label for _, label in steps]
    # The trace opens a period, runs both codels in it, and the period is still open 12 ms later.
    opening = max(k for k, label in enumerate(labels) if label == "Zeno.main:period")
    assert {"Zeno.A:exec_start", "Zeno.B:exec_start"} <= set(labels[opening:])
    assert "Zeno.main:sleep" not in labels[opening:]
    last = out.rstrip().splitlines()[-1]
    assert "time passes" in last and float(last.split(".. ")[1].split(" ms")[0]) - steps[opening][0] > 10


# --------------------------------------------------------------------------- cores and policies


@pytest.mark.parametrize("policy", ["edf", "fixed-priority"])
def test_two_tasks_overrun_on_one_core_and_not_on_two(tmp_path, capsys, policy):
    one = platform_file(tmp_path, ONE_CORE.format(policy=policy), "one.yaml")
    two = platform_file(tmp_path, f"cores: 2\npolicy: {policy}\nbest: wcet\n", "two.yaml")
    code, out, _ = verify(capsys, PAIR, "--timed", "--schedulability", "--platform", one)
    assert code == 4
    found = verdicts(out)
    if policy == "fixed-priority":  # fast (priority 0) is granted first at every release: slow is late
        assert found == {"Pair.fast": "none", "Pair.slow": "overrun"}, out
    else:  # equal deadlines: either may go second
        assert found == {"Pair.fast": "overrun", "Pair.slow": "overrun"}, out
    code, out, _ = verify(capsys, PAIR, "--timed", "--schedulability", "--platform", two)
    assert code == 0
    assert verdicts(out) == {"Pair.fast": "none", "Pair.slow": "none"}, out


def test_released_one_by_one_a_lower_priority_may_take_the_core_first(tmp_path, capsys):
    # Both tasks are released at 0, 10, 20...  Together (the default), fixed priority grants fast first at every
    # release and only slow overruns.  One by one, slow's release may be seen first and take the free core while
    # fast is not queued yet: fast can overrun too, by a trace where slow is granted before fast opens.
    one = platform_file(tmp_path, "cores: 1\npolicy: fixed-priority\nbest: wcet\nreleases: one-by-one\n")
    code, out, _ = verify(capsys, PAIR, "--timed", "--schedulability", "--platform", one)
    assert code == 4 and verdicts(out) == {"Pair.fast": "overrun", "Pair.slow": "overrun"}, out
    assert "platform: 1 core, fixed priority (non-preemptive at codel boundaries), releases at one instant one " \
           "by one" in out.splitlines()
    labels = [label for _, label in printed_trace(out, "period of Pair.fast (10 ms): overrun reachable")]
    assert labels.index("Pair.slow:grant") < labels.index("Pair.fast:period") < labels.index("Pair.fast:grant")


@pytest.mark.parametrize("cores,expected", [(1, {"Pair.fast": 12, "Pair.slow": 12}),
                                            (2, {"Pair.fast": 6, "Pair.slow": 6})])
def test_response_times_of_two_tasks_under_edf(tmp_path, capsys, cores, expected):
    path = platform_file(tmp_path, f"cores: {cores}\npolicy: edf\nbest: wcet\n")
    _, out, _ = verify(capsys, PAIR, "--timed", "--platform", path, "--response-times")
    assert response_ms(out) == expected


SWAPPED = ("cores: 1\npolicy: {policy}\nbest: wcet\n"
           "tasks:\n  Pair.slow:\n    priority: 0\n  Pair.fast:\n    priority: 1\n")


def test_edf_goes_by_deadlines_whatever_the_priorities(tmp_path, capsys):
    # slow's period is 20 ms: at every common release fast's deadline is earlier and EDF grants it first
    # (0..6, slow 6..12; fast's next release at 10 waits for slow until 12: 8 ms; at 20 slow waits for fast: 12 ms).
    path = platform_file(tmp_path, SWAPPED.format(policy="edf"))
    code, out, _ = verify(capsys, PAIR, "-DSLOW_PERIOD=20", "--timed", "--schedulability", "--platform", path,
                          "--response-times")
    assert response_ms(out) == {"Pair.fast": 8, "Pair.slow": 12}
    assert code == 0


def test_the_platform_file_priorities_override_the_description(tmp_path, capsys):
    # slow made priority 0: it is granted first at 0 and fast ends 12 ms after its release.
    path = platform_file(tmp_path, SWAPPED.format(policy="fixed-priority"))
    code, out, _ = verify(capsys, PAIR, "-DSLOW_PERIOD=20", "--timed", "--schedulability", "--platform", path,
                          "--response-times")
    assert verdicts(out) == {"Pair.fast": "overrun", "Pair.slow": "none"}
    assert response_ms(out) == {"Pair.fast": 12, "Pair.slow": 6}
    assert code == 4


def test_the_platform_is_said_in_one_line(tmp_path, capsys):
    path = platform_file(tmp_path, "cores: 2\npolicy: fixed-priority\n")
    _, out, _ = verify(capsys, PAIR, "--timed", "--schedulability", "--platform", path)
    assert "platform: 2 cores, fixed priority (non-preemptive at codel boundaries)" in out.splitlines()


# --------------------------------------------------------------------------- blocking on shared data


@pytest.mark.parametrize("sharing", [[], ["-DPORTS"]], ids=["ids-member", "port"])
def test_a_shared_lock_makes_a_task_wait_for_the_other_core(tmp_path, capsys, sharing):
    two = platform_file(tmp_path, "cores: 2\npolicy: edf\nbest: wcet\n")
    _, out, _ = verify(capsys, SHARED, *sharing, "--timed", "--platform", two, "--response-times")
    assert response_ms(out)["Shared.quick"] == 9  # 7 ms of long's codel, then its own 2 ms
    _, out, _ = verify(capsys, SHARED, "-DAPART", "--timed", "--platform", two, "--response-times")
    assert response_ms(out) == {"Shared.quick": 2, "Shared.long": 7}


@pytest.mark.parametrize("sharing", [[], ["-DPORTS"]], ids=["ids-member", "port"])
def test_blocking_makes_an_overrun_reachable_that_is_not_without_sharing(tmp_path, capsys, sharing):
    two = platform_file(tmp_path, "cores: 2\npolicy: edf\nbest: wcet\n")
    code, out, _ = verify(capsys, SHARED, "-DSLOW", *sharing, "--timed", "--schedulability", "--platform", two)
    assert code == 4 and verdicts(out)["Shared.quick"] == "overrun", out
    steps = printed_trace(out, "period of Shared.quick (10 ms): overrun reachable")
    labels = [label for _, label in steps]
    # quick is granted its core but its codel starts only once long's codel has ended (the lock).
    assert labels.index("Shared.long:exec_start") < labels.index("Shared.long:end_start") \
        < labels.index("Shared.quick:exec_start")
    code, out, _ = verify(capsys, SHARED, "-DSLOW", "-DAPART", "--timed", "--schedulability", "--platform", two)
    assert code == 0 and verdicts(out) == {"Shared.quick": "none", "Shared.long": "none"}, out


def test_readers_of_one_member_do_not_exclude_each_other(tmp_path, capsys):
    # Both codels read x (GenoM3 lets readers share): no lock, so no waiting.
    gen = tmp_path / "Readers.gen"
    gen.write_text(SHARED.read_text().replace("quick_step(ids out x)", "quick_step(ids in x)"))
    two = platform_file(tmp_path, "cores: 2\npolicy: edf\nbest: wcet\n")
    _, out, _ = verify(capsys, gen, "--timed", "--platform", two, "--response-times")
    assert response_ms(out) == {"Shared.quick": 2, "Shared.long": 7}


# --------------------------------------------------------------------------- a scheduling anomaly

EXACT = "cores: 1\npolicy: fixed-priority\nbest: wcet\n"
EARLY = EXACT + "execution:\n  Anomaly.mid.mid_step: [1 ms, 4 ms]\n"


def test_a_shorter_best_case_gives_a_longer_response_time(tmp_path, capsys):
    # mid taking exactly 4 ms: high (released at 3 ms) waits 1 ms for mid, then runs 2 ms.
    _, out, _ = verify(capsys, ANOMALY, "--timed", "--platform", platform_file(tmp_path, EXACT, "exact.yaml"),
                       "--response-times")
    exact = response_ms(out)
    assert exact["Anomaly.high"] == 3, out
    # mid ending early lets low take the core for 10 ms before high's release: high ends much later.
    _, out, _ = verify(capsys, ANOMALY, "--timed", "--platform", platform_file(tmp_path, EARLY, "early.yaml"),
                       "--response-times")
    early = response_ms(out)
    assert early["Anomaly.high"] > exact["Anomaly.high"]
    assert early["Anomaly.high"] >= 10  # low's whole codel (10 ms) lies between high's release and its start
    steps = [label for _, label in printed_trace(out, "Anomaly.high: ")]
    assert steps.index("Anomaly.mid:end_start") < steps.index("Anomaly.low:exec_start") \
        < steps.index("Anomaly.high:exec_start")
    assert early["Anomaly.low"] == exact["Anomaly.low"] == 16  # mid 4, high 2, low 10 in the worst case


def test_a_delayed_first_release_is_there_to_choose_from_at_its_instant(tmp_path, capsys):
    # mid takes exactly 3 ms and high is released at 3 ms: at that instant the core goes to high (priority 0),
    # as it does at every later release (23 ms, 43 ms...), not to low (priority 2), which would keep it 10 ms.
    path = platform_file(tmp_path, EXACT + "execution:\n  Anomaly.mid.mid_step: 3 ms\n")
    _, out, _ = verify(capsys, ANOMALY, "--timed", "--platform", path, "--response-times")
    assert response_ms(out)["Anomaly.high"] == 2, out


def test_the_platform_file_delay_overrides_the_description(tmp_path, capsys):
    # high released at 5 ms instead of 3: low was granted at 4 ms when mid ended, and holds the core to 14 ms.
    path = platform_file(tmp_path, EXACT + "tasks:\n  Anomaly.high:\n    delay: 5 ms\n")
    _, out, _ = verify(capsys, ANOMALY, "--timed", "--platform", path, "--response-times")
    assert response_ms(out)["Anomaly.high"] == 11, out
    steps = printed_trace(out, "Anomaly.high: ")
    assert [ms for ms, label in steps if label == "Anomaly.high:period"][0] == 5


def test_the_anomaly_is_seen_by_a_latency_observer_too(tmp_path, capsys):
    observers = tmp_path / "observers.yaml"
    observers.write_text("observers:\n  - name: high-quickly\n    from: Anomaly.high:period\n"
                         "    to: Anomaly.high:sleep\n    within: 5 ms\n")
    for text, code, verdict in ((EXACT, 0, "no violation reachable"), (EARLY, 4, "violation reachable")):
        path = platform_file(tmp_path, text)
        got, out, _ = verify(capsys, ANOMALY, "--timed", "--platform", path, "--observers", observers)
        assert got == code and f"latency high_quickly (within 5 ms): {verdict}" in out, out


def test_a_late_period_opens_at_the_end_of_the_last_and_the_next_on_the_grid(tmp_path, capsys):
    # Catchup.main (10 ms, first release at 1 ms): Run's start codel (13 ms) overruns the first period; the
    # release at 11 ms is kept and opens the second period at 14 ms (second, 2 ms); the third opens at 21 ms,
    # on the grid, not 10 ms after the late opening: Run's final report comes 23 ms after its request.
    platform = platform_file(tmp_path, "cores: 1\nbest: wcet\ntasks:\n  Catchup.main:\n    delay: 1 ms\n")
    mission = platform_file(tmp_path, "mission: run-once\nsteps:\n  - send: Catchup.Run\n    until: queued\n",
                            "run.yaml")
    code, out, err = verify(capsys, CATCHUP, "--timed", "--platform", platform, "--client", mission,
                            "--response-times")
    assert code == 4 and verdicts(out) == {"Catchup.main": "overrun"}, out + err
    assert response_ms(out) == {"Catchup.main": 13, "Catchup.Run": 23}, out
    steps = printed_trace(out, "Catchup.Run: ")
    assert [ms for ms, label in steps if label == "Catchup.main:period"] == [1, 14, 21]
    assert [ms for ms, label in steps if label == "Catchup.main:late"] == [11]


# --------------------------------------------------------------------------- a client mission


def test_a_mission_that_waits_between_requests_keeps_the_period(tmp_path, capsys):
    # The default environment overruns a 10 ms period (A and B in one period); the mission sends B 10 ms
    # after A has finished, so they never share a period.
    one = platform_file(tmp_path, "cores: 1\n")
    code, out, _ = verify(capsys, ZENO, "-DPERIOD=10", "--timed", "--schedulability", "--platform", one)
    assert code == 4 and verdicts(out) == {"Zeno.main": "overrun"}
    code, out, err = verify(capsys, ZENO, "-DPERIOD=10", "--timed", "--schedulability", "--platform", one,
                            "--client", FIXTURES / "a_then_b.yaml")
    assert verdicts(out) == {"Zeno.main": "none"}, out + err
    assert code == 0
    assert "explored with clock zones" in out and "note:" not in out  # a wait ('after') is a clock zones take


def test_a_mission_keeps_its_order(tmp_path, capsys):
    one = platform_file(tmp_path, "cores: 1\n")
    _, out, err = verify(capsys, ZENO, "-DPERIOD=10", "--timed", "--platform", one, "--client",
                         FIXTURES / "a_then_b.yaml", "--response-times")
    assert "Zeno.B" in response_table(out), out + err
    steps = printed_trace(out, "Zeno.B: ")
    times = {label: ms for ms, label in reversed(steps)}  # the first time of each label
    assert times["Zeno.A:trigger"] <= times["Zeno.A:finish"]
    assert times["Zeno.B:trigger"] - times["Zeno.A:finish"] >= 10  # 'after: 10 ms'


def test_execution_times_of_service_codels_override_their_wcet(tmp_path, capsys):
    # A then B, never in one period: the task's cycle is one codel long, A's or B's.
    mission = FIXTURES / "a_then_b.yaml"
    exact = platform_file(tmp_path, "cores: 1\nbest: wcet\n", "exact.yaml")
    _, out, _ = verify(capsys, ZENO, "-DPERIOD=10", "--timed", "--platform", exact, "--client", mission,
                       "--response-times")
    assert response_ms(out)["Zeno.main"] == 6, out
    faster = platform_file(tmp_path, "cores: 1\nbest: wcet\nexecution:\n  Zeno.A.a_run: 2 ms\n"
                                     "  Zeno.B.b_run: [1 ms, 3 ms]\n", "faster.yaml")
    _, out, _ = verify(capsys, ZENO, "-DPERIOD=10", "--timed", "--platform", faster, "--client", mission,
                       "--response-times")
    assert response_ms(out)["Zeno.main"] == 3, out
    assert "one tick is 1 ms" in out  # the tick divides the platform's durations too


def test_until_started_lets_the_next_request_share_the_period(tmp_path, capsys):
    one = platform_file(tmp_path, "cores: 1\n")
    code, out, _ = verify(capsys, ZENO, "-DPERIOD=10", "--timed", "--schedulability", "--platform", one,
                          "--client", FIXTURES / "b_started_then_a.yaml")
    assert code == 4 and verdicts(out) == {"Zeno.main": "overrun"}
    labels = [label for _, label in printed_trace(out, "period of Zeno.main (10 ms): overrun reachable")]
    assert labels.index("Zeno.B:trigger") < labels.index("Zeno.B:start") < labels.index("Zeno.A:trigger")


B_STARTS = ("observers:\n  - name: b-runs\n    from: Zeno.B:start\n    to: Zeno.B:finish\n"
            "    within: 2 ms\n")  # B's codel takes 6 ms: violated as soon as B ever starts


def test_a_service_the_mission_never_sends_is_never_started(tmp_path, capsys):
    one = platform_file(tmp_path, "cores: 1\nbest: wcet\n")
    observers = platform_file(tmp_path, B_STARTS, "observers.yaml")
    code, out, _ = verify(capsys, ZENO, "--timed", "--platform", one, "--observers", observers)
    assert code == 4 and "latency b_runs (within 2 ms): violation reachable" in out  # the default sends B
    code, out, _ = verify(capsys, ZENO, "--timed", "--platform", one, "--observers", observers,
                          "--client", FIXTURES / "only_a.yaml")
    assert "latency b_runs (within 2 ms): no violation reachable" in out, out
    assert code == 0


def test_the_response_table_lists_an_unsent_service_as_never_requested(tmp_path, capsys):
    one = platform_file(tmp_path, "cores: 1\n")
    _, out, _ = verify(capsys, ZENO, "--timed", "--platform", one, "--client", FIXTURES / "only_a.yaml",
                       "--response-times")
    table = response_table(out)
    assert "Zeno.A" in table
    assert table.get("Zeno.B") == "never requested", out
    assert not re.search(r"^Zeno\.B: ", out, re.M)  # no trace for it
