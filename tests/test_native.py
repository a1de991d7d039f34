"""The compiled step and search agree with the Python step: same successors, states, deadlocks, traces, errors."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest
from hypothesis import HealthCheck, given, settings

from runtime.bip2 import parse_text
from runtime.engine.errors import EngineError
from runtime.explore import StateSpace, explore
from runtime.native import compiled as native
from tests import enginekit, verifykit
from tests.nativekit import agree, compiled, models, needs_cc

pytestmark = needs_cc

ENGINE_CASES = [
    ("AtomPriorities", "System()"), ("AtomPriorities", "GuardedCycle()"), ("Broadcast", "System()"),
    ("Chain", "System()"), ("Dining", "Table3()"), ("Errors", "Nondet()"), ("Errors", "Internal()"),
    ("Errors", "OneSafe()"), ("Errors", "Loop()"), ("Hierarchy", "TwoSources()"), ("NestedAny", "Dangling()"),
    ("Priorities", "Low()"), ("Priorities", "High()"), ("Priorities", "Star()"), ("Priorities", "Nested()"),
    ("Priorities", "GuardedCycle()"),
]
VERIFY_CASES = [("Codel", "Main()"), ("Counters", "Pair()"), ("Dining", "Table2()"), ("Dining", "Table3()"),
                ("Server", "Main()")]


@pytest.mark.parametrize("name, root", ENGINE_CASES)
def test_same_successors_on_engine_fixtures(name, root):
    space = StateSpace(enginekit.package(name), root)
    assert agree(space, compiled(space)) >= 1


@pytest.mark.parametrize("name, root", VERIFY_CASES)
@pytest.mark.parametrize("reduce", [True, False])
def test_same_successors_on_verify_fixtures(name, root, reduce):
    space = StateSpace(verifykit.package(name), root, reduce=reduce)
    assert agree(space, compiled(space)) == len(space)


def same_search(space_args: tuple, **kw):
    python = StateSpace(*space_args, **kw)
    ours = explore(python)
    cs = compiled(StateSpace(*space_args, **kw))
    theirs = cs.explore()
    assert (theirs.states, theirs.transitions, theirs.depth, theirs.complete) == \
        (ours.states, ours.transitions, ours.depth, ours.complete)
    assert theirs.deadlocks == ours.deadlocks
    for sid in ours.deadlocks:
        assert [str(s) for s in cs.trace_to(sid)] == [str(s) for s in python.trace_to(sid)]
    return ours, theirs


@pytest.mark.parametrize("name, root", VERIFY_CASES)
def test_same_search_on_verify_fixtures(name, root):
    same_search((verifykit.package(name), root))


def test_ndd_has_125440_states_and_no_deadlock(shipped_c_level):
    # the level users get, on the whole search of the main model (the other tests build at -O0)
    pkg, root = verifykit.ndd_model()
    cs = compiled(StateSpace(pkg, root))
    result = cs.explore()
    assert (result.states, result.complete, result.deadlocks) == (125_440, True, [])
    assert result.transitions == 992_672


def test_ndd_agrees_state_by_state_with_a_request_budget():
    pkg, root = verifykit.ndd_model()
    space = StateSpace(pkg, root, requests=1)
    assert agree(space, compiled(space), limit=400) == 400


def test_depth_first_and_limits_agree():
    args = (verifykit.package("Dining"), "Table3()")
    for kw in ({"dfs": True}, {"max_depth": 2}, {"dfs": True, "max_depth": 2}):
        ours = explore(StateSpace(*args), **kw)
        theirs = compiled(StateSpace(*args)).explore(**kw)
        assert (theirs.states, theirs.transitions, theirs.stopped_by, theirs.deadlocks) == \
            (ours.states, ours.transitions, ours.stopped_by, ours.deadlocks)
    ours = explore(StateSpace(*args, max_states=5))
    theirs = compiled(StateSpace(*args)).explore(max_states=5)
    assert (theirs.states, theirs.transitions, theirs.stopped_by) == (ours.states, ours.transitions, "max-states")


@pytest.mark.parametrize("root", ["Nondet()", "OneSafe()", "Loop()"])
def test_model_errors_are_worded_by_the_engine_with_a_trace(root):
    pkg = enginekit.package("Errors")
    ours = explore(StateSpace(pkg, root))
    theirs = compiled(StateSpace(pkg, root)).explore()
    assert theirs.error is not None and ours.error is not None
    assert theirs.error.message == ours.error.message
    assert theirs.error.state == ours.error.state
    assert [str(s) for s in theirs.error.trace] == [str(s) for s in ours.error.trace]


DIVISION = """package Div
  port type Port()
  atom type A()
    data int x
    port Port dec()
    place s
    initial to s do { x = 2; }
    on dec from s to s do { x = 6 / (x - 1); }
  end
  compound type Main()
    component A a()
  end
end
"""


def test_division_by_zero_is_reported_at_its_state():
    ours = explore(verifykit.text_space(DIVISION))
    theirs = compiled(verifykit.text_space(DIVISION)).explore()
    assert "division by zero" in ours.error.message
    assert theirs.error.message == ours.error.message and theirs.error.state == ours.error.state == 2
    assert [s.label for s in theirs.error.trace] == ["a.dec", "a.dec"]


BIG = """package Big
  port type Port()
  atom type A()
    data int x
    port Port grow()
    place s
    initial to s do { x = 1; }
    on grow from s to s provided (x > 0) do { x = x * 1000; }
  end
  compound type Main()
    component A a()
  end
end
"""


def test_an_int_past_64_bits_gives_way_to_the_python_step():
    with pytest.raises(native.Diverged):
        compiled(verifykit.text_space(BIG)).explore()


PYTHON_EXTERN = """package Ext
  extern function int twice(const int)
  port type Port()
  atom type A()
    data int x
    export port Port p()
    place s
    initial to s
    on p from s to s do { x = twice(1); }
  end
  compound type Main()
    component A a()
  end
end
"""


def test_without_a_compiler_the_note_says_so(monkeypatch):
    monkeypatch.setenv("PATH", "")
    monkeypatch.delenv("CC", raising=False)
    cs, note = native.compile_space(verifykit.space("Dining", "Table2()"))
    assert cs is None and note.startswith("no C compiler on PATH")


def test_unsupported_models_say_why():
    cs, note = native.compile_space(verifykit.text_space(PYTHON_EXTERN, externs={"twice": lambda x: 2 * x}))
    assert cs is None and note == ("compiled exploration does not take this model (atom a (A), transition on p from s "
                                   "to s (Inline.bip:9:8): extern twice is bound to Python code): exploring with the "
                                   "Python step")


def test_the_library_is_cached_by_model(tmp_path, monkeypatch):
    monkeypatch.setenv("GENOM2BIP_CACHE", str(tmp_path))
    compiled(verifykit.space("Dining", "Table2()"))
    compiled(verifykit.space("Dining", "Table2()"))
    compiled(verifykit.space("Dining", "Table3()"))
    libraries = sorted(p for p in os.listdir(tmp_path) if p.endswith(".so"))
    assert len(libraries) == 2
    assert sorted(os.listdir(tmp_path)) == sorted(libraries + [p[:-3] + ".c" for p in libraries])



def test_the_optimisation_level_is_part_of_the_cache_key(tmp_path, monkeypatch):
    monkeypatch.setenv("GENOM2BIP_CACHE", str(tmp_path))
    for level in ("0", "2", "0"):
        monkeypatch.setenv("GENOM2BIP_OPT", level)
        cs = compiled(verifykit.space("Dining", "Table2()"))
        result = cs.explore()
        assert (result.states, result.deadlocks) == (6, [4])  # every level: the same search
    assert len([p for p in os.listdir(tmp_path) if p.endswith(".so")]) == 2  # one per level, never mixed


def test_an_unknown_optimisation_level_is_refused_by_name(tmp_path, monkeypatch):
    monkeypatch.setenv("GENOM2BIP_CACHE", str(tmp_path))
    monkeypatch.setenv("GENOM2BIP_OPT", "fast")
    cs, note = native.compile_space(verifykit.space("Dining", "Table2()"))
    assert cs is None
    assert note == ("compiling the step failed (GENOM2BIP_OPT='fast': expected one of 0, 1, 2, 3 (gcc's -O level)): "
                    "exploring with the Python step")
    assert os.listdir(tmp_path) == []


BUILD_ONE = """
import sys
from tests import verifykit
from runtime.native.compiled import compile_space
cs, note = compile_space(verifykit.space("Dining", "Table3()"), search=True)
assert cs is not None, note
print(cs.explore().states)
"""


def test_workers_building_the_same_library_at_once_all_load_a_whole_one(tmp_path):
    """What ``pytest -n`` relies on: each writes under its own name and renames into place."""
    env = dict(os.environ, GENOM2BIP_CACHE=str(tmp_path), PYTHONPATH=str(verifykit.ROOT))
    procs = [subprocess.Popen([sys.executable, "-c", BUILD_ONE], env=env, cwd=verifykit.ROOT, text=True,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE) for _ in range(4)]
    results = [p.communicate(timeout=600) for p in procs]
    assert [p.returncode for p in procs] == [0] * 4, results
    assert len({out for out, _ in results}) == 1
    names = sorted(os.listdir(tmp_path))
    steps = [n for n in names if n.startswith("step-")]
    assert len(steps) == 2 and {n.rsplit(".", 1)[1] for n in steps} == {"so", "c"}, names  # no partial file
    assert all(n.startswith("lark-") and n.endswith(".tables") for n in set(names) - set(steps)), names  # (parsing)

# -- random models ---------------------------------------------------------------------------------

#: Written with the compiled step: the C step's successors, in the Python step's order, state by state, on
#: guards, counters, atom and compound priorities, rendezvous and broadcasts.  40 examples (cheap: each model
#: is small and built at -O0).
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(models())
def test_random_models_have_the_same_successors(text):
    try:
        space = StateSpace(parse_text(text, "Random.bip"), "Main()")
    except EngineError:
        return  # refused before any step (a priority cycle, ...): nothing to compare
    agree(space, compiled(space), limit=500)


WIDE = """package Wide
  port type Port()
  atom type A()
    data int x
    port Port grow()
    place s
    initial to s do { x = 0; }
    on grow from s to s do { x = (x + 7) % 300 - 100; }
  end
  compound type Main()
    component A a()
  end
end
"""


def test_ints_outgrowing_their_field_are_widened():
    ours = explore(verifykit.text_space(WIDE))
    cs = compiled(verifykit.text_space(WIDE))
    theirs = cs.explore()
    assert (theirs.states, theirs.transitions, theirs.deadlocks) == (ours.states, ours.transitions, [])
    assert ours.states == 102 and cs.widths == {1: 16}  # -100..199: 4 bits, then 8, then 16


def verdicts(pkg, root, items):
    from runtime.native.properties import compiled_check
    from runtime.props import check

    observed = set().union(*(i.observed for i in items))
    out = []
    for item in items:
        ours = check(StateSpace(pkg, root, observed=observed), item)
        theirs = compiled_check(StateSpace(pkg, root, observed=observed), item)
        out.append((item.name, ours, theirs))
    return out


def test_safety_observers_give_the_python_checkers_verdicts_and_trace_lengths():
    from runtime.engine import flatten
    from runtime.props import read_properties, read_property_file

    cases = []
    for path in (str(verifykit.NDD), str(verifykit.NDD_NO_AFTER)):
        pkg, root = verifykit.ndd_model(path)
        items, _ = read_property_file(verifykit.FIXTURES / "goto_after_setspeed.mcl", flatten(pkg, root))
        cases += verdicts(pkg, root, items)
    pkg = verifykit.package("Server")
    items, _ = read_properties("a: invariant S.served <= 1; b: invariant not S @ DONE; c: deadlock free", "p.mcl",
                               flatten(pkg, "Main()"))
    cases += verdicts(pkg, "Main()", items)
    checked = [(name, ours, theirs) for name, ours, theirs in cases if theirs is not None]
    assert len(checked) == 7  # the paper's property is not an observer shape: the Python checker takes it
    for name, ours, theirs in checked:
        assert theirs.holds == ours.holds, name
        assert [str(s) for s in theirs.trace] == [str(s) for s in ours.trace], name
    assert sorted(name for name, _, theirs in checked if theirs.holds is False) == \
        ["b", "goto_after_setspeed", "goto_after_setspeed_mcl"]
