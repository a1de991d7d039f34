"""The verification API: models from plain parameters, one function per check, results with a stable JSON form."""
from __future__ import annotations

import json
import pickle
import subprocess
import sys
from pathlib import Path

import pytest

from genom2bip.verify import (
    CheckResult, DeadlockResult, InputError, Listener, ObserverResult, PropertyResult, SearchOptions, TimeSettings,
    Trace, UsageError, Verdict, build_model, check_deadlock, check_deadlock_compositional, check_observer_localized,
    check_observers, check_property, explore, observers, read_properties, state_space,
)
from tests.nativekit import needs_cc

ROOT = Path(__file__).resolve().parents[1]
DALA = ROOT / "descriptions" / "dala"
NDD = DALA / "NDD.gen"
NDD_NO_AFTER = ROOT / "tests" / "fixtures" / "verify" / "ndd_no_after" / "NDD.gen"
DINING = ROOT / "tests" / "fixtures" / "verify" / "Dining.bip"
ERRORS = ROOT / "tests" / "fixtures" / "engine" / "Errors.bip"
PHILOSOPHERS = ROOT / "tests" / "fixtures" / "compositional" / "Philosophers.bip"
CRUISE = ROOT / "tests" / "fixtures" / "timed" / "Cruise.gen"
CRUISE_OBSERVERS = ROOT / "tests" / "fixtures" / "timed" / "observers.yaml"

#: The keys every result has in JSON, whatever the check.
COMMON = {"check", "subject", "verdict", "method", "limit", "message", "exhaustive", "figures", "trace", "notes",
          "details"}
FIGURES = {"states", "transitions", "seconds", "memory", "depth"}


class Recorder(Listener):
    """A listener that keeps what it hears."""

    def __init__(self) -> None:
        self.notes: list[str] = []
        self.progresses = 0

    def progress(self):
        self.progresses += 1
        return super().progress()

    def note(self, text: str) -> None:
        self.notes.append(text)


def as_json(result: CheckResult) -> dict:
    """The result's JSON form, checked to be plain JSON (it survives a round trip unchanged); the result itself
    pickles, as it must to come back from another process."""
    data = result.to_json()
    assert json.loads(json.dumps(data)) == data
    assert pickle.loads(pickle.dumps(result)).to_json() == data
    assert set(data) == COMMON and set(data["figures"]) == FIGURES
    return data


# --------------------------------------------------------------------------- building models


def test_a_directory_is_built_as_generate_builds_it_rules_included():
    from genom2bip.back.bip2 import write_package as write_bip
    from genom2bip.generate import model_of
    from genom2bip.parser import parse_paths
    from genom2bip.rules import all_rules
    from runtime.diagnostics import Reporter

    model = build_model([str(DALA)])
    description = parse_paths(sorted(str(p) for p in DALA.glob("*.gen")))
    package, root, _ = model_of(description, "dala", all_rules(description, DALA / "rules.yaml", Reporter()))
    assert (model.root, model.title) == (root, f"dala ({root})")
    assert write_bip(model.package) == write_bip(package)
    bare = build_model([str(DALA)], no_rules=True)
    assert write_bip(bare.package) != write_bip(package)  # the rule file's connectors are gone
    assert not model.timed and model.warnings == []


def test_defines_and_include_paths_are_plain_parameters(tmp_path):
    (tmp_path / "inc").mkdir()
    (tmp_path / "inc" / "extra.gen").write_text("attribute SetLimit(in limit);\n")
    (tmp_path / "m.gen").write_text(
        "component m {\n  ids { long limit; };\n  attribute GetLimit(out limit);\n#ifdef EXTRA\n"
        '#include "extra.gen"\n#endif\n};\n')
    plain = build_model([str(tmp_path / "m.gen")])
    extra = build_model([str(tmp_path / "m.gen")], defines={"EXTRA": "1"}, include_dirs=[str(tmp_path / "inc")])
    assert plain.title == "m (M())"
    names = {t.name for t in extra.package.atom_types} - {t.name for t in plain.package.atom_types}
    assert names and all("SetLimit" in n for n in names)


def test_time_settings_add_ticks_and_the_observer_file():
    untimed = build_model([str(CRUISE)])
    assert not untimed.timed and observers(untimed) == []
    periods = build_model([str(CRUISE)], time=TimeSettings())
    assert periods.timed and [a.kind for a in observers(periods)] == ["overrun"]
    both = build_model([str(CRUISE)], time=TimeSettings(observers=CRUISE_OBSERVERS, tick_us=1000))
    assert [(a.kind, a.bound) for a in observers(both)] == [("overrun", 10), ("latency", 16), ("latency", 2)]
    assert [a.kind for a in observers(both, ("latency",))] == ["latency", "latency"]


def test_bad_input_is_an_input_error_that_says_what_and_prints_nothing(tmp_path, capsys):
    with pytest.raises(InputError) as info:
        build_model([str(tmp_path / "nowhere.gen"), str(tmp_path)])
    assert info.value.messages == [f"{tmp_path / 'nowhere.gen'}: no such file or directory",
                                   f"{tmp_path}: no .gen file in this directory"]
    with pytest.raises(InputError, match="nosuch.yaml: no such rule file"):
        build_model([str(NDD)], rules=str(tmp_path / "nosuch.yaml"))
    with pytest.raises(InputError, match="nosuch.yaml: no such observer file"):
        build_model([str(CRUISE)], time=TimeSettings(observers=tmp_path / "nosuch.yaml"))
    with pytest.raises(UsageError, match="give either one .bip file or description files, not both"):
        build_model([str(NDD), str(DINING)])
    assert capsys.readouterr() == ("", "")
    assert list(tmp_path.iterdir()) == []


def test_diagnostics_travel_in_the_error_or_go_to_the_report_as_they_are_found(tmp_path, capsys):
    rules = tmp_path / "rules.yaml"
    rules.write_text("rules:\n  - id: r\n    service: NDD.GoTo\n    requires: [POM.Nope]\n")
    with pytest.raises(InputError) as info:
        build_model([str(NDD)], rules=rules)
    (group,) = info.value.groups
    assert group.diagnostics and all(d.span.file == str(rules) for d in group.diagnostics)
    assert f"{rules}:4:" in str(info.value)
    heard = []
    with pytest.raises(InputError) as info:
        build_model([str(NDD)], rules=rules, report=lambda diagnostics, sources: heard.append(list(diagnostics)))
    assert info.value.groups == [] and heard == [group.diagnostics]
    assert capsys.readouterr() == ("", "")


# --------------------------------------------------------------------------- deadlocks


@needs_cc
@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_a_deadlock_comes_with_its_shortest_trace_state_and_figures(engine):
    model = build_model([str(DINING)], root="Table2()")
    options = SearchOptions(engine=engine)
    found = check_deadlock(state_space(model, options), options)
    assert isinstance(found, DeadlockResult)
    assert (found.verdict, found.complete, found.shortest) == (Verdict.VIOLATED, True, True)
    assert (found.figures.states, found.figures.transitions) == (6, 8)  # the fixture's own count
    (deadlock,) = found.deadlocks
    assert sorted(s.label for s in deadlock.trace.steps) == ["left0", "left1"]
    assert "p0: ONE" in deadlock.text and "p0: ONE" in deadlock.moved
    assert found.trace is deadlock.trace
    data = as_json(found)
    assert (data["check"], data["verdict"], data["limit"]) == ("deadlock", "violated", None)
    assert data["trace"] == {"steps": [{"label": s.label, "outcomes": []} for s in deadlock.trace.steps],
                             "loop": None, "timed": False, "tick_us": None}
    assert set(data["details"]) == {"deadlocks", "complete", "shortest", "reported", "model_error"}
    assert data["details"]["deadlocks"][0]["state"] == deadlock.state


@needs_cc
def test_a_search_stopped_by_a_limit_is_inconclusive_and_names_the_limit():
    model = build_model([str(NDD)])
    options = SearchOptions(max_states=2000)
    found = check_deadlock(state_space(model, options), options)
    assert (found.verdict, found.limit, found.complete) == (Verdict.INCONCLUSIVE, "max-states", False)
    assert found.deadlocks == [] and found.trace is None and found.figures.states == 2000
    assert as_json(found)["limit"] == "max-states"
    deep = SearchOptions(max_depth=3, engine="python")
    assert check_deadlock(state_space(model, deep), deep).limit == "max-depth"


def test_a_model_error_is_an_error_verdict_with_its_trace():
    model = build_model([str(ERRORS)], root="Nondet()")
    options = SearchOptions(engine="python")
    found = check_deadlock(state_space(model, options), options)
    assert found.verdict is Verdict.ERROR and "non-determinism" in found.message
    assert found.model_error is not None and [s.label for s in found.model_error.trace.steps] == ["n.inc"]
    data = as_json(found)
    assert data["verdict"] == "error" and data["details"]["model_error"]["message"] == found.message


@needs_cc
def test_the_listener_hears_the_notes_that_the_result_keeps():
    model = build_model([str(DINING)], root="Table2()")
    heard = Recorder()
    options = SearchOptions(engine="python", por=True, workers=2)
    found = check_deadlock(state_space(model, options), options, heard)
    assert found.notes == heard.notes == [
        "no partial-order reduction in the Python explorer: every interleaving is explored",
        "the Python explorer runs on one thread over exact states (--workers and --store are the compiled "
        "explorer's)"]
    assert heard.progresses == 1
    silent = check_deadlock(state_space(model, options), options)  # no listener: the same result, notes kept
    assert silent.notes == found.notes and silent.verdict is found.verdict
    lts = explore(state_space(model, SearchOptions(), keep_edges=True), SearchOptions(), lts=True)
    assert lts.notes == ["LTS exports need every successor list: exploring with the Python step"]


# --------------------------------------------------------------------------- properties


@needs_cc
def test_properties_hold_or_are_violated_with_a_counterexample():
    model = build_model([str(NDD)])
    items, warnings = read_properties(model, [DALA / "properties" / "NDD.mcl"])
    options = SearchOptions()
    space = state_space(model, options, items)
    results = [check_property(space, item, options) for item in items]
    assert [(r.name, r.verdict) for r in results] == [(i.name, Verdict.HOLDS) for i in items]
    assert all(isinstance(r, PropertyResult) and r.figures.states > 0 for r in results)
    broken = build_model([str(NDD_NO_AFTER)])
    (item, _, paper), _ = read_properties(broken, [ROOT / "tests" / "fixtures" / "verify" / "goto_after_setspeed.mcl"])
    space = state_space(broken, options, [item, paper])
    found = check_property(space, item, options)
    assert (found.verdict, found.evidence, found.method) == (Verdict.VIOLATED, "counterexample",
                                                              "compiled observer search")
    assert found.trace.steps[-1].label == "NDD.GoTo:trigger"
    data = as_json(found)
    assert data["details"] == {"name": item.name, "evidence": "counterexample"}
    assert [s["label"] for s in data["trace"]["steps"]] == [s.label for s in found.trace.steps]
    witnessed = check_property(space, paper, options)  # a possibility: the Python checker, with a witness
    assert (witnessed.verdict, witnessed.evidence, witnessed.method) == (Verdict.HOLDS, "witness", "local fixed point")
    assert witnessed.trace.steps[-1].label == "NDD.SetSpeed:finish"
    assert witnessed.notes == ["property paper is checked with the Python step (the compiled search takes deadlock "
                               "freedom and [R] false / [R] {P} shapes, on models it compiles)"]


def test_a_lasso_keeps_its_loop_in_the_result_and_in_json():
    from genom2bip.verify.search import property_result
    from runtime.explore.space import Step
    from runtime.props import Verdict as RuntimeVerdict
    from runtime.props import read_property_text

    model = build_model([str(DINING)], root="Table2()")
    item = read_property_text("[true*] <true> true", model.flat)
    steps = [Step("left0", 0), Step("right0", 1), Step("release0", 2)]
    found = property_result(item, RuntimeVerdict(item.property, False, steps, "counterexample", 0, "local fixed point"))
    assert found.trace.loop == 0 and found.verdict is Verdict.VIOLATED
    assert as_json(found)["trace"]["loop"] == 0
    no_loop = property_result(item, RuntimeVerdict(item.property, False, steps, "counterexample"))
    assert no_loop.trace.loop is None


# --------------------------------------------------------------------------- timing observers


@needs_cc
def test_each_observer_has_its_result_with_a_timed_trace():
    model = build_model([str(CRUISE)], time=TimeSettings(observers=CRUISE_OBSERVERS))
    results = check_observers(model)
    assert all(isinstance(r, ObserverResult) for r in results)
    assert [(r.observer, r.kind, r.verdict) for r in results] == [
        ("Cruise.loop.overrun", "overrun", Verdict.VIOLATED), ("track_reacts", "latency", Verdict.HOLDS),
        ("command_quickly", "latency", Verdict.VIOLATED)]
    late = results[2]
    assert late.subject == "latency command_quickly (within 2 ms)" and late.bound_ms == 2.0
    ticks = late.trace.ticks
    assert len(ticks) == len(late.trace.steps) and ticks == sorted(ticks) and ticks[-1] > 0
    data = as_json(late)
    assert data["details"] == {"observer": "command_quickly", "kind": "latency", "bound_ticks": late.bound_ticks,
                               "bound_ms": 2.0}
    assert data["trace"]["timed"] and data["trace"]["tick_us"] == late.tick_us
    assert [s["time_ms"] for s in data["trace"]["steps"]] == [t * late.tick_us / 1000 for t in ticks]
    by_localization = check_observer_localized(model, observers(model)[2])
    assert by_localization.verdict is Verdict.VIOLATED and by_localization.method.startswith("localization")


# --------------------------------------------------------------------------- compositional


def test_the_compositional_analysis_returns_its_candidates():
    model = build_model([str(PHILOSOPHERS)])
    found = check_deadlock_compositional(model, SearchOptions(check_states=10_000))
    assert (found.verdict, found.method) == (Verdict.HOLDS, "compositional")
    assert found.potentials == len(found.refuted) + len(found.candidates)
    data = as_json(found)
    assert set(data["details"]) == {"potentials", "refuted", "candidates", "reused_traps", "listing_complete",
                                    "explored"}


# --------------------------------------------------------------------------- layering


def test_the_api_runs_without_the_command_line():
    code = (
        "import sys\n"
        "from genom2bip.verify import SearchOptions, build_model, check_deadlock, state_space\n"
        f"model = build_model([{str(DINING)!r}], root='Table2()')\n"
        "options = SearchOptions(engine='python')\n"
        "print(check_deadlock(state_space(model, options), options).verdict.value)\n"
        "print(sorted(m for m in sys.modules if m.startswith('genom2bip.cli')))\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines() == ["violated", "[]"]


def test_a_trace_without_steps_is_empty_json():
    assert Trace().to_json() == {"steps": [], "loop": None, "timed": False, "tick_us": None}
