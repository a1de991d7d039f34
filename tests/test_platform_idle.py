"""A periodic task with nothing to run for the client is not searched through its releases
(genom2bip/build/timed.py, ``idle_tasks``): its period holds and its response time is 0 ms by the build's
argument, and every other answer is that of the model that keeps its releases."""
from __future__ import annotations

import json
import re

import pytest

from genom2bip.build import timed
from genom2bip.loading import TimeSettings
from genom2bip.verify.model import build_model
from genom2bip.verify.results import ObserverResult
from genom2bip.verify.zones import IDLE, ResponseResult, check_timing, idle_owners
from platformkit import FIXTURES, platform_file, verify
from test_cli import ROOT
from test_platform_responses import model_of, tick_maxima

SPARE = FIXTURES / "Spare.gen"
RUN_ONLY = FIXTURES / "run_only.yaml"
PLATFORMS = {"one-core": "cores: 1\nbest: 1 ms\n", "two-cores": "cores: 2\nbest: 1 ms\n"}


def build(tmp_path, platform: str, mission=RUN_ONLY, idle: bool = True):
    with pytest.MonkeyPatch.context() as patch:
        if not idle:
            patch.setattr(timed, "idle_tasks", lambda level, mission: [])
        return model_of(tmp_path, SPARE, {}, PLATFORMS[platform], mission)


def idle_of(model) -> list[str]:
    return sorted(idle_owners(model))


def test_a_task_is_idle_when_the_client_sends_none_of_its_services_and_it_has_no_codel_of_its_own(tmp_path):
    assert idle_of(build(tmp_path, "one-core")) == ["Spare.spare"]
    assert idle_of(build(tmp_path, "one-core", FIXTURES / "run_then_help.yaml")) == []  # Help is sent once
    suspends = model_of(tmp_path, SPARE, {}, PLATFORMS["one-core"] + "tasks:\n  Spare.spare:\n    suspend: 2 ms\n",
                        RUN_ONLY)
    assert idle_of(suspends) == []  # each of its periods lasts its suspension
    delayed = model_of(tmp_path, SPARE, {}, PLATFORMS["one-core"] + "tasks:\n  Spare.spare:\n    delay: 3 ms\n",
                       RUN_ONLY)
    assert idle_of(delayed) == []
    dala = ROOT / "descriptions" / "dala"
    mission = tmp_path / "init.yaml"
    mission.write_text("mission: init-only\nsteps:\n  - send: RFLEX.Init\n    expect: ok\n")
    model = build_model([dala], time=TimeSettings(platform=dala / "platforms" / "one-core.yaml", client=mission,
                                                  responses=True))
    # LaserRF's acquisition, POM's fusion and NDD's motion run codels of their own every period; RFLEX's servo
    # runs Init; the control tasks have no period
    assert idle_of(model) == ["Aspect.map", "Planner.plan"]


def _answers(results) -> dict[str, tuple]:
    out = {}
    for r in results:
        if isinstance(r, ResponseResult):
            out[r.subject] = (r.verdict, r.value_ticks, r.unbounded, r.until_stopped)
        elif isinstance(r, ObserverResult):
            out[r.subject] = (r.verdict,)
    return out


@pytest.mark.parametrize("platform", sorted(PLATFORMS))
def test_the_idle_task_leaves_every_answer_as_it_was_with_fewer_states(tmp_path, platform):
    sliced, whole = build(tmp_path, platform), build(tmp_path, platform, idle=False)
    assert idle_of(sliced) == ["Spare.spare"] and idle_of(whole) == []
    got, kept = check_timing(sliced, ("overrun",), True), check_timing(whole, ("overrun",), True)
    assert _answers(got) == _answers(kept)
    assert got[0].figures.states < kept[0].figures.states
    spare = next(r for r in got if isinstance(r, ResponseResult) and r.owner == "Spare.spare")
    assert (spare.value_ticks, spare.message, spare.trace) == (0, IDLE, None)
    period = next(r for r in got if isinstance(r, ObserverResult) and "Spare.spare" in r.subject)
    assert period.message == IDLE
    # an oracle that knows nothing of zones nor of the build's argument: the tick model that keeps the releases
    ticks = tick_maxima(whole)
    assert ticks["Spare.spare.response"] == 0 and ticks["Spare.main.response"] == 3


def test_the_report_says_why_the_idle_task_has_its_answers(tmp_path, capsys):
    two = platform_file(tmp_path, PLATFORMS["two-cores"])
    code, out, _ = verify(capsys, SPARE, "--timed", "--platform", two, "--client", RUN_ONLY, "--response-times",
                          "--traces", "terminal")
    assert f"period of Spare.spare (20 ms): {IDLE} (zones, " in out, out
    assert "  Spare.spare  0 ms  (period 20 ms)" in out, out
    assert f"Spare.spare: {IDLE}\n" in out, out  # no trace: no release of it was searched
    code_json, doc, _ = verify(capsys, SPARE, "--timed", "--platform", two, "--client", RUN_ONLY,
                               "--response-times", "--json")
    assert code_json == code
    checks = {c["subject"]: c for c in json.loads(doc)["checks"]}
    period = checks["period of Spare.spare (20 ms)"]
    assert (period["verdict"], period["message"], period["traces"]) == ("holds", IDLE, [])


def test_statistical_runs_give_the_idle_task_the_same_answer(tmp_path, capsys):
    two = platform_file(tmp_path, PLATFORMS["two-cores"])
    code, out, _ = verify(capsys, SPARE, "--timed", "--platform", two, "--client", RUN_ONLY, "--smc", "--runs", "20",
                          "--time-bound", "100ms", "--seed", "1")
    assert code == 0, out
    assert f"  Spare.spare  0 ms: {IDLE}\n" in out, out
    assert "period of Spare.spare (20 ms): Pr[<= 100 ms](<> overrun) = 0.0000" in out, out
    assert re.search(r"  Spare\.main   mean [0-9.]+ ms, p99 3 ms, max 3 ms", out), out
