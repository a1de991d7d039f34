"""bench/quadcopter_bench.py reads the client of the quadcopter's UPPAAL model as a mission: checked on client
processes written here in the same shape (the artefact itself stays out of the repository)."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
import quadcopter_bench  # noqa: E402

#: A client of the artefact's shape: a wait from the start, requests each once the component takes them, a held
#: wait from the last reset, a bounded loop of one request, then the rest.
CLIENT = """
process client(bool &s_alpha, urgent broadcast chan &recv_alpha, int[none_alpha,nserv_alpha-1] &req_alpha,
urgent broadcast chan &recv_urg_beta, int[none_beta,nserv_beta-1] &req_beta) {
    clock x;
const int t := 250;
const int max:= 3;
int count:= 0;
state
    ini { x<=700 }, a, b { x<=t }, c, loop { ; 10000 }, done;
init
    ini;
trans
    ini -> a { guard x==700; },
    a -> b { guard s_alpha; sync recv_alpha!; assign req_alpha:= go_alpha, x:=0; },
    b -> c { guard x==t; },
    c -> loop { guard s_alpha; sync recv_urg_beta!; assign req_beta:= set_mode_beta, x:=0; },
    loop -> loop { guard s_beta && count < max; sync recv_urg_beta!; assign req_beta:= waypoint_beta, count:= 1; },
    loop -> done { guard s_beta; sync recv_urg_beta!; assign req_beta:= land_beta; };
}
"""


def test_the_client_is_read_as_requests_waits_and_a_bounded_repeat():
    client = quadcopter_bench.read_client(CLIENT)
    assert [(s.request, s.after_us) for s in client.steps] == [
        ("alpha.go", 7000), ("beta.set_mode", 2500), ("beta.land", 0)]  # units of 10 us
    assert client.repeat.request == "beta.waypoint" and client.most == 3 and client.at == 2
    assert [s.request for s in client.mission(2)] == ["alpha.go", "beta.set_mode", "beta.waypoint", "beta.waypoint",
                                                      "beta.land"]
    assert [s.request for s in client.mission(0)] == ["alpha.go", "beta.set_mode", "beta.land"]


def test_the_mission_sends_each_request_once_the_previous_is_queued_after_its_wait():
    steps = quadcopter_bench.read_client(CLIENT).mission(1)
    mission = yaml.safe_load(quadcopter_bench.mission_text(steps, {"alpha.go": {"speed": 0}}))
    assert mission["steps"] == [
        {"send": "alpha.go", "after": "7 ms", "with": {"speed": 0}, "until": "queued"},
        {"send": "beta.set_mode", "after": "2.5 ms", "until": "queued"},
        {"send": "beta.waypoint", "until": "queued"},
        {"send": "beta.land", "until": "queued"}]


@pytest.mark.parametrize("text,message", [
    ("process other() {\n}\n", "no process 'client' in the .xta"),
    (CLIENT.replace("init\n    ini;", ""), "the client process has no 'init'"),
    (CLIENT.replace("    loop -> done", "    loop -> c { guard x==1; },\n    loop -> done"),
     "state loop: 2 ways on and 1 loops (one and at most one expected)"),
    (CLIENT.replace("sync recv_urg_beta!; assign req_beta:= waypoint_beta", "assign x:=0"),
     "state loop: a loop that is not a bounded request"),
    (CLIENT.replace("assign req_alpha:= go_alpha, x:=0;", "assign req_alpha:= go_alpha;"),
     "state b: waits for x == t, but the time since x was reset is not known there (a request was sent since, "
     "without resetting x)"),
    ("process client() {\n    clock x;\nstate ini, a;\ninit ini;\ntrans\n    ini -> a { guard x==5; };\n}\n",
     "the client sends no request"),
])
def test_a_client_that_is_not_such_a_chain_is_refused_with_the_reason(text, message):
    with pytest.raises(quadcopter_bench.ClientError) as err:
        quadcopter_bench.read_client(text)
    assert str(err.value) == message


def test_a_budget_in_minutes_is_read_as_timeout_writes_it():
    assert quadcopter_bench.budget_seconds("10m") == 600
    assert quadcopter_bench.budget_seconds("30 s") == 30
    assert quadcopter_bench.budget_seconds("ten minutes") is None


def test_the_exact_platform_takes_each_codel_at_its_worst_case_and_keeps_the_rest(tmp_path):
    platform = tmp_path / "p.yaml"
    platform.write_text("cores: 8\npolicy: edf\nexecution:\n  alpha.main.step: [1 ms, 3 ms]\n"
                        "tasks:\n  alpha.main:\n    delay: 2 ms\n")
    exact = yaml.safe_load(quadcopter_bench.exact_platform(platform, tmp_path).read_text())
    assert exact == {"cores": 8, "policy": "edf", "execution": {"alpha.main.step": ["3 ms", "3 ms"]},
                     "tasks": {"alpha.main": {"delay": "2 ms"}}, "best": "wcet"}
    assert platform.read_text().startswith("cores: 8\n")  # the given file is left as it was


def _response(verdict: str, value_ticks=None, message: str = ""):
    from genom2bip.verify.results import Verdict
    from genom2bip.verify.zones import ResponseResult

    return ResponseResult("response time of a.s", Verdict(verdict), value_ticks=value_ticks, message=message,
                          cap_ticks=800, tick_us=10, owner="a.s", kind="service")


def test_a_stopped_search_shows_a_lower_bound_past_the_cap_or_what_is_not_requested_yet():
    from genom2bip.verify.zones import ABOVE_CAP

    assert quadcopter_bench._value(_response("inconclusive", value_ticks=5)) == ">= 0.05 ms"
    assert quadcopter_bench._value(_response("inconclusive", message=ABOVE_CAP)) == "> 8 ms"
    assert quadcopter_bench._value(_response("inconclusive", message="never requested")) == "not requested yet"
    assert quadcopter_bench._value(_response("inconclusive")) == "not reached yet"
    assert quadcopter_bench._value(_response("holds", value_ticks=5)) == "0.05 ms"
