"""``A only while "M.S" runs``: a service's run read from its events, a renewed request keeping it running."""
from __future__ import annotations

import pytest

from runtime.diagnostics import DiagnosticError
from runtime.engine import flatten
from runtime.explore import StateSpace
from runtime.native.properties import compiled_check
from runtime.props import read_properties
from tests.nativekit import needs_cc
from tests.verifykit import ndd_model

#: GoTo interrupts itself (a new goal replaces the running one) and NDD's Stop interrupts it.
RUNS = 'plans: "NDD.GoTo:exec_plan" only while "NDD.GoTo" runs;\n'
#: The same written with "since its last end": a renewed request's end reads as the end of the run.
SINCE_END = ("since_end: [ true* . 'NDD\\.GoTo:(finish|fail|interrupted)' . (not \"NDD.GoTo:trigger\")*\n"
             "            . \"NDD.GoTo:exec_plan\" ] false;\n")


def verdicts(text: str):
    pkg, root = ndd_model()
    items, _ = read_properties(text, "runs.mcl", flatten(pkg, root))
    return {i.name: (i, compiled_check(StateSpace(pkg, root, observed=i.observed), i)) for i in items}


@needs_cc
def test_goto_plans_only_while_it_runs_across_a_renewed_request():
    got = verdicts(RUNS + SINCE_END)
    item, runs = got["plans"]
    assert item.property.pattern == "only while"
    assert runs.holds is True, runs.note
    _, since = got["since_end"]
    assert since.holds is False
    labels = [s.label for s in since.trace]
    # the counterexample renews GoTo: a second trigger before the first request's end, then the new one plans
    first_end = next(k for k, lab in enumerate(labels)
                     if lab in ("NDD.GoTo:finish", "NDD.GoTo:fail", "NDD.GoTo:interrupted"))
    assert labels[:first_end].count("NDD.GoTo:trigger") == 2 and labels[-1] == "NDD.GoTo:exec_plan"


def test_the_shorthand_needs_the_model_for_what_interrupts_the_service():
    with pytest.raises(DiagnosticError) as info:
        read_properties(RUNS, "runs.mcl")
    (d,) = info.value.diagnostics
    assert str(d.span) == "runs.mcl:1:8"
    assert d.message == ('only while "NDD.GoTo" runs: what interrupts NDD.GoTo is read from a model; check this '
                         "property against one")


def test_a_service_the_model_does_not_have_is_an_error_where_it_is_named():
    pkg, root = ndd_model()
    with pytest.raises(DiagnosticError) as info:
        read_properties('ok: never "NDD.GoTo:fail";\nbad: "NDD.GoTo:trigger" only while "NDD.Fly" runs;\n',
                        "runs.mcl", flatten(pkg, root))
    assert [(str(d.span), d.message) for d in info.value.diagnostics] == [
        ("runs.mcl:2:6", 'only while "NDD.Fly" runs: the model has no service NDD.Fly (write it MODULE.SERVICE)')]


def test_the_shorthand_is_told_in_words_not_as_its_expansion():
    # Its formula repeats every event of the service several times: "means:" says what B is instead.
    from runtime.props.check import describe
    from runtime.props.formulas import show

    pkg, root = ndd_model()
    (item,), _ = read_properties(RUNS, "runs.mcl", flatten(pkg, root))
    text = describe(item)
    name, means = text.split("\n")
    assert name == 'plans: "NDD.GoTo:exec_plan" only while "NDD.GoTo" runs'
    assert means.startswith('  means: [B . "NDD.GoTo:exec_plan"] false, B a path after which "NDD.GoTo" does not run')
    assert "to its finish, fail or interrupted, or to " in means and "NDD.Stop:start" in means
    assert len(means) < len(show(item.property.formula))
