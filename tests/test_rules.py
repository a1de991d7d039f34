"""Rules between services: the rule file's errors, each rule kind in the model, and the default rule file."""
from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from genom2bip.build import build_package
from genom2bip.cli import main
from genom2bip.parser import parse_paths
from genom2bip.rules import all_rules
from genomkit import engine_for, labels, places, walk
from runtime.diagnostics import Reporter

ROOT = Path(__file__).resolve().parents[1]
ARM = ROOT / "tests/fixtures/rules/arm.gen"


@pytest.fixture(scope="module")
def description():
    return parse_paths([ARM])


def rules_from(tmp_path, description, text: str):
    path = tmp_path / "rules.yaml"
    path.write_text(textwrap.dedent(text))
    reporter = Reporter()
    rules = all_rules(description, path, reporter)
    return rules, reporter, path


def errors(tmp_path, description, text):
    _, reporter, path = rules_from(tmp_path, description, text)
    return [(d.span.line, d.span.column, d.message) for d in reporter.diagnostics if d.severity == "error"], path


# --------------------------------------------------------------------------- bad rule files


@pytest.mark.parametrize("text,line,col,message", [
    ("rules:\n  - id: r\n    service: Bse.Track\n    requires: [Base.Localise]\n",
     3, 14, "rule r: unknown module 'Bse'"),
    ("rules:\n  - id: r\n    service: Arm.Move\n    requires: [Base.Localize]\n",
     4, 16, "rule r: module Base has no service 'Localize'"),
    ("rules:\n  - id: r\n    service: Arm.Move\n    requries: [Base.Localise]\n",
     4, 5, "rule #1: unknown key 'requries'"),
    ("rules:\n  - service: Arm.Move\n    requires: [Base.Localise]\n",
     2, 5, "rule #1 has no 'id'"),
    ("rules:\n  - id: r\n    service: Arm.Move\n    requires: Base\n",
     4, 15, "rule r: 'Base' is not Module.Service"),
    ("rules:\n  - id: r\n    service: Arm.Move\n    requires: [Base.Localise]\n    on_violation: later\n",
     5, 19, "rule r: on_violation is 'later'; expected reject or wait"),
    ("rules:\n  - id: r\n    service: Arm.Move\n    requires_running: [Base.Track]\n    completed: latest\n",
     5, 16, "rule r: 'completed' does not apply to this kind of rule"),
    ("rules:\n  - id: r\n    service: Arm.Move\n    requires: [Base.Localise]\n    interrupts: [Base.Track]\n",
     5, 5, "rule r: give exactly one of requires, requires_running, forbidden_while, before, interrupts, "
           "exclusive (found requires, interrupts)"),
    ("rules:\n  - id: r\n    service: Arm.Move\n",
     2, 5, "rule r: give exactly one of requires, requires_running, forbidden_while, before, interrupts, exclusive"),
    ("rules:\n  - id: r\n    service: Arm.Move\n    requires: [Arm.Move]\n",
     4, 15, "rule r: Arm.Move names itself in 'requires'"),
    ("rules:\n  - id: r\n    exclusive: [Arm.Move]\n",
     3, 16, "rule r: 'exclusive' needs at least two different services"),
    ("rules:\n  - id: r\n    service: Arm.Move\n    exclusive: [Arm.Move, Arm.Park]\n",
     3, 5, "rule r: 'exclusive' takes its services in its own list"),
    ("rules:\n  - id: r\n    requires: [Arm.Move]\n",
     2, 5, "rule r has no 'service' (the service the rule constrains)"),
    ("rules:\n  - id: r\n    service: Arm.Move\n    requires: []\n",
     4, 15, "rule r: 'requires' names no service"),
    ("rules: [unclosed\n", 2, 1, "not valid YAML: expected ',' or ']', but got '<stream end>'"),
    ("- id: r\n", 1, 1, "a rule file is a mapping with a 'rules' list"),
    ("rule:\n  - id: r\n", 1, 1, "unknown top-level key 'rule'"),
    ("rules:\n  - just a string\n", 2, 5, "rule #1 must be a mapping of keys (id, service, requires...)"),
])
def test_each_problem_is_named_with_its_location(tmp_path, description, text, line, col, message):
    found, _ = errors(tmp_path, description, text)
    assert (line, col, message) in found, found


def test_unknown_names_come_with_a_suggestion(tmp_path, description):
    _, reporter, _ = rules_from(tmp_path, description, "rules:\n  - id: r\n    service: Arm.Mvoe\n"
                                                        "    requires: [Base.Localise]\n")
    assert reporter.diagnostics[0].hint == "did you mean 'Move'?"


def test_duplicate_ids_point_at_the_second_and_name_the_first(tmp_path, description):
    found, path = errors(tmp_path, description, """\
        rules:
          - id: same
            service: Arm.Move
            requires: [Base.Localise]
          - id: same
            service: Arm.Park
            requires: [Base.Localise]
        """)
    assert found == [(5, 9, "duplicate rule id 'same'")]


def test_a_cycle_of_requirements_is_reported_with_its_rules(tmp_path, description):
    found, _ = errors(tmp_path, description, """\
        rules:
          - id: a
            service: Arm.Move
            requires: [Base.Track]
          - id: b
            service: Base.Track
            requires_running: [Arm.Move]
        """)
    assert found == [(2, 9, "rules a, b form a cycle of requirements that can never be satisfied: "
                            "Arm.Move -> Base.Track -> Arm.Move")]


def test_a_rule_contradicting_another_is_reported(tmp_path, description):
    found, _ = errors(tmp_path, description, """\
        rules:
          - id: needs
            service: Arm.Move
            requires_running: [Base.Track]
          - id: never
            service: Arm.Move
            forbidden_while: [Base.Track]
        """)
    assert found == [(2, 9, "rule needs contradicts never (rules): Arm.Move could never start")]


def test_a_rule_contradicting_the_description_is_reported(tmp_path):
    gen = tmp_path / "m.gen"
    gen.write_text("component M {\n  task t { period 10 ms; };\n"
                   "  activity A() { task t; before B; codel <start> a() yield ether; };\n"
                   "  activity B() { task t; codel <start> b() yield ether; };\n};\n")
    found, _ = errors(tmp_path, parse_paths([gen]), "rules:\n  - id: r\n    service: M.A\n    requires: [M.B]\n")
    assert found == [(2, 9, "rule r contradicts M.A.before (description): M.A could never start")]


def test_a_bad_rule_file_writes_nothing(tmp_path, capsys):
    rules = tmp_path / "rules.yaml"
    rules.write_text("rules:\n  - id: r\n    service: Arm.Move\n    requires: [Base.Nope]\n")
    out = tmp_path / "out"
    assert main([str(ARM), "--rules", str(rules), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"{rules}:4:16: error: rule r: module Base has no service 'Nope'" in err
    assert "    requires: [Base.Nope]" in err and "^^^^^^^^^" in err
    assert not out.exists()


def test_missing_rule_file_is_an_error(tmp_path, capsys):
    assert main([str(ARM), "--rules", str(tmp_path / "none.yaml"), "-o", str(tmp_path / "out")]) == 1
    assert "none.yaml: no such rule file" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


# --------------------------------------------------------------------------- each kind in the model


def built(tmp_path, description, text):
    rules, reporter, _ = rules_from(tmp_path, description, text)
    assert not reporter.has_errors, [d.message for d in reporter.diagnostics]
    package = build_package(description, "arm", rules)
    return engine_for(package, "ARM()")


def test_requires_refuses_until_the_other_has_completed_once(tmp_path, description):
    engine, _ = built(tmp_path, description, """\
        rules:
          - id: localised
            service: Arm.Move
            requires: [Base.Localise]
        """)
    s = engine.initial_state()
    assert "Arm.Move:refuse" in labels(engine, s) and "Arm.Move:trigger" not in labels(engine, s)
    refusal = engine.find(s, "Arm.Move:refuse")
    assert any(a.name == "rule" and a.arguments == {"name": "localised"}
               for a in next(c for c in engine.flat.connectors if c.path == refusal.connector).instance.annotations)
    s = walk(engine, s, "Base.Localise:trigger", "Base.Localise:start", "Base.servo:period",
             "Base.Localise:exec_start", "Base.Localise:finish")
    assert "Arm.Move:trigger" in labels(engine, s) and "Arm.Move:refuse" not in labels(engine, s)


def test_requires_latest_looks_at_the_last_run_only(tmp_path, description):
    engine, codels = built(tmp_path, description, """\
        rules:
          - id: localised
            service: Arm.Move
            requires: [Base.Localise]
            completed: latest
        """)
    s = walk(engine, engine.initial_state(), "Base.Localise:trigger", "Base.Localise:start", "Base.servo:period",
             "Base.Localise:exec_start", "Base.Localise:finish")
    assert "Arm.Move:trigger" in labels(engine, s)
    codels.next["loc_start"] = -1  # the next localisation fails
    s = walk(engine, s, "Base.Localise:trigger", "Base.Localise:start", "Base.Localise:exec_start",
             "Base.Localise:fail")
    assert "Arm.Move:refuse" in labels(engine, s) and "Arm.Move:trigger" not in labels(engine, s)


def test_requires_running_and_wait_hold_the_request_without_refusing(tmp_path, description):
    engine, _ = built(tmp_path, description, """\
        rules:
          - id: tracking
            service: Arm.Move
            requires_running: [Base.Track]
            on_violation: wait
        """)
    s = engine.initial_state()
    assert not {"Arm.Move:trigger", "Arm.Move:refuse"} & set(labels(engine, s))
    trigger = next(c for c in engine.flat.connectors if c.label == "Arm.Move:trigger")
    assert [(a.name, a.arguments) for a in trigger.instance.annotations if a.name == "wait"] == [
        ("wait", {"rules": "tracking"})]
    s = walk(engine, s, "Base.Track:trigger")
    assert "Arm.Move:trigger" in labels(engine, s)  # running from the moment it was accepted


def test_exclusive_services_are_never_accepted_together(tmp_path, description):
    engine, _ = built(tmp_path, description, """\
        rules:
          - id: one-at-a-time
            exclusive: [Arm.Move, Base.Track]
            on_violation: wait
        """)
    s = walk(engine, engine.initial_state(), "Arm.Move:trigger")
    assert "Base.Track:trigger" not in labels(engine, s)
    s = walk(engine, s, "Arm.Move:start", "Arm.motion:period", "Arm.Move:exec_start")
    s = engine.fire(s, engine.find(s, "Arm.Move:exec_go"))  # pause::go
    assert "Base.Track:trigger" not in labels(engine, s)
    # Explore everything reachable in a few steps: never both running.
    frontier, seen = [engine.initial_state()], set()
    for _ in range(12):
        nxt = []
        for state in frontier:
            for _, t in engine.successors(state):
                if t not in seen:
                    seen.add(t)
                    nxt.append(t)
                    d = engine.describe_state(t)
                    assert not (d["Arm.Move.control"]["data"]["running"] and d["Base.Track.control"]["data"]["running"])
        frontier = nxt


def test_interrupts_across_modules(tmp_path, description):
    engine, _ = built(tmp_path, description, """\
        rules:
          - id: halt-stops-arm
            service: Base.Halt
            interrupts: [Arm.Move]
        """)
    s = walk(engine, engine.initial_state(), "Arm.Move:trigger", "Arm.Move:start", "Arm.motion:period",
             "Arm.Move:exec_start", "Base.Halt:trigger")
    assert "Arm.Move:exec_go" not in labels(engine, s), "the interruption comes first (priority)"
    start = engine.find(s, "Base.Halt:start")
    assert "Arm.Move.activity.abort" in start.ports
    s = engine.fire(s, start)
    assert places(engine, s, "Arm.Move.activity") == ["STOP"]
    s = walk(engine, s, "Arm.Move:exec_stop", "Arm.Move:interrupted")
    assert places(engine, s, "Arm.Move.control") == ["IDLE"]


# --------------------------------------------------------------------------- the default rule file


def test_rules_yaml_next_to_the_descriptions_is_used_by_default(tmp_path, capsys):
    import shutil

    src = tmp_path / "robot"
    src.mkdir()
    shutil.copy(ARM, src / "arm.gen")
    (src / "rules.yaml").write_text("rules:\n  - id: localised\n    service: Arm.Move\n"
                                    "    requires: [Base.Localise]\n")
    assert main([str(src), "-o", str(tmp_path / "out")]) == 0
    bip = (tmp_path / "out" / "robot" / "robot.bip").read_text()
    assert "@rule(name=localised)" in bip
    assert "// rule localised: refuse the request unless Arm.Move only after Base.Localise completed" in bip


def test_dala_rules_are_in_the_generated_model():
    bip = (ROOT / "gen/dala/dala.bip").read_text()
    for rule in ("goto-after-pom-run", "goto-needs-laser-and-map"):
        assert f'@rule(name="{rule}")' in bip  # quoted: not an identifier
    assert '@wait(rules="goto-waits-for-base")' in bip
    # RFLEX's Stop (with the TrackSpeed it interrupts at home) aborts NDD's GoTo too: one port of each module
    assert "connector Triggered_1_1 RFLEX_Stop_start(RFLEX.Stop_start, NDD.GoTo_RFLEX_Stop_start)" in bip
    assert "connector TriggeredX_1_1 Stop_start(Stop.start, TrackSpeed.Stop_start)" in bip
    assert "connector BroadcastX_2 RFLEX_Stop_start(activity.abort, control.cancel)" in bip


def test_a_single_description_file_does_not_pick_up_the_rule_file_beside_it(tmp_path):
    import shutil

    src = tmp_path / "robot"
    src.mkdir()
    shutil.copy(ARM, src / "arm.gen")
    (src / "rules.yaml").write_text("rules:\n  - id: names-another-module\n    service: Other.X\n"
                                    "    requires: [Base.Localise]\n")
    assert main([str(src / "arm.gen"), "-o", str(tmp_path / "one")]) == 0
    assert main([str(src), "--no-rules", "-o", str(tmp_path / "none")]) == 0
    assert "@rule" not in (tmp_path / "none" / "robot" / "robot.bip").read_text()
    assert main([str(src), "-o", str(tmp_path / "all")]) == 1  # the directory's rule file is read, and wrong
    assert not (tmp_path / "all").exists()


def test_a_binary_rule_file_is_located_and_writes_nothing(tmp_path, capsys):
    rules = tmp_path / "rules.yaml"
    rules.write_bytes(b"rules:\n  - id: r\xff\xfe\x00\n")
    out = tmp_path / "out"
    assert main([str(ARM), "--rules", str(rules), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"{rules}:2:10: error: not a UTF-8 text file: byte 0xff cannot be read" in err
    assert "      - id: r\ufffd\ufffd?\n             ^\n" in err and "save it as UTF-8 text" in err
    assert "internal error" not in err
    assert not out.exists()


def test_a_rule_file_nested_without_bound_is_located_not_an_internal_error(tmp_path, capsys):
    rules = tmp_path / "rules.yaml"
    rules.write_text("rules:\n  - id: r\n    service: Arm.Move\n    requires: " + "[" * 5000 + "]" * 5000 + "\n")
    out = tmp_path / "out"
    assert main([str(ARM), "--rules", str(rules), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"{rules}:4:62: error: nested more than 50 levels deep: not a rule file\n")
    assert "internal error" not in err
    assert not out.exists()
