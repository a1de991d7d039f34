"""Statistical model checking (``verify --timed --smc``): estimates whose intervals contain probabilities computed
by hand, zero where exhaustive search proves no overrun, the same estimate whatever runs the batches, traces that
replay on the engine, and bad input said with its place and exit status.

Slack (tests/fixtures/smc/Slack.gen): a 10 ms period running a 4 ms codel then one drawn uniformly in
[0, 10] ms.  The first period overruns when the second codel takes more than its 6 ms of slack: 0.4; the
overrun is seen at the tick after the period's end (12 ms at 2 ms ticks).  Within 24 ms a second period can
overrun too: 0.4 + 0.6 * 0.4 = 0.64.  Branch: the first codel goes on to a 10 ms codel once for three 2 ms ones
(branch.proba): 0.25; uniformly, 0.5.
"""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest

from genom2bip.cli import main
from genom2bip.verify import TimeSettings, build_model
from genom2bip.verify.smc import SmcSettings, estimate, replay, sim_config, simulator
from tests.nativekit import needs_cc

ROOT = Path(__file__).resolve().parents[1]
SMC = ROOT / "tests" / "fixtures" / "smc"
SLACK, BRANCH = SMC / "Slack.gen", SMC / "Branch.gen"


def verify(capsys, *argv) -> tuple[int, str, str]:
    code = main(["verify", *[str(a) for a in argv]])
    out, err = capsys.readouterr()
    return code, out, err


def estimates(out: str) -> dict[str, tuple[float, float, float, int, int]]:
    """``{observer: (estimate, low, high, hits, runs)}`` of every estimate printed."""
    found = {}
    for m in re.finditer(r"^(period of \S+) \([\d.]+ ms\): Pr\[<= [\d.]+ ms\]\(<> \w+\) = ([\d.]+)  "
                         r"\[([\d.]+), ([\d.]+)\]  \(([\d,]+) of ([\d,]+) runs reached it\)$", out, re.M):
        found[m.group(1)] = (float(m.group(2)), float(m.group(3)), float(m.group(4)),
                             int(m.group(5).replace(",", "")), int(m.group(6).replace(",", "")))
    return found


def slack(platform: str = "slack.yaml"):
    return build_model([SLACK], time=TimeSettings(platform=str(SMC / platform)))


# --------------------------------------------------------------------------- probabilities computed by hand


@pytest.mark.parametrize("bound, exact", [("15 ms", 0.4), ("25 ms", 0.64)])
def test_the_interval_contains_the_overrun_probability_computed_by_hand(capsys, bound, exact):
    code, out, err = verify(capsys, SLACK, "--timed", "--platform", SMC / "slack.yaml", "--smc", "--time-bound",
                            bound, "--epsilon", "0.05", "--delta", "0.01")
    assert code == 4, err  # runs reached the overrun: a violation, with its trace
    value, low, high, hits, runs = estimates(out)["period of Slack.cycle"]
    assert runs == 1060  # ln(2 / 0.01) / (2 * 0.05^2), rounded up
    assert low <= exact <= high and high - low == pytest.approx(0.1, abs=1e-3)
    assert value == pytest.approx(hits / runs, abs=1e-4)
    assert "Chernoff-Hoeffding, epsilon 0.05, delta 0.01" in out


def test_weights_of_a_proba_file_change_the_probability_as_computed_by_hand(capsys):
    common = [BRANCH, "--timed", "--platform", SMC / "branch.yaml", "--smc", "--time-bound", "15 ms",
              "--epsilon", "0.04", "--delta", "0.01"]
    _, weighted, err = verify(capsys, *common, "--proba", SMC / "branch.proba")
    value, low, high, _, _ = estimates(weighted)["period of branch.cycle"]
    assert low <= 0.25 <= high and not low <= 0.5 <= high, weighted + err
    _, uniform, _ = verify(capsys, *common)
    value, low, high, _, _ = estimates(uniform)["period of branch.cycle"]
    assert low <= 0.5 <= high and not low <= 0.25 <= high


def test_no_overrun_proved_by_exhaustive_search_is_estimated_zero_with_its_bound(capsys):
    code, out, _ = verify(capsys, SLACK, "--timed", "--platform", SMC / "safe.yaml", "--schedulability")
    assert code == 0 and "period of Slack.cycle (10 ms): no overrun reachable" in out
    code, out, _ = verify(capsys, SLACK, "--timed", "--platform", SMC / "safe.yaml", "--smc", "--time-bound",
                          "60 ms", "--epsilon", "0.05")
    assert code == 0, out
    assert estimates(out)["period of Slack.cycle"] == (0.0, 0.0, 0.05, 0, 738)
    assert "first reached" not in out


def test_wald_decides_on_each_side_of_the_threshold(capsys):
    common = [SLACK, "--timed", "--platform", SMC / "slack.yaml", "--smc", "--time-bound", "15 ms",
              "--epsilon", "0.05", "--delta", "0.01"]
    code, out, _ = verify(capsys, *common, "--threshold", "0.3")
    assert re.search(r"Pr\[<= 14 ms\]\(<> overrun\) >= 0.3 accepted \(Wald SPRT, \d+ runs", out), out
    code, out, _ = verify(capsys, *common, "--threshold", "0.5")
    assert re.search(r"Pr\[<= 14 ms\]\(<> overrun\) < 0.5 accepted \(Wald SPRT, \d+ runs", out), out


def test_response_times_seen_never_pass_the_exhaustive_maximum(capsys):
    code, out, _ = verify(capsys, SLACK, "--timed", "--platform", SMC / "safe.yaml", "--response-times")
    exhaustive = float(re.search(r"^  Slack.cycle\s+([\d.]+) ms", out, re.M).group(1))
    assert exhaustive == 10  # 4 ms, then at most 6
    model = slack("safe.yaml")
    report = estimate(model, SmcSettings(horizon_us=50_000, runs=300))
    cycle = next(d for d in report.responses if d.owner == "Slack.cycle")
    assert cycle.samples == 300 * 5  # five periods end in each run
    assert cycle.max_ms == exhaustive  # reached: the compute codel's last tick has probability 0.2
    assert 4 < cycle.mean_ms < 10 and cycle.percentile_ms() <= cycle.max_ms
    assert set(cycle.counts) == {3, 4, 5}  # 6, 8 or 10 ms in 2 ms ticks


# --------------------------------------------------------------------------- reproducible whatever computes the runs


def test_batches_of_any_size_give_the_same_estimate():
    model = slack()
    base = SmcSettings(horizon_us=24_000, runs=400, seed=7)
    one = estimate(model, base)
    other = estimate(model, SmcSettings(horizon_us=24_000, runs=400, seed=7, batch=13))
    assert [r.hits for r in one.results] == [r.hits for r in other.results]
    assert [d.counts for d in one.responses] == [d.counts for d in other.responses]
    reseeded = estimate(model, SmcSettings(horizon_us=24_000, runs=400, seed=8))
    assert [d.counts for d in reseeded.responses] != [d.counts for d in one.responses]  # the seed matters


@needs_cc
def test_the_python_step_and_the_compiled_step_make_the_same_runs():
    from dataclasses import replace

    from runtime.smc import Simulator

    model = slack()
    config = replace(sim_config(model, SmcSettings(horizon_us=24_000)), native=False)  # the loop in Python
    compiled, why = simulator(model, config)
    assert not why
    python = Simulator(compiled.space, None, config)
    for index in range(40):
        a, b = compiled.run(3, index, record=True), python.run(3, index, record=True)
        assert (a.reached, a.responses, a.choices) == (b.reached, b.responses, b.choices)


@needs_cc
def test_one_and_two_dask_workers_give_the_estimate_of_this_process(capsys):
    pytest.importorskip("distributed")
    common = [SLACK, "--timed", "--platform", SMC / "slack.yaml", "--smc", "--time-bound", "25 ms",
              "--runs", "600", "--batch", "50", "--seed", "11"]
    _, here, _ = verify(capsys, *common)
    _, one, _ = verify(capsys, *common, "--smc-workers", "1")
    _, two, _ = verify(capsys, *common, "--smc-workers", "2")
    assert "local cluster" in one and "2 workers" in two
    assert estimates(here) == estimates(one) == estimates(two)
    responses = [out.split("response times seen", 1)[1] for out in (here, one, two)]
    assert responses[0] == responses[1] == responses[2]


# --------------------------------------------------------------------------- traces


def test_the_first_run_reaching_the_overrun_is_written_and_replays_on_the_engine(capsys, tmp_path):
    path = tmp_path / "runs.json"
    code, out, _ = verify(capsys, SLACK, "--timed", "--platform", SMC / "slack.yaml", "--smc", "--time-bound",
                          "15 ms", "--runs", "50", "--smc-trace", path)
    assert code == 4
    written = json.loads(path.read_text())
    [trace] = written["traces"]
    assert trace["observer"] == "Slack.cycle.overrun" and f"first reached by run {trace['run']} at 12 ms" in out
    steps = trace["trace"]["steps"]
    assert steps[-1]["time_ms"] == 12 and steps[-1]["label"] == "tick"
    assert any(s["label"] == "Slack.cycle:exec_work" and s["outcomes"] == ["compute -> pause::start"] for s in steps)
    model = slack()
    replay(model, trace["trace"], "Slack.cycle.overrun")  # ends with the observer in ERROR
    with pytest.raises(ValueError, match="is not in ERROR at its end"):
        replay(model, {"steps": steps[:-1]}, "Slack.cycle.overrun")
    wrong = [dict(s) for s in steps]
    k = next(i for i, s in enumerate(wrong) if s["label"] == "Slack.cycle:exec_work")
    wrong[k]["outcomes"] = ["compute -> ether"]
    with pytest.raises(ValueError, match=rf"step {k + 1} \(Slack.cycle:exec_work\) does not replay"):
        replay(model, {"steps": wrong})


def test_a_histogram_picture_is_written(capsys, tmp_path):
    path = tmp_path / "responses.png"
    code, out, _ = verify(capsys, SLACK, "--timed", "--platform", SMC / "safe.yaml", "--smc", "--time-bound",
                          "30 ms", "--runs", "40", "--histogram", path)
    assert code == 0 and f"wrote {path}" in out
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert re.search(r"^  Slack.cycle  mean [\d.]+ ms, p99 [\d.]+ ms, max [\d.]+ ms  \(120\)$", out, re.M)


# --------------------------------------------------------------------------- bad input


def bad_proba(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "bad.proba"
    path.write_text(text)
    return path


@pytest.mark.parametrize("text, where, message", [
    ("cycle::branch_start::branch_short 3\ncycle::branch_start 2\n", "2:1",
     "'cycle::branch_start' is not OWNER::STATE::NEXT"),
    ("cycle::branch_start::branch_short three\n", "1:35", "'three' is not a number of occurrences"),
    ("cycle::branch_start::branch_short -1\n", "1:35", "'-1' is not a number of occurrences"),
    ("cycle::branch_start::branch_short\n", "1:34", "expected the number of occurrences after the transition"),
    ("\n# a comment\ncylce::branch_start::branch_short 3\n", "3:1",
     "no task or service is named 'cylce'"),
    ("cycle::branch_begin::branch_short 3\n", "1:8", "'cycle' has no state 'branch_begin'"),
    ("cycle::branch_start::branch_shrt 3\n", "1:22",
     "branch.cycle: state start (codel choose) does not yield 'shrt'"),
    ("cycle::branch_start::branch_short 3 4\n", "1:37", "unexpected '4' after the number of occurrences"),
    ("cycle::branch_start::branch_short 3\n  cycle::branch_start::branch_short 1\n", "2:3",
     "'cycle::branch_start::branch_short' given twice (first on line 1)"),
])
def test_a_bad_proba_line_is_named_at_its_line_and_column(capsys, tmp_path, text, where, message):
    path = bad_proba(tmp_path, text)
    trace = tmp_path / "trace.json"
    code, out, err = verify(capsys, BRANCH, "--timed", "--platform", SMC / "branch.yaml", "--smc", "--runs", "10",
                            "--proba", path, "--smc-trace", trace)
    assert code == 1
    assert f"{path}:{where}: error: {message}" in err
    assert "^" in err and "Traceback" not in err
    assert "Pr[" not in out and not trace.exists()  # nothing estimated, nothing written


def test_a_missing_or_unreadable_proba_file_is_said(capsys, tmp_path):
    code, out, err = verify(capsys, BRANCH, "--timed", "--platform", SMC / "branch.yaml", "--smc", "--runs", "10",
                            "--proba", tmp_path / "none.proba")
    assert code == 1 and "none.proba: no such .proba file" in err and "Pr[" not in out
    code, out, err = verify(capsys, BRANCH, "--timed", "--platform", SMC / "branch.yaml", "--smc", "--runs", "10",
                            "--proba", tmp_path)
    assert code == 1 and f"{tmp_path}: not a file (a .proba file was expected)" in err and "Pr[" not in out
    binary = tmp_path / "b.proba"
    binary.write_bytes(b"cycle::branch_start::branch_short \xff3\n")
    code, out, err = verify(capsys, BRANCH, "--timed", "--platform", SMC / "branch.yaml", "--smc", "--runs", "10",
                            "--proba", binary)
    assert code == 1 and f"{binary}: error: cannot read the .proba file: 'utf-8' codec" in err and "Pr[" not in out


@pytest.mark.parametrize("option, value, message", [
    ("--epsilon", "0", "--epsilon is 0; expected a number between 0 and 1"),
    ("--epsilon", "1.5", "--epsilon is 1.5; expected a number between 0 and 1"),
    ("--epsilon", "nan", "--epsilon is nan; expected a number between 0 and 1"),
    ("--delta", "-0.1", "--delta is -0.1; expected a number between 0 and 1"),
    ("--threshold", "1", "--threshold is 1; expected a probability between 0 and 1"),
    ("--runs", "0", "--runs is 0; expected at least 1"),
    ("--time-bound", "soon", "--time-bound: 'soon' is not a duration"),
    ("--smc-workers", "0", "--smc-workers must be >= 1"),
    ("--batch", "0", "--batch is 0; expected at least 1"),
])
def test_bad_smc_options_are_usage_errors(capsys, option, value, message):
    code, out, err = verify(capsys, SLACK, "--timed", "--platform", SMC / "slack.yaml", "--smc", option, value)
    assert code == 2 and message in err and out == ""


def test_smc_options_need_smc_and_smc_needs_timed(capsys):
    code, _, err = verify(capsys, SLACK, "--smc")
    assert code == 2 and "--smc needs --timed" in err
    code, _, err = verify(capsys, SLACK, "--timed", "--runs", "5")
    assert code == 2 and "--runs needs --smc" in err


@pytest.mark.parametrize("text, where, message", [
    ("  Slack.cycle.compute: gaussian\n", "7:24", "distribution of Slack.cycle.compute is 'gaussian'"),
    ("  Slack.cycle.compute: {normal: [5 ms, 0 ms]}\n", "7:40", "the standard deviation must be positive"),
    ("  Slack.cycle.compute: {triangular: soon}\n", "7:37", "the mode is 'soon'; expected a duration"),
    ("  Slack.cycle.comptue: uniform\n", "7:3", "Slack.cycle runs no codel 'comptue'"),
])
def test_a_bad_distribution_is_named_at_its_line_and_column(capsys, tmp_path, text, where, message):
    path = tmp_path / "p.yaml"
    path.write_text((SMC / "slack.yaml").read_text() + "distributions:\n" + text)
    code, out, err = verify(capsys, SLACK, "--timed", "--platform", path, "--smc", "--runs", "5")
    assert code == 1 and f"{path}:{where}: error:" in err and message in err, err
    assert "Pr[" not in out


def test_a_triangular_distribution_moves_the_probability_as_computed_by_hand():
    # mode at 10 ms on [0, 10]: P(d > 6 ms) = 1 - 0.6^2 = 0.64
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "p.yaml"
        path.write_text((SMC / "slack.yaml").read_text()
                        + "distributions:\n  Slack.cycle.compute: {triangular: 10 ms}\n")
        model = build_model([SLACK], time=TimeSettings(platform=str(path)))
        report = estimate(model, SmcSettings(horizon_us=14_000, epsilon=0.05, delta=0.01))
    [overrun] = report.results
    assert overrun.estimate.contains(0.64) and not overrun.estimate.contains(0.4)


# --------------------------------------------------------------------------- campaigns


def campaign_file(tmp_path: Path, smc: str, vary: str = "{cores: [1, 2], policy: [edf, fixed-priority]}") -> Path:
    path = tmp_path / "c.yaml"
    path.write_text(f"""campaign: smc
models:
  slack:
    paths: [{SLACK}]
    timed: {{platform: {SMC / 'slack.yaml'}}}
checks:
  - check: smc
    model: slack
    smc: {smc}
    vary: {vary}
""")
    return path


def test_a_campaign_asks_for_smc_over_cores_and_policies(tmp_path):
    from genom2bip.campaign import expand, read_campaign, run_job

    path = campaign_file(tmp_path, "{time-bound: 15 ms, epsilon: 0.05, delta: 0.05, seed: 2}")
    jobs = expand(read_campaign(path)).jobs
    assert [dict(j.point) for j in jobs] == [{"cores": c, "policy": p} for c in (1, 2)
                                             for p in ("edf", "fixed-priority")]
    assert {j.target for j in jobs} == {"Pr[<= 15 ms]"} and len({j.id for j in jobs}) == 4
    record = run_job(jobs[0])
    assert record["status"] == "done" and record["verdict"] == "violated", record
    [overrun] = record["result"]["details"]["results"]
    details = overrun["details"]
    assert details["runs"] == 738 and details["seed"] == 2 and details["low"] <= 0.4 <= details["high"]
    other = expand(read_campaign(campaign_file(tmp_path, "{time-bound: 15 ms, epsilon: 0.05, seed: 3}"))).jobs
    assert {j.id for j in other}.isdisjoint(j.id for j in jobs)  # the seed is part of what a job is


@pytest.mark.parametrize("smc, column, message", [
    ("{epsilon: 2}", 20, "smc: epsilon is 2; expected a number between 0 and 1"),
    ("{time-bound: soon}", 23, "time-bound: 'soon' is not a duration"),
    ("{runs: many}", 17, "runs: 'many' is not a whole number"),
    ("{epsilon: 0.1, samples: 5}", 25, "unknown key 'samples'"),
])
def test_a_bad_smc_setting_of_a_campaign_is_located(tmp_path, smc, column, message):
    from genom2bip.campaign import read_campaign
    from runtime.diagnostics import DiagnosticError

    path = campaign_file(tmp_path, smc)
    with pytest.raises(DiagnosticError) as info:
        read_campaign(path)
    text = info.value.render()
    assert f"{path}:9:{column}: error: check 1 (smc): smc: " in text and message in text, text


def test_smc_refuses_what_belongs_to_exhaustive_verification(capsys, tmp_path):
    code, out, err = verify(capsys, SLACK, "--timed", "--platform", SMC / "slack.yaml", "--smc", "--deadlock")
    assert code == 2 and "--deadlock belongs to exhaustive verification" in err and out == ""
    assert main(["generate", str(SLACK), "--timed", "--platform", str(SMC / "slack.yaml"), "-o", str(tmp_path)]) == 0
    capsys.readouterr()
    code, out, err = verify(capsys, tmp_path / "slack" / "slack.bip", "--timed", "--smc")
    assert code == 2 and "--smc takes description files (a .bip file has no platform" in err and "Pr[" not in out


def test_the_python_engine_and_the_compiled_one_both_contain_the_probability(capsys):
    # the compiled engine runs its loop in C, from other random numbers than the Python loop's: other runs, drawn
    # from the same distribution (tests/test_smc_leaps.py)
    common = [SLACK, "--timed", "--platform", SMC / "slack.yaml", "--smc", "--time-bound", "15 ms", "--runs", "300"]
    _, compiled, _ = verify(capsys, *common)
    _, python, _ = verify(capsys, *common, "--engine", "python")
    for out in (compiled, python):
        _, low, high, _, runs = estimates(out)["period of Slack.cycle"]
        assert runs == 300 and low <= 0.4 <= high


def test_outputs_that_cannot_be_written_are_refused_before_any_run(capsys, tmp_path):
    code, out, err = verify(capsys, SLACK, "--timed", "--platform", SMC / "slack.yaml", "--smc", "--runs", "5",
                            "--histogram", tmp_path / "h.txt")
    assert code == 2 and "--histogram: " in err and "must end in .png or .svg" in err and out == ""
    platform = tmp_path / "slack.yaml"
    platform.write_text((SMC / "slack.yaml").read_text())
    before = platform.read_text()
    code, out, err = verify(capsys, SLACK, "--timed", "--platform", platform, "--smc", "--runs", "5",
                            "--smc-trace", SLACK)
    assert code == 1 and "is an input of this command" in err and out == ""
    code, out, err = verify(capsys, SLACK, "--timed", "--platform", platform, "--smc", "--runs", "5",
                            "--histogram", tmp_path / "slack.svg", "--smc-trace", platform)
    assert code == 1 and f"{platform} is an input of this command" in err and out == ""
    assert not (tmp_path / "slack.svg").exists()
    assert platform.read_text() == before and SLACK.read_text().startswith("/*")


def test_one_ctrl_c_prints_the_estimates_of_the_runs_read(tmp_path):
    from test_timing_interrupt import _interrupted

    # a million runs of 1 s: far more than a machine computes before the first progress line
    code, out, err = _interrupted(
        [str(SLACK), "--timed", "--platform", str(SMC / "safe.yaml"), "--smc", "--time-bound", "1 s", "--runs",
         "1000000", "--batch", "20", "--progress"], tmp_path,
        lambda s: any(x.startswith("smc: ") and " of 1,000,000 runs" in x for x in s["err"]))
    assert code == 5, out + err  # no run reached an overrun, and the estimate is not the one asked for
    assert "genom2bip: stopping: what was found so far follows (Ctrl-C again stops at once)" in err
    runs = int(re.search(r"interrupted by Ctrl-C after ([\d,]+) runs", out).group(1).replace(",", ""))
    assert runs > 0 and runs % 20 == 0  # whole batches only
    value, low, high, hits, counted = estimates(out)["period of Slack.cycle"]
    assert (value, low, hits, counted) == (0.0, 0.0, 0, runs)
    assert high == pytest.approx(min(1.0, (math.log(2 / 0.05) / (2 * runs)) ** 0.5), abs=1e-4)


@needs_cc
def test_ctrl_c_while_the_runs_call_back_into_python_stops_the_estimate(monkeypatch):
    # The C runs call back into Python for each interaction they meet first.  Python's own Ctrl-C handler raised
    # KeyboardInterrupt there, inside a ctypes callback, where it is printed and lost: the runs then ended as out
    # of memory, or the estimate went on with every run it planned (the test above, once, under load).
    import signal

    from runtime.smc import crun

    define, pressed = crun.CRuns._on_define, []

    def on_define(self, *args):
        if not pressed:
            pressed.append(True)
            signal.raise_signal(signal.SIGINT)
        return define(self, *args)

    monkeypatch.setattr(crun.CRuns, "_on_define", on_define)
    model = build_model([SLACK], time=TimeSettings(platform=str(SMC / "safe.yaml")))
    report = estimate(model, SmcSettings(horizon_us=100_000, runs=2000, batch=20))
    assert pressed and report.runner == "this process"
    assert report.stopped == "interrupted" and report.runs == 20, (report.stopped, report.runs)


# --------------------------------------------------------------------------- waits drawn over their interval


def test_a_first_period_delay_is_drawn_uniformly_over_its_interval():
    # delay [0, 10] ms at 2 ms ticks: the first period opens at 2, 4, 6, 8 or 10 ms, each with probability 0.2
    # (a race between time and the opening would open it within a tick or two most of the time)
    from collections import Counter

    model = build_model([SLACK], time=TimeSettings(platform=str(SMC / "delayed.yaml")))
    config = sim_config(model, SmcSettings(horizon_us=12_000))
    assert [(w.atom, w.end) for w in config.windows] == [("Slack.cycle.timer", "first")]
    sim, _ = simulator(model, config)
    opened: Counter = Counter()
    for index in range(1000):
        run = sim.run(5, index, record=True)
        labels = [sim.space.interaction(i).label for i, _ in run.choices]
        opened[labels[:labels.index("Slack.cycle:period")].count("tick")] += 1
    assert set(opened) == {1, 2, 3, 4, 5}
    assert all(abs(n / 1000 - 0.2) < 0.05 for n in opened.values()), opened


def test_a_suspension_is_drawn_uniformly_over_its_interval(capsys):
    # suspend [0, 4] ms, then 4 ms and 2 ms codels: a response of 8 or 10 ms, each half of the time
    model = build_model([SLACK], time=TimeSettings(platform=str(SMC / "suspended.yaml")))
    report = estimate(model, SmcSettings(horizon_us=100_000, runs=200))
    [cycle] = [d for d in report.responses if d.owner == "Slack.cycle"]
    assert set(cycle.counts) == {4, 5} and cycle.samples == 200 * 10
    assert abs(cycle.counts[4] / cycle.samples - 0.5) < 0.05
    code, out, _ = verify(capsys, SLACK, "--timed", "--platform", SMC / "suspended.yaml", "--response-times")
    assert code == 0 and re.search(r"^  Slack.cycle\s+10 ms", out, re.M)  # the largest SMC saw is the bound


def test_a_scheduler_out_of_reach_is_said_and_nothing_written(capsys, monkeypatch, tmp_path):
    pytest.importorskip("distributed")
    from genom2bip.cli import verify_smc
    from tests.test_campaign_dask import free_port

    monkeypatch.setattr(verify_smc, "CONNECT_TIMEOUT", 2.0)
    trace = tmp_path / "t.json"
    address = f"tcp://127.0.0.1:{free_port()}"  # nobody listens there
    code, out, err = verify(capsys, SLACK, "--timed", "--platform", SMC / "slack.yaml", "--smc", "--runs", "10",
                            "--scheduler", address, "--smc-trace", trace)
    assert code == 1 and f"cannot reach the Dask scheduler {address}" in err and "internal error" not in err
    assert "Pr[" not in out and not trace.exists()
