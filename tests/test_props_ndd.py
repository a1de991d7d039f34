"""The paper's results on the generated NDD module (Basu et al., IV-C), and the mutation that breaks them."""
import pytest

from runtime.codels import any_request, codel_specs
from runtime.engine import Engine, flatten
from runtime.explore import StateSpace, explore
from runtime.props import check, read_property_file
from tests.verifykit import FIXTURES, NDD_NO_AFTER, ndd_model

PROPERTIES = FIXTURES / "goto_after_setspeed.mcl"


@pytest.fixture(scope="module")
def ndd():
    pkg, root = ndd_model()
    items, warnings = read_property_file(PROPERTIES, flatten(pkg, root))
    assert warnings == []
    return pkg, root, items


@pytest.fixture(scope="module")
def mutated():
    pkg, root = ndd_model(str(NDD_NO_AFTER))
    items, _ = read_property_file(PROPERTIES, flatten(pkg, root))
    return pkg, root, items


def test_ndd_has_no_reachable_deadlock():
    pkg, root = ndd_model()
    result = explore(StateSpace(pkg, root))
    assert result.complete and result.deadlocks == [] and result.error is None
    assert result.states == 125_440


def test_goto_is_triggered_only_after_setspeed_finished(ndd):
    pkg, root, items = ndd
    space = StateSpace(pkg, root, keep_edges=True)
    verdicts = {item.name: check(space, item) for item in items}
    assert verdicts["goto_after_setspeed"].holds is True
    assert verdicts["goto_after_setspeed_mcl"].holds is True
    # the paper's formula: a possibility, shown by a witness
    paper = verdicts["paper"]
    assert paper.holds is True and [s.label for s in paper.trace] == [
        "NDD.SetSpeed:trigger", "NDD.SetSpeed:start", "NDD.SetSpeed:finish"]


def test_without_the_after_constraint_it_is_violated(mutated):
    pkg, root, items = mutated
    space = StateSpace(pkg, root, keep_edges=True)
    v = check(space, items[0])
    assert v.holds is False and v.evidence == "counterexample"
    assert [s.label for s in v.trace] == ["NDD.GoTo:trigger"]


def replay(pkg, root, trace):
    """Run a fresh engine along the trace, each codel answering what the trace says; return the labels fired."""
    answers: list[int] = []
    externs = dict(any_request())
    for name in codel_specs(pkg):
        externs[name] = lambda: answers.pop(0)
    engine = Engine(pkg, root, externs)
    state = engine.initial_state()
    fired = []
    for step in trace:
        answers[:] = [pos for _, pos in step.outcomes]
        inter = engine.find(state, step.label)
        state = engine.fire(state, inter)
        assert answers == [], f"codel answers left over after {step.label}"
        fired.append(inter.label)
    return fired, engine, state


def test_the_counterexample_is_a_real_path(mutated):
    pkg, root, items = mutated
    space = StateSpace(pkg, root, keep_edges=True)
    v = check(space, items[1])  # the regular-formula version
    assert v.holds is False
    fired, engine, state = replay(pkg, root, v.trace)
    assert fired == ["NDD.GoTo:trigger"]
    places = engine.describe_state(state)
    assert places["NDD.GoTo.control"]["places"] == ["CHECK"]
    assert places["NDD.SetSpeed.control"]["data"]["done"] is False


def test_a_longer_counterexample_replays_with_its_codel_outcomes(ndd):
    pkg, root, _ = ndd
    from runtime.props import read_property_text
    item = read_property_text('never "GoTo:exec_plan" . "GoTo:fail"', flatten(pkg, root))
    space = StateSpace(pkg, root, keep_edges=True)
    v = check(space, item)
    assert v.holds is False
    fired, _, _ = replay(pkg, root, v.trace)
    assert fired[-2:] == ["NDD.GoTo:exec_plan", "NDD.GoTo:fail"]
    plan = v.trace[-2]
    assert plan.outcome_names[0].startswith("nddPlan -> throw NDD::")
