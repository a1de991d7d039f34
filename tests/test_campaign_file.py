"""Campaign files: every problem named file:line:column with what was expected, nothing run or written; the jobs a
good file gives (the cross product of its axes, one per target, stable ids); sweeps' variants run in this process."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from genom2bip.campaign import expand, read_campaign, run_job
from runtime.diagnostics import DiagnosticError

ROOT = Path(__file__).resolve().parents[1]
DALA = ROOT / "descriptions" / "dala"
CRUISE = ROOT / "tests" / "fixtures" / "timed" / "Cruise.gen"
NDD_PROPS = ROOT / "tests" / "fixtures" / "verify" / "goto_after_setspeed.mcl"

GOOD_MODELS = f"""models:
  cruise:
    paths: [{CRUISE}]
    timed: true
  ndd:
    paths: [{DALA / 'NDD.gen'}]
"""


def problems(tmp_path: Path, text: str, settings=None) -> list[tuple[int, int, str]]:
    """(line, column, message) of every error the file has, read and expanded."""
    path = tmp_path / "c.yaml"
    path.write_text(text)
    with pytest.raises(DiagnosticError) as info:
        expand(read_campaign(path, settings))
    return [(d.span.line, d.span.column, d.message) for d in info.value.diagnostics if d.severity == "error"]


def one(tmp_path: Path, text: str, **kw) -> tuple[int, int, str]:
    found = problems(tmp_path, text, **kw)
    assert len(found) == 1, found
    return found[0]


def at(text: str, line: int, token: str) -> tuple[int, int]:
    """The line and column of ``token`` on ``line`` of ``text`` (1-based): where an error must point."""
    return line, text.splitlines()[line - 1].index(token) + 1


@pytest.mark.parametrize("text, line, token, message", [
    ("- a list\n", 1, "-", "a campaign file is a mapping with 'models' and 'checks'"),
    ("models: {}\nchecks: []\nsteps: 1\n", 3, "steps", "campaign file: unknown key 'steps'"),
    ("checks: []\n", 1, "checks", "campaign file: 'models' expected"),
    ("models:\n  m: {paths: [a], each: b}\nchecks: [{check: deadlock, model: m}]\n", 2, "{",
     "model m: exactly one of 'paths'"),
    ("models:\n  m: {paths: [nowhere.gen]}\nchecks: [{check: deadlock, model: m}]\n", 2, "nowhere",
     "model m: paths: nowhere.gen: no such file or directory"),
    ("models:\n  m: {each: '${corpus}'}\nchecks: [{check: deadlock, model: m}]\n", 2, "'",
     "model m: each: ${corpus} is not set"),
    ("models:\n  m: {paths: [x], timed: {tick: soon}}\nchecks: []\n", 2, "soon", "model m: tick: a duration expected"),
    ("models: {m: {paths: [x]}}\nchecks: [1]\n", 2, "1", "check 1: a mapping expected"),
])
def test_the_file_s_shape(tmp_path, text, line, token, message):
    (tmp_path / "x").mkdir()
    found = problems(tmp_path, text)
    assert [(n, c) for n, c, m in found if message in m] == [at(text, line, token)], found


@pytest.mark.parametrize("check, token, message", [
    ("{check: liveness, model: ndd}", "liveness", "check 1: unknown check 'liveness' (checks: deadlock, property, "
                                                  "observer, response-times, smc)"),
    ("{check: deadlock, model: nope}", "nope", "check 1 (deadlock): no model 'nope' (models: cruise, ndd)"),
    ("{check: deadlock, model: ndd, method: magic}", "magic", "method: one of explore, compositional expected"),
    (f"{{check: deadlock, model: ndd, files: [{NDD_PROPS}]}}", "files",
     "'files' belongs to another kind of check (this one takes: check, model, method, options, timeout, vary, doc)"),
    ("{check: property, model: ndd}", "{", "check 1 (property): 'files' expected"),
    ("{check: observer, model: ndd}", "ndd", "check 1 (observer): model ndd is not timed"),
    ("{check: observer, model: cruise, kinds: [slow]}", "[slow", "kinds: 'slow' is not one of overrun, latency"),
    ("{check: deadlock, model: ndd, options: {max-states: -1}}", "-1", "max-states: an integer (0 or more) expected"),
    ("{check: deadlock, model: ndd, options: {engine: uppaal}}", "uppaal", "engine: one of compiled, python, spin"),
    ("{check: deadlock, model: ndd, timeout: soon}", "soon", "timeout: a positive duration expected (e.g. 30 s"),
    ("{check: deadlock, model: ndd, options: {speed: 2}}", "speed", "options: unknown key 'speed' (keys: engine,"),
    ("{check: deadlock, model: ndd, vary: {colour: [1]}}", "colour", "unknown axis 'colour' (axes: define.NAME,"),
    ("{check: deadlock, model: ndd, vary: {define.9x: [1]}}", "define", "define.NAME with a macro name expected"),
    ("{check: deadlock, model: ndd, vary: {wcet-scale: [1]}}", "wcet-scale",
     "check 1 (deadlock): axis wcet-scale changes only a timed model, and model ndd is not timed"),
    ("{check: deadlock, model: cruise, vary: {default-wcet: [1 ms, fast]}}", "fast",
     "default-wcet: a duration expected (e.g. 10 ms, 1 s, 500 us), got 'fast'"),
    ("{check: deadlock, model: cruise, vary: {wcet-scale: [1, 1.0]}}", "[1,", "wcet-scale: a value is given twice"),
    ("{check: deadlock, model: cruise, vary: {wcet-scale: [1.0e+300]}}", "1.0e",
     "wcet-scale: a factor from 0 to 1000 expected"),
    ("{check: deadlock, model: cruise, vary: {period.loop: [1 ms]}}", "period", "a task Module.task expected"),
    ("{check: deadlock, model: cruise, vary: {period.Cruise.nope: [5 ms]}}", "period",
     "period of Cruise.nope: no task Cruise.nope (tasks: Cruise.loop)"),
    ("{check: observer, model: cruise, only: [Cruise.nope]}", "[Cruise",
     "no observer Cruise.nope (found: Cruise.loop.overrun)"),
    (f"{{check: property, model: ndd, files: [{NDD_PROPS}], only: [nope]}}", "[nope",
     "no property nope (found: goto_after_setspeed, goto_after_setspeed_mcl, paper)"),
])
def test_each_check_s_problem_is_located(tmp_path, check, token, message):
    text = GOOD_MODELS + f"checks:\n  - {check}\n"
    assert [(n, c) for n, c, m in problems(tmp_path, text) if message in m] == [at(text, 8, token)]


def test_a_property_file_s_own_errors_name_that_file(tmp_path):
    bad = tmp_path / "bad.mcl"
    bad.write_text("ok: deadlock free;\nbroken: [ true* . ] false;\n")
    path = tmp_path / "c.yaml"
    path.write_text(GOOD_MODELS + f"checks:\n  - {{check: property, model: ndd, files: [{bad}]}}\n")
    with pytest.raises(DiagnosticError) as info:
        expand(read_campaign(path))
    assert [d.span.file for d in info.value.diagnostics] == [str(bad)]
    assert info.value.diagnostics[0].span.line == 2


def test_not_valid_yaml_is_located(tmp_path):
    assert one(tmp_path, "models: {a: [1, 2}\n")[:2] == (1, 18)


def test_every_problem_at_once(tmp_path):
    found = problems(tmp_path, GOOD_MODELS + "checks:\n  - {check: liveness, model: ndd}\n"
                                            "  - {check: deadlock, model: nope}\n")
    assert [m.split(":")[0] for _, _, m in found] == ["check 1", "check 2 (deadlock)"]


def test_on_the_command_line_an_error_runs_nothing_and_writes_nothing(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text(GOOD_MODELS + "checks:\n  - {check: deadlock, model: nope}\n")
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "genom2bip", "campaign", str(path), "-o", str(out)],
                          capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr
    assert f"{path}:8:30: error: check 1 (deadlock): no model 'nope' (models: cruise, ndd)" in proc.stderr
    assert "    - {check: deadlock, model: nope}" in proc.stderr  # the line quoted, a caret under the column
    assert proc.stdout == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml"]


def test_an_unset_variable_says_how_to_set_it_and_set_it_is_read(tmp_path):
    text = "models:\n  m: {each: '${corpus}', no-rules: true}\nchecks: [{check: deadlock, model: m}]\n"
    path = tmp_path / "c.yaml"
    path.write_text(text)
    with pytest.raises(DiagnosticError) as info:
        read_campaign(path)
    assert info.value.diagnostics[0].hint == "give --set corpus=VALUE"
    jobs = expand(read_campaign(path, {"corpus": str(DALA)})).jobs
    assert [j.model for j in jobs] == ["Aspect", "LaserRF", "NDD", "POM", "Planner", "RFLEX"]


# --------------------------------------------------------------------------- the jobs


SWEEP = f"""campaign: sweep
models:
  cruise:
    paths: [{CRUISE}]
    timed: true
vary:
  define.PERIOD: [10, 15]
checks:
  - check: observer
    model: cruise
    vary: {{wcet-scale: [0.5, 1]}}
  - check: deadlock
    model: cruise
"""


def test_the_cross_product_one_job_per_target_and_ids_that_do_not_move(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "c.yaml").write_text(SWEEP)
    jobs = expand(read_campaign(tmp_path / "a" / "c.yaml")).jobs
    observers = [j for j in jobs if j.check == "observer"]
    assert len(observers) == 2 * 2 * 1 and len(jobs) == 4 + 2  # the file's axis times the check's, one observer
    assert [dict(j.point) for j in observers] == [{"define.PERIOD": p, "wcet-scale": s}
                                                  for p in (10, 15) for s in (0.5, 1)]
    assert len({j.id for j in jobs}) == len(jobs)
    again = expand(read_campaign(tmp_path / "a" / "c.yaml")).jobs
    assert [j.id for j in again] == [j.id for j in jobs]
    # the same file elsewhere, with the model beside it at the same relative place: the same ids
    (tmp_path / "b").mkdir()
    moved = (tmp_path / "b" / "c.yaml")
    moved.write_text(SWEEP.replace(str(CRUISE), "../Cruise.gen"))
    (tmp_path / "Cruise.gen").write_text(CRUISE.read_text())
    relative = tmp_path / "a" / "r.yaml"
    relative.write_text(SWEEP.replace(str(CRUISE), "../Cruise.gen"))
    assert [j.id for j in expand(read_campaign(moved)).jobs] == [j.id for j in expand(read_campaign(relative)).jobs]


def test_deadlock_freedom_in_a_property_file_is_the_deadlock_check_s_job_compositionally():
    jobs = expand(read_campaign(DALA / "campaign.yaml")).jobs
    dala = [j for j in jobs if j.model == "dala"]
    assert [j.target for j in dala].count("deadlock freedom") == 1
    assert len([j for j in dala if j.check == "property"]) == 13  # NDD.mcl's 4 others and rules.mcl's 9
    assert len(jobs) == 5 + 1 + 13 + 1 + 7 + 4  # the timed level: time-locks, six periods, a latency; 1 to 4 cores


@pytest.mark.parametrize("axis, value, verdict", [
    ("define.PERIOD", 10, "violated"), ("define.PERIOD", 15, "holds"),
    ("period.Cruise.loop", "15 ms", "holds"), ("wcet-scale", 0.5, "holds"), ("wcet-scale", 1, "violated"),
])
def test_a_sweep_point_is_the_model_built_with_its_value(tmp_path, axis, value, verdict):
    """Cruise's codels take up to 12 ms in a period of 10 ms: a longer period, or WCETs halved, leave no overrun."""
    path = tmp_path / "c.yaml"
    path.write_text(f"models:\n  cruise: {{paths: [{CRUISE}], timed: true}}\nvary: {{{axis}: [{value}]}}\n"
                    "checks: [{check: observer, model: cruise, kinds: [overrun]}]\n")
    (job,) = expand(read_campaign(path)).jobs
    record = run_job(job)
    assert (record["status"], record["verdict"], record["target"]) == ("done", verdict, "Cruise.loop.overrun")
    assert record["point"] == {axis: value}
    assert record["result"]["trace"] is None if verdict == "holds" else record["result"]["trace"]["timed"]


def test_a_job_stopped_by_its_limit_is_recorded_as_inconclusive_with_the_limit(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text(f"models:\n  ndd: {{paths: [{DALA / 'NDD.gen'}]}}\n"
                    "checks: [{check: deadlock, model: ndd, options: {max-states: 100}}]\n")
    (job,) = expand(read_campaign(path)).jobs
    record = run_job(job)
    assert (record["status"], record["verdict"], record["limit"]) == ("done", "inconclusive", "max-states")
    assert record["options"] == {"max_states": 100} and record["figures"]["states"] <= 101
