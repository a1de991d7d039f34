"""Description lines travel from the IR to the BIP model, its .bip text, traces and model errors."""
from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

from runtime.bip2 import parse_text
from runtime.explore import StateSpace, explore
from runtime.model import source_annotation, source_of
from runtime.diagnostics import NOWHERE, Span
from tests.verifykit import FIXTURES, NDD, NDD_NO_AFTER, ndd_model

from genom2bip.back.bip2 import write_package
from genom2bip.cli import main

ROOT = Path(__file__).resolve().parents[1]


def _line(at: str) -> str:
    """The text of the description line ``file:line:column`` names."""
    file, line, _ = at.rsplit(":", 2)
    return (ROOT / file if not Path(file).is_absolute() else Path(file)).read_text().splitlines()[int(line) - 1]


def test_source_annotation_round_trip():
    assert source_annotation(NOWHERE) == []
    [a] = source_annotation(Span("x/m.gen", 12, 5))
    assert (a.name, a.arguments) == ("source", {"file": "x/m.gen", "line": "12", "column": "5"})
    assert source_of([a]) == "x/m.gen:12:5"
    assert source_of([]) is None


def test_atoms_transitions_and_connectors_name_their_description_line():
    package, _ = ndd_model(str(NDD))
    activity = package.atom_type("NDD_GoTo_Activity")
    assert "activity GoTo(" in _line(source_of(activity.annotations))
    plan = next(t for t in activity.transitions if t.port == "exec_plan")
    assert "codel <plan> nddPlan(" in _line(source_of(plan.annotations))
    control = package.atom_type("NDD_GoTo_Control")
    trigger = next(t for t in control.transitions if t.port == "trigger")
    assert "nddCheckGoal" in _line(source_of(trigger.annotations))  # the validate codel runs on trigger
    connectors = [c for ct in package.compound_types for c in ct.connectors]
    labelled = {a.arguments["name"]: c for c in connectors for a in c.annotations if a.name == "label"}
    assert "nddPlan" in _line(source_of(labelled["NDD.GoTo:exec_plan"].annotations))
    assert "task motion" in _line(source_of(labelled["NDD.motion:period"].annotations))


def test_bip_text_carries_source_annotations_that_read_back():
    package, _ = ndd_model(str(NDD))
    text = write_package(package)
    assert re.search(r'@source\(file="[^"]*NDD\.gen", line="\d+", column="\d+"\)\n\s+on exec_plan from PLAN', text)
    again = parse_text(text, "ndd.bip")
    assert again.atom_type("NDD_GoTo_Activity").annotations == package.atom_type("NDD_GoTo_Activity").annotations


def test_counterexample_steps_name_the_service_line(capsys):
    prop = str(FIXTURES / "goto_after_setspeed.mcl")
    code = main(["verify", str(NDD_NO_AFTER), "--no-rules", "--property", prop])
    out = capsys.readouterr().out
    assert code == 4
    step = re.search(r"1  NDD\.GoTo:trigger  \[nddCheckGoal -> ok\]    \((\S+NDD\.gen:\d+:\d+)\)", out)
    assert step, out
    assert "activity GoTo(" in _line(step.group(1))


def test_model_error_at_run_time_names_the_description_line():
    """Two outcome transitions made to overlap: the non-determinism names the yields' lines."""
    package, root = ndd_model(str(NDD))
    activity = package.atom_type("NDD_GoTo_Activity")
    outcomes = [t for t in activity.transitions if t.internal and t.sources == ["PLAN_YIELD"]]
    first, second = outcomes[0], outcomes[1]
    activity.transitions[activity.transitions.index(second)] = replace(second, guard=first.guard)
    try:
        result = explore(StateSpace(package, root))
    finally:
        ndd_model.cache_clear()  # the shared, cached model was changed
    assert result.error is not None
    message = result.error.message
    assert "non-determinism" in message
    sources = re.findall(r"from PLAN_YIELD to \w+ \(from (\S+NDD\.gen:\d+:\d+)\)", message)
    assert len(sources) >= 2, message
    assert all("yield" in _line(s) or "nddPlan" in _line(s) for s in sources)


def _break_exec_plan(package) -> None:
    """Make the connector of NDD.GoTo:exec_plan name a port its component does not export."""
    from runtime.model import PortRef

    for ct in package.compound_types:
        for c in ct.connectors:
            if {"name": "NDD.GoTo:exec_plan"} in [a.arguments for a in c.annotations if a.name == "label"]:
                c.ports[1] = PortRef(c.ports[1].component, "no_such_port")


def _refusal(monkeypatch, spoil) -> str:
    """The message that refuses NDD's model once ``spoil`` has broken the package the builder made."""
    import genom2bip.generate as generate
    from genom2bip.parser import parse_paths

    build = generate.FunctionalLevel.build

    def broken(self):
        package = build(self)
        spoil(package)
        return package

    monkeypatch.setattr(generate.FunctionalLevel, "build", broken)
    try:
        generate.model_of(parse_paths([str(NDD)]), "NDD")
    except generate.GenerateError as exc:
        return str(exc)
    raise AssertionError("the broken model was accepted")


def test_a_refused_connector_of_a_generated_model_names_its_codel_line(monkeypatch):
    message = _refusal(monkeypatch, _break_exec_plan)
    found = re.search(r"^  (\S+NDD\.gen:\d+:\d+): component 'GoTo' .* exports no port 'no_such_port'$", message, re.M)
    assert found, message
    assert "codel <plan> nddPlan(" in _line(found.group(1))


def test_every_element_of_generated_dala_built_from_the_description_names_its_line():
    """Atoms, transitions and connectors (split sub-connectors too) carry ``@source``; the library's do not."""
    from genom2bip.generate import model_of
    from genom2bip.parser import parse_paths

    package, _, _ = model_of(parse_paths([str(ROOT / "descriptions" / "dala")]), "dala")
    # one type for every task or poster: no description line of its own (IdleScheduler: a task that runs no codel)
    library = {"Timer", "Scheduler", "IdleScheduler", "Poster"}
    unlocated = {("atom", a.name) for a in package.atom_types if source_of(a.annotations) is None}
    unlocated |= {("transition", a.name) for a in package.atom_types for t in a.transitions
                  if source_of(t.annotations) is None}
    unlocated |= {("connector", f"{ct.name}.{c.name}") for ct in package.compound_types for c in ct.connectors
                  if source_of(c.annotations) is None}
    assert unlocated == {(kind, name) for name in library for kind in ("atom", "transition")}
    for a in package.atom_types:
        for where in [source_of(a.annotations)] + [source_of(t.annotations) for t in a.transitions]:
            assert a.name in library or Path(where.rsplit(":", 2)[0]).name.endswith(".gen")
    # a connector split so that it binds each component once: its sub-connectors name the same line as the whole
    connectors = {f"{ct.name}.{c.name}": c for ct in package.compound_types for c in ct.connectors}
    sub = connectors["NDD_motion_Task.period"]
    assert "task motion" in _line(source_of(sub.annotations))
    assert sub.type.startswith("TriggeredX") and not any(a.name == "label" for a in sub.annotations)
    whole = next(c for c in connectors.values() if {"name": "NDD.motion:period"} in
                 [a.arguments for a in c.annotations if a.name == "label"])
    assert source_of(whole.annotations) == source_of(sub.annotations)
    # GenoM's own control task and the request acceptor are the component's; each acceptance is its service's
    control = next(c for c in connectors.values() if {"name": "NDD.control:period"} in
                   [a.arguments for a in c.annotations if a.name == "label"])
    assert "component NDD" in _line(source_of(control.annotations))
    take = next(t for t in package.atom_type("NDD_Requests").transitions if t.port == "GoTo")
    assert "activity GoTo(" in _line(source_of(take.annotations))


def test_a_refused_split_sub_connector_names_the_line_of_the_connector_it_was_split_from(monkeypatch):
    from runtime.model import PortRef

    def spoil(package):
        task = next(ct for ct in package.compound_types if ct.name == "NDD_motion_Task")
        sub = next(c for c in task.connectors if c.name == "period")  # unlabelled: a part of NDD.motion:period
        assert not any(a.name == "label" for a in sub.annotations)
        sub.ports[0] = PortRef(sub.ports[0].component, "no_such_port")

    message = _refusal(monkeypatch, spoil)
    found = re.search(r"^  (\S+NDD\.gen:\d+:\d+): component 'timer' \(atom type Timer\) has no port 'no_such_port'$",
                      message, re.M)
    assert found, message
    assert "task motion" in _line(found.group(1))
