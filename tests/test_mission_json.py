"""``genom2bip mission --json``: the report as one document that follows genom2bip/cli/mission_schema.json, with
the same verdicts as the text report and nothing else on stdout (docs/output.md)."""
from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest

from genom2bip.cli.command import main

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
SCHEMA = json.loads((ROOT / "genom2bip" / "cli" / "mission_schema.json").read_text())


@pytest.fixture(scope="module")
def thermo(tmp_path_factory):
    out = tmp_path_factory.mktemp("gen")
    assert main([str(EXAMPLES / "thermo.gen"), "-I", str(EXAMPLES / "include"), "-D", "SIM=1", "-o", str(out)]) == 0
    return out / "thermo"


def mission(capsys, package, tmp_path, text=None, codels=True):
    path = EXAMPLES / "thermo.yaml"
    if text is not None:
        path = tmp_path / "m.yaml"
        path.write_text(text)
    argv = ["mission", str(path), "--package", str(package), "--out", str(tmp_path / "out"), "--json"]
    code = main(argv + (["--codels", str(EXAMPLES / "codels")] if codels else []))
    out, err = capsys.readouterr()
    data = json.loads(out)  # stdout is the document alone
    jsonschema.validate(data, SCHEMA)
    assert data["exit_status"] == code, err
    return code, data


def test_a_mission_met_in_json(capsys, thermo, tmp_path):
    code, data = mission(capsys, thermo, tmp_path)
    assert code == 0 and data["ok"] and data["expectations_met"] and data["real_time_held"]
    assert [(r["target"], r["status"]) for r in data["requests"]] == [
        ("thermo.SetLimit", "ok"), ("thermo.Heat", "ok"), ("thermo.Heat", "failed"), ("thermo.Heat", "interrupted"),
        ("thermo.Stop", "ok"), ("heating", "interrupted")]
    assert data["requests"][2]["exception"].endswith("e_too_hot")
    (sense,) = data["timing"]
    assert (sense["task"], sense["missed"], sense["overran"]) == ("thermo.sense", 0, 0)
    assert data["files"] == [str(tmp_path / "out" / "thermo.jsonl")]
    assert (tmp_path / "out" / "thermo.jsonl").is_file()


def test_an_unmet_expectation_in_json(capsys, thermo, tmp_path):
    code, data = mission(capsys, thermo, tmp_path, "mission: wrong\nsteps:\n  - send: thermo.SetLimit\n"
                                                   "    with: {limit: 25.0}\n    expect: failed\n")
    assert code == 4 and not data["ok"] and not data["expectations_met"]
    (request,) = data["requests"]
    assert request["expected"] is False and request["problem"].startswith("expected status failed, got 'ok'")
