"""``genom2bip campaign --json``: one document on stdout that follows genom2bip/cli/campaign_schema.json (each job
with its answer and record, the counts, the run, the pictures, the exit status); a bad file prints no document.

The runs are small campaigns on a local Dask cluster; each test waits for the command to end, never for a time.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import jsonschema
import pytest

from genom2bip.campaign import expand, read_campaign
from tests.nativekit import needs_cc
from test_campaign_run import CRUISE, CRUISE_OBSERVERS, PATIENCE

ROOT = Path(__file__).resolve().parents[1]
SCHEMA = json.loads((ROOT / "genom2bip" / "cli" / "campaign_schema.json").read_text())

SWEEP = f"""campaign: cruise
models:
  cruise:
    paths: [{CRUISE}]
    timed: {{observers: {CRUISE_OBSERVERS}}}
vary:
  define.PERIOD: [10, 15]
checks:
  - check: observer
    model: cruise
"""


def campaign(args, cwd: Path) -> tuple[subprocess.CompletedProcess, dict | None]:
    """The command (this checkout's code) and its document, validated against the schema; None when stdout is
    empty."""
    proc = subprocess.run([sys.executable, "-m", "genom2bip", "campaign", *map(str, args), "--json"],
                          capture_output=True, text=True, cwd=cwd, timeout=PATIENCE,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    if not proc.stdout:
        return proc, None
    data = json.loads(proc.stdout)  # stdout is the document alone
    jsonschema.validate(data, SCHEMA)
    assert data["exit_status"] == proc.returncode, proc.stderr
    return proc, data


@pytest.fixture
def sweep(tmp_path) -> Path:
    path = tmp_path / "cruise.yaml"
    path.write_text(SWEEP)
    return path


def test_list_prints_the_jobs_and_runs_nothing(tmp_path, sweep):
    proc, data = campaign([sweep, "--list"], tmp_path)
    jobs = expand(read_campaign(sweep)).jobs
    assert proc.returncode == 0 and data["listed"] and data["directory"] is None and data["run"] is None
    assert [j["job"] for j in data["jobs"]] == [j.id for j in sorted(jobs, key=lambda j: j.index)] and len(jobs) == 6
    assert all(j["answer"] is None and j["record"] is None and not j["ran"] for j in data["jobs"])
    assert data["counts"] == {} and data["meaning"].startswith("done")
    assert not (tmp_path / "out").exists()


@needs_cc
def test_a_run_then_a_second_that_has_nothing_left_to_run(tmp_path, sweep):
    pytest.importorskip("distributed")
    out = tmp_path / "out"
    proc, data = campaign([sweep, "-o", out, "--workers", "1"], tmp_path)
    assert proc.returncode == 4, proc.stderr  # a period of 10 ms overruns
    records = {r["job"]: r for r in map(json.loads, (out / "results.jsonl").read_text().splitlines())}
    assert {j["job"] for j in data["jobs"]} == set(records) and len(records) == 6
    for job in data["jobs"]:
        assert job["record"] == records[job["job"]] and job["ran"]
        assert job["answer"] == records[job["job"]]["verdict"]
    by_point = {(j["point"]["define.PERIOD"], j["target"]): j["answer"] for j in data["jobs"]}
    assert by_point[10, "Cruise.loop.overrun"] == "violated" and by_point[15, "Cruise.loop.overrun"] == "holds"
    assert sum(data["counts"].values()) == 6 and data["counts"]["violated"] >= 1
    assert data["run"]["jobs_run"] == 6 and data["run"]["cluster"].startswith("local cluster")
    assert data["results"] == str(out / "results.jsonl") and data["directory"] == str(out)
    assert data["pictures"] and all(Path(p).is_file() for p in data["pictures"])
    assert (data["stopped"], data["undone"]) == (None, [])
    assert data["meaning"].startswith("found")
    again, second = campaign([sweep, "-o", out], tmp_path)
    assert again.returncode == 4 and second["run"] is None  # nothing to run: no cluster started
    assert [(j["job"], j["answer"]) for j in second["jobs"]] == [(j["job"], j["answer"]) for j in data["jobs"]]
    assert not any(j["ran"] for j in second["jobs"]) and second["counts"] == data["counts"]


def test_a_bad_campaign_file_prints_no_document_and_writes_nothing(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("models: {m: {paths: [nowhere.gen]}}\nchecks: [{check: deadlock, model: m}]\n")
    proc, data = campaign([path, "-o", tmp_path / "out"], tmp_path)
    assert proc.returncode == 1 and data is None
    assert f"{path}:1:22: error: model m: paths: nowhere.gen: no such file or directory" in proc.stderr
    assert not (tmp_path / "out").exists()


def test_the_document_of_an_interrupted_run_names_the_jobs_left_undone():
    from genom2bip.campaign.document import CampaignAnswer, document
    from genom2bip.campaign.jobs import Job
    from genom2bip.campaign.params import ModelParams

    params = ModelParams(("m.gen",))
    jobs = [Job(f"j{k}", "m", params, "deadlock", "explore", "deadlock freedom", index=k) for k in range(3)]
    record = {"job": "j0", "status": "done", "verdict": "holds", "seconds": 0.1}
    answer = CampaignAnswer("c", "c.yaml", jobs, records={"j0": record}, directory="out", results="out/results.jsonl",
                            ran={"j0"}, run={"cluster": "local cluster tcp://127.0.0.1:1: 1 workers, 1 threads",
                                             "jobs_run": 1, "wall_s": 0.5, "job_s": 0.1, "cpu_s": 0.1},
                            undone=["j1", "j2"], stopped="interrupted")
    data = document(answer, 130)
    jsonschema.validate(data, SCHEMA)
    assert [j["answer"] for j in data["jobs"]] == ["holds", "not done", "not done"]
    assert data["counts"] == {"not done": 2, "holds": 1} and data["undone"] == ["j1", "j2"]
    assert data["meaning"].startswith("interrupted")


def test_the_schema_refuses_a_document_missing_its_exit_status():
    from genom2bip.campaign.document import CampaignAnswer, document

    data = document(CampaignAnswer("c", "c.yaml", []), 0)
    jsonschema.validate(data, SCHEMA)
    del data["exit_status"]
    with pytest.raises(jsonschema.ValidationError, match="exit_status"):
        jsonschema.validate(data, SCHEMA)


def test_the_schema_is_shipped_with_the_package():
    text = (ROOT / "pyproject.toml").read_text()
    assert '"cli/campaign_schema.json"' in text
