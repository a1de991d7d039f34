"""Campaigns on a platform: the platform and client keys of a model, the cores, policy and platform axes, and the
response-times check, whose values (ms per task, or ``unbounded``) go into each record, the table and the picture.

The sweep runs on a local Dask cluster and waits for the command to end, never for a time.  Its values are the ones
worked out by hand for the fixtures (tests/fixtures/platform/*.gen say why), and the same as each job run alone.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from genom2bip.campaign import expand, read_campaign, run_job
from genom2bip.campaign.params import ModelParams
from genom2bip.loading import TimeSettings, UsageError
from genom2bip.verify import build_model
from runtime.diagnostics import DiagnosticError
from tests.nativekit import needs_cc

ROOT = Path(__file__).resolve().parents[1]
PLATFORM = ROOT / "tests" / "fixtures" / "platform"
PAIR = PLATFORM / "Pair.gen"
STARVED = PLATFORM / "Starved.gen"
DALA = ROOT / "descriptions" / "dala"
#: Far past what a loaded machine needs for this small campaign: a hang fails, a slow machine does not.
PATIENCE = 900

MODELS = f"""models:
  pair:
    paths: [{PAIR}]
    timed: true
  ndd:
    paths: [{DALA / 'NDD.gen'}]
"""


def problems(tmp_path: Path, text: str) -> list[tuple[str, int, int, str]]:
    """(file, line, column, message) of every error the campaign has, read and expanded."""
    path = tmp_path / "c.yaml"
    path.write_text(text)
    with pytest.raises(DiagnosticError) as info:
        expand(read_campaign(path))
    return [(d.span.file, d.span.line, d.span.column, d.message) for d in info.value.diagnostics
            if d.severity == "error"]


def at(text: str, line: int, token: str) -> tuple[int, int]:
    return line, text.splitlines()[line - 1].index(token) + 1


# --------------------------------------------------------------------------- errors, located


@pytest.mark.parametrize("model, token, message", [
    ("timed: {platform: nowhere.yaml}", "nowhere", "model m: platform: nowhere.yaml: no such file or directory"),
    ("timed: {client: nowhere.yaml}", "nowhere", "model m: client: nowhere.yaml: no such file or directory"),
    ("timed: {platform: [a, b]}", "[a", "model m: platform: a single value expected"),
    ("timed: {platform: p.yaml, cores: 2}", "cores: 2",
     "model m: timed: unknown key 'cores' (keys: tick, default-wcet, observers, platform, client)"),
])
def test_a_model_s_platform_and_client_are_located(tmp_path, model, token, message):
    (tmp_path / "p.yaml").write_text("cores: 1\n")
    text = f"models:\n  m: {{paths: [{PAIR}], {model}}}\nchecks: [{{check: deadlock, model: m}}]\n"
    found = problems(tmp_path, text)
    assert [(n, c) for _, n, c, m in found if message in m] == [at(text, 2, token)], found


@pytest.mark.parametrize("check, token, message", [
    ("{check: deadlock, model: pair, vary: {cores: [1, 0]}}", "0]",
     "vary: cores: a whole number of cores from 1 to 256 expected, got 0"),
    ("{check: deadlock, model: pair, vary: {cores: [two]}}", "two", "cores from 1 to 256 expected, got 'two'"),
    ("{check: deadlock, model: pair, vary: {cores: [1.5]}}", "1.5", "cores from 1 to 256 expected, got 1.5"),
    ("{check: deadlock, model: pair, vary: {cores: [2, 2]}}", "[2", "vary: cores: a value is given twice"),
    ("{check: deadlock, model: pair, vary: {cores.x: [2]}}", "cores.x", "axis 'cores.x': cores takes no name"),
    ("{check: deadlock, model: pair, vary: {cores: [1], policy: [rms]}}", "rms",
     "vary: policy: a policy expected (edf or fixed-priority), got 'rms'"),
    ("{check: deadlock, model: pair, vary: {policy: [edf]}}", "policy",
     "check 1 (deadlock): axis policy needs a platform, and model pair has none"),
    ("{check: deadlock, model: pair, vary: {platform: [nowhere.yaml]}}", "nowhere",
     "check 1 (deadlock): vary: platform: nowhere.yaml: no such file or directory"),
    ("{check: deadlock, model: pair, vary: {platform: [7]}}", "7", "platform: a platform file's path expected, got 7"),
    ("{check: deadlock, model: ndd, vary: {cores: [1, 2]}}", "cores",
     "check 1 (deadlock): axis cores changes only a timed model, and model ndd is not timed"),
    ("{check: response-times, model: ndd}", "ndd", "check 1 (response-times): model ndd is not timed"),
    ("{check: response-times, model: pair, of: [threads]}", "[threads",
     "of: 'threads' is not one of tasks, services"),
    ("{check: response-times, model: pair, files: [x]}", "files", "'files' belongs to another kind of check (this "
                                                                  "one takes: check, model, method, options, timeout, "
                                                                  "vary, doc, of, only)"),
    ("{check: response-times, model: pair, method: compositional}", "compositional",
     "response times are measured by one exploration with clock zones: method explore (the default)"),
    ("{check: response-times, model: pair, only: [Pair.nope]}", "[Pair",
     "no task or service Pair.nope (found: Pair.fast, Pair.slow)"),
])
def test_each_problem_of_the_new_keys_and_axes_is_located(tmp_path, check, token, message):
    text = MODELS + f"checks:\n  - {check}\n"
    found = problems(tmp_path, text)
    assert [(n, c) for _, n, c, m in found if message in m] == [at(text, 8, token)], found


def test_a_platform_file_s_own_errors_name_that_file(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("cores: 1\nexecution:\n  Pair.fast.nope: 2 ms\n")
    found = problems(tmp_path, f"models:\n  m: {{paths: [{PAIR}], timed: {{platform: {bad}}}}}\n"
                               "checks: [{check: response-times, model: m}]\n")
    assert [(f, n, c) for f, n, c, _ in found] == [(str(bad), 3, 3)], found
    assert "Pair.fast runs no codel 'nope'" in found[0][3]


def test_on_the_command_line_a_bad_axis_runs_nothing_and_writes_nothing(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text(MODELS + "checks:\n  - {check: response-times, model: pair, vary: {cores: [1, 0]}}\n")
    proc = subprocess.run([sys.executable, "-m", "genom2bip", "campaign", str(path), "-o", str(tmp_path / "out")],
                          capture_output=True, text=True, cwd=tmp_path, timeout=PATIENCE)
    assert proc.returncode == 1, proc.stderr
    assert f"{path}:8:60: error: check 1 (response-times): vary: cores: a whole number of cores from 1 to 256 " \
           "expected, got 0" in proc.stderr
    assert proc.stdout == "" and sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml"]


# --------------------------------------------------------------------------- the model's parameters


def test_a_cores_axis_without_a_file_is_that_many_cores_under_edf_and_over_a_file_replaces_its_cores(tmp_path):
    alone = build_model([PAIR], time=TimeSettings(cores=3))
    assert _platform(alone) == "3 cores, cooperative EDF"
    fp = tmp_path / "fp.yaml"
    fp.write_text("cores: 1\npolicy: fixed-priority\n")
    over = build_model([PAIR], time=TimeSettings(platform=fp, cores=2))
    assert _platform(over) == "2 cores, fixed priority (non-preemptive at codel boundaries)"
    policy = build_model([PAIR], time=TimeSettings(platform=fp, policy="edf"))
    assert _platform(policy) == "1 core, cooperative EDF"


@pytest.mark.parametrize("settings, message", [
    (TimeSettings(policy="edf"), "policy edf needs a platform: a platform file or a number of cores"),
    (TimeSettings(cores=0), "cores is 0; expected a whole number from 1 to 256"),
    (TimeSettings(cores=1, policy="rms"), "policy is 'rms'; expected edf or fixed-priority"),
])
def test_settings_that_make_no_platform_are_refused(settings, message):
    with pytest.raises(UsageError) as info:
        build_model([PAIR], time=settings)
    assert info.value.messages == [message]


def test_a_campaign_without_a_platform_keeps_the_job_ids_it_had_before_the_platform_keys():
    # The id of this job as the campaign computed it before a model could have a platform: results written then
    # are still recognised, and not run again.
    from genom2bip.campaign.jobs import job_id

    assert job_id(Path("/x"), ModelParams(("/x/a.gen",), timed=True), "observer", "explore", "t", (), ()) \
        == "593a160c90fedaf0"


def _platform(model) -> str:
    ann = next(a for a in model.package.annotations if a.name == "timed")
    return ann.arguments.get("platform", "")


# --------------------------------------------------------------------------- a sweep over cores, on the cluster

SWEEP = f"""campaign: cores
models:
  pair:
    paths: [{PAIR}]
    timed: true                         # no platform file: the cores axis makes one (EDF, codels in [0, WCET])
  starved:
    paths: [{STARVED}]
    timed: {{platform: fp.yaml}}          # 1 core by fixed priority, codels take their WCET; the axis replaces 1
vary:
  cores: [1, 2]
checks:
  - check: response-times
    model: pair
  - check: response-times
    model: starved
    of: [tasks]
  - check: observer
    model: pair
    kinds: [overrun]
    only: [Pair.slow.overrun]
"""


@needs_cc
def test_a_sweep_over_cores_records_each_response_time_tables_and_draws_them(tmp_path):
    pytest.importorskip("distributed")
    (tmp_path / "fp.yaml").write_text("cores: 1\npolicy: fixed-priority\nbest: wcet\n")
    path = tmp_path / "cores.yaml"
    path.write_text(SWEEP)
    jobs = expand(read_campaign(path)).jobs
    assert len(jobs) == 6
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "genom2bip", "campaign", str(path), "-o", str(out), "--workers", "2"],
                          capture_output=True, text=True, cwd=tmp_path, env=dict(os.environ), timeout=PATIENCE)
    assert proc.returncode == 4, proc.stdout + proc.stderr  # starved on one core: a response without a bound
    records = {(r["model"], r["check"], r["point"]["cores"]): r
               for r in map(json.loads, (out / "results.jsonl").read_text().splitlines())}
    assert len(records) == 6 and all(r["status"] == "done" for r in records.values())
    values = {key: r["values"] for key, r in records.items() if r["check"] == "response-times"}
    # Pair: two 6 ms codels released together every 10 ms; on one core the second granted ends at 6 + 6 = 12 ms
    # (either one: EDF with equal deadlines), on two cores each ends at 6 ms.
    assert values["pair", "response-times", 1] == {"Pair.fast": 12, "Pair.slow": 12}
    assert values["pair", "response-times", 2] == {"Pair.fast": 6, "Pair.slow": 6}
    # Starved (tasks only): busy takes its whole 10 ms; on one core by fixed priority idle is never granted the
    # core (recorded as a word, not a number), on two it ends its 1 ms codel 1 ms after its release.
    assert values["starved", "response-times", 1] == {"Starved.busy": 10, "Starved.idle": "unbounded"}
    assert values["starved", "response-times", 2] == {"Starved.busy": 10, "Starved.idle": 1}
    unbounded = records["starved", "response-times", 1]
    assert unbounded["verdict"] == "violated" and unbounded["message"] == "no bound: Starved.idle"
    lasso = json.loads((out / unbounded["trace"]).read_text())["trace"]
    assert lasso["loop"] is not None and lasso["timed"]
    assert {r["verdict"] for k, r in records.items() if k != ("starved", "response-times", 1)
            and k[1] == "response-times"} == {"holds"}
    # the period observer on a platform model is decided by clock zones, as verify decides it
    assert records["pair", "observer", 1]["verdict"] == "violated"
    assert records["pair", "observer", 2]["verdict"] == "holds"
    assert json.loads((out / records["pair", "observer", 1]["result"]).read_text())["method"].startswith("zones")
    # every value is the one of the job run alone, in this process
    for job in jobs:
        assert run_job(job)["values"] == records[job.model, job.check, dict(job.point)["cores"]]["values"], job.title
    # the table: a row per task or service, a column per point, the word where there is no number
    table = proc.stdout.split("task or service", 1)[1].splitlines()
    assert table[0].split() == ["cores=1", "cores=2"]
    assert table[1].split() == ["pair", "response-times", "Pair.fast", "12", "ms", "6", "ms"]
    assert table[4].split() == ["starved", "response-times", "Starved.idle", "unbounded", "1", "ms"]
    assert f"picture: {out / 'cores.png'}" in proc.stdout
    assert (out / "cores.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@needs_cc
@pytest.mark.parametrize("of, verdict, values", [
    # Watch pauses for ever once started: only an interruption could end its request; Once ends within 14 ms
    # (docs of Endless.gen)
    ("[services]", "violated", {"Endless.Watch": "until stopped", "Endless.Once": 14}),
    ("[tasks]", "holds", {"Endless.main": None}),
])
def test_the_verdict_and_values_are_those_of_the_tasks_or_services_recorded(tmp_path, of, verdict, values):
    (tmp_path / "fp.yaml").write_text("cores: 1\npolicy: fixed-priority\nbest: wcet\n")
    path = tmp_path / "c.yaml"
    path.write_text(f"models:\n  m: {{paths: [{PLATFORM / 'Endless.gen'}], timed: {{platform: fp.yaml}}}}\n"
                    f"checks: [{{check: response-times, model: m, of: {of}}}]\n")
    (job,) = expand(read_campaign(path)).jobs
    record = run_job(job)
    assert (record["status"], record["verdict"]) == ("done", verdict), record["message"]
    assert set(record["values"]) == set(values) and record["of"] == [of.strip("[]")]
    for owner, value in values.items():
        if value is None:  # main's cycle ends within its period, whichever services run
            assert 0 < record["values"][owner] <= 10
        else:
            assert record["values"][owner] == value
