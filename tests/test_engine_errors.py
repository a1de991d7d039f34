"""Model errors raised by the step, named by atom, port, places and transitions; bad roots and structures."""
import pytest
from enginekit import engine, labels, walk

from runtime.engine import Engine, ExternError, FlattenError, ModelError, first
from runtime.model import (
    AtomType, ComponentInstance, CompoundType, ConnectorInstance, ConnectorParam, ConnectorType, DefineGroup,
    DefinePort, InitialTransition, Package, PortDecl, PortRef, PortType, Transition,
)


def test_non_determinism_on_one_port():
    e = engine("Errors", "Nondet()")
    s = e.initial_state()
    assert labels(e, s) == ["n.p", "n.inc"]       # x = 0: only the second transition on p
    s = walk(e, "n.inc", state=s)                 # x = 1: both
    with pytest.raises(ModelError) as info:
        e.enabled(s)
    err = info.value
    assert (err.atom, err.port) == ("n", "p")
    assert len(err.transitions) == 2 and all(t.startswith("on p from s to s") for t in err.transitions)
    assert "non-determinism" in str(err)


def test_two_internal_transitions():
    e = engine("Errors", "Internal()")
    s = e.initial_state()
    with pytest.raises(ModelError) as info:
        e.fire(s, e.find(s, "i.go"))
    err = info.value
    assert err.atom == "i"
    assert [t.split(" (")[0] for t in err.transitions] == ["internal from b to c", "internal from b to d"]


def test_one_safety():
    e = engine("Errors", "OneSafe()")
    s = e.initial_state()
    with pytest.raises(ModelError) as info:
        e.fire(s, e.find(s, "u.t"))
    err = info.value
    assert (err.atom, err.port, err.places) == ("u", "t", ("b",))
    assert "1-safety" in str(err)


def test_internal_livelock_is_reported():
    e = engine("Errors", "Loop()")
    with pytest.raises(ModelError, match="livelock"):
        walk(e, "l.go")


def test_model_error_ends_a_run_with_its_message():
    e = engine("Errors", "Nondet()")
    summary = e.run(lambda s, en: en[-1])          # n.inc first, then both p transitions
    assert summary.outcome == "error" and summary.steps == 1
    assert "atom n" in summary.message and "port p" in summary.message
    assert summary.line().startswith("1 step, model error: non-determinism")


def test_atom_priority_cycles():
    with pytest.raises(ModelError, match=r"priority cycle between ports a, b.*atom c"):
        engine("AtomPriorities", "Cycle()")      # static: no guard
    e = engine("AtomPriorities", "GuardedCycle()")
    s = e.initial_state()
    assert labels(e, s) == ["g.a"]
    s = walk(e, "g.a", state=s)                  # n = 1: a < b < a
    with pytest.raises(ModelError, match="priority cycle"):
        e.enabled(s)


def test_compound_priority_cycles():
    with pytest.raises(ModelError, match="priority cycle between compound priorities ab.*ba"):
        engine("Priorities", "Cycle()")
    e = engine("Priorities", "GuardedCycle()")
    s = walk(e, "b", "b")
    with pytest.raises(ModelError, match="priority cycle"):
        e.enabled(s)


def test_rules_on_one_connector_that_cannot_meet_are_no_cycle():
    e = engine("Priorities", "OneConnector()")
    s = e.initial_state()
    assert labels(e, s) == ["bc"]
    s = walk(e, "bc", "R1.work", state=s)           # R2 busy: bc[S.snd,R1.rcv] and bc[S.snd]; r1 keeps the larger
    assert labels(e, s) == ["bc[S.snd,R1.rcv]", "R2.work"]
    s = walk(e, "R2.work", "bc", "R2.work", state=s)  # R1 busy: bc[S.snd,R2.rcv] and bc[S.snd]
    assert labels(e, s) == ["bc[S.snd,R2.rcv]", "R1.work"]
    e = engine("Priorities", "StarBeside()")
    assert labels(e, e.initial_state()) == ["bc"]


def test_missing_extern_bindings_before_the_first_step():
    with pytest.raises(ExternError) as info:
        engine("Arith", "System()")
    assert info.value.missing == ("log", "twice")
    assert "log, twice" in str(info.value)
    with pytest.raises(ExternError, match="without a Python binding: log"):
        engine("Arith", "System()", {"twice": lambda x: x})
    with pytest.raises(ExternError, match="cannot import module"):
        engine("Arith", "System()", "no_such_module_here")


def test_extern_failure_and_division_by_zero_name_the_atom():
    e = engine("Arith", "System()", {"twice": lambda x: x / 0, "log": print})
    with pytest.raises(ModelError, match=r"extern function twice\(7,\) raised ZeroDivisionError.*atom c"):
        e.initial_state()
    e = engine("Arith", "DivZero()", {"twice": lambda x: x, "log": print})
    with pytest.raises(ModelError, match=r"integer division by zero \(in atom c \(Calc\)"):
        e.initial_state()


# -- bad roots and structures ----------------------------------------------------------------------

@pytest.mark.parametrize("root, message", [
    ("Nope()", "no compound or atom type named 'Nope'"),
    ("Table3(1)", "Table3 takes 0 argument(s) (), 1 given"),
    ("Table3(", "expected a type name and arguments"),
    ("Table3(x + 1)", "arguments must be constants"),
])
def test_bad_root(root, message):
    with pytest.raises(FlattenError, match=message.replace("(", r"\(").replace(")", r"\)")):
        engine("Dining", root)


def test_root_arguments_bind_parameters():
    with pytest.raises(FlattenError, match=r"System takes 3 argument\(s\) \(int i, int j, int k\), 2 given"):
        engine("NestedMax", "System(1, 2)")
    with pytest.raises(FlattenError, match="unknown name 'undefined_name'"):
        engine("NestedMax", "System(1, 2, undefined_name)")
    e = engine("NestedMax", "System(-4, -2, -3)")
    assert [st["data"]["x"] for st in e.describe_state(e.initial_state()).values()] == [-4, -2, -3]


def _tiny(ports_given, second_port="q"):
    port = PortType("P")
    a = AtomType("A", ports=[PortDecl("P", "p", exported=True), PortDecl("P", "q", exported=True)], places=["s"],
                 initial=InitialTransition(["s"]),
                 transitions=[Transition("p", ["s"], ["s"]), Transition("q", ["s"], ["s"])])
    rdv = ConnectorType("R", [ConnectorParam("P", "x"), ConnectorParam("P", "y")],
                        DefineGroup([DefinePort("x"), DefinePort("y")]))
    refs = [PortRef("a", "p"), PortRef("b", second_port), PortRef("a", "q")][:ports_given]
    top = CompoundType("System", components=[ComponentInstance("A", "a"), ComponentInstance("A", "b")],
                       connectors=[ConnectorInstance("R", "c", refs)])
    return Package("Tiny", port_types=[port], atom_types=[a], connector_types=[rdv], compound_types=[top])


def test_python_built_model_runs():
    e = Engine(_tiny(2))
    s = e.initial_state()
    assert labels(e, s) == ["c"]


def test_connector_arity_and_references_checked_without_the_reader():
    with pytest.raises(FlattenError, match=r"connector c of type R: 2 port\(s\) expected, 3 given"):
        Engine(_tiny(3))
    with pytest.raises(FlattenError, match="component b has no exported port 'zz'"):
        Engine(_tiny(2, "zz"))


def test_same_atom_twice_in_one_connector():
    pkg = _tiny(2)
    pkg.compound_types[0].connectors[0].ports = [PortRef("a", "p"), PortRef("a", "q")]
    with pytest.raises(FlattenError, match="atom a is reached through both parameters x and y"):
        Engine(pkg)


def test_run_never_raises_for_model_errors():
    e = engine("Errors", "OneSafe()")
    summary = e.run(first)
    assert summary.outcome == "error" and "places b" in summary.message
