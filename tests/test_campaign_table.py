"""The campaign's table says why a job gave no answer: the limit that stopped it, or its failure's first line."""
from __future__ import annotations

import io
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from genom2bip.campaign.report import summary, why
from tests.nativekit import needs_cc

ROOT = Path(__file__).resolve().parents[1]
CRUISE = ROOT / "tests" / "fixtures" / "timed" / "Cruise.gen"


@pytest.mark.parametrize("record, said", [
    ({"status": "done", "verdict": "holds"}, "-"),
    ({"status": "done", "verdict": "violated", "message": "overrun reachable"}, "-"),
    ({"status": "done", "verdict": "inconclusive", "limit": "max-states",
      "message": "stopped at 5,000,000 states (round 2)"},
     "stopped by max-states: stopped at 5,000,000 states (round 2)"),
    ({"status": "done", "verdict": "inconclusive", "limit": "max-memory", "message": ""}, "stopped by max-memory"),
    ({"status": "timeout", "limit": "timeout", "message": "stopped past its time limit of 2 s; its worker was "
      "restarted"}, "stopped past its time limit of 2 s; its worker was restarted"),
    ({"status": "failed", "message": "externs: importing x.py failed: RuntimeError: broken\n  more lines"},
     "externs: importing x.py failed: RuntimeError: broken"),
    ({"status": "crashed", "message": "the worker process died each time it ran it " + "x" * 80}, None),
    (None, "not run yet"),
], ids=["holds", "violated", "inconclusive", "limit only", "timeout", "failed", "long", "not run"])
def test_why_a_job_gave_no_answer_in_one_short_cell(record, said):
    text = why(record)
    if said is None:
        assert len(text) == 72 and text.endswith("...") and text.startswith("the worker process died")
    else:
        assert text == said


@needs_cc
def test_the_table_of_a_campaign_with_an_inconclusive_job_says_which_limit_stopped_it(tmp_path):
    pytest.importorskip("distributed")
    path = tmp_path / "c.yaml"
    path.write_text(f"""models:
  cruise: {{paths: [{CRUISE}], timed: true}}
checks:
  - {{check: observer, model: cruise, options: {{max-states: 50}}}}
""")
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "genom2bip", "campaign", str(path), "-o", str(out), "--workers", "1"],
                          capture_output=True, text=True, cwd=tmp_path, env=dict(os.environ), timeout=900)
    assert proc.returncode == 5, proc.stdout + proc.stderr
    records = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert {r["verdict"] for r in records} == {"inconclusive"} and {r["limit"] for r in records} == {"max-states"}
    table = proc.stdout[proc.stdout.index("model "):].splitlines()
    assert table[0].split()[-1] == "why"
    rows = [line for line in table[1:] if line.startswith("cruise")]
    assert rows and all(line.split("  ")[-1].strip().startswith("stopped by max-states") for line in rows), table


def test_summary_keeps_one_row_per_job_with_its_reason():
    from genom2bip.campaign.jobs import Job
    from genom2bip.campaign.params import ModelParams

    jobs = [Job(id="a", model="m", params=ModelParams(paths=()), check="deadlock", method="explore",
                target="deadlock freedom", index=0)]
    out = io.StringIO()
    counts = summary(jobs, {"a": {"status": "done", "verdict": "inconclusive", "limit": "max-depth",
                                   "figures": {"states": 12}, "seconds": 1.0}}, out)
    header, row, total = out.getvalue().splitlines()
    assert header.split()[-1] == "why" and row.endswith("stopped by max-depth") and counts == {"inconclusive": 1}
    assert total == "1 jobs: 1 inconclusive"
