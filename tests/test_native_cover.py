"""The C step on what it took last: nested connectors, timed models, floats, strings, wide connectors; refusals."""
from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

from genom2bip.build.timed import TimeOptions
from genom2bip.generate import model_of
from genom2bip.parser import parse_paths
from genom2bip.rules import description_rules
from runtime.bip2 import parse_text
from runtime.engine.errors import EngineError
from runtime.explore import StateSpace
from runtime.native import compiled as native
from runtime.native import cstep
from tests import enginekit, verifykit
from tests.nativekit import agree, compiled, models, needs_cc
from tests.runkit import dala_without_wcets
from tests.test_native import same_search

pytestmark = needs_cc
ROOT = Path(__file__).resolve().parents[1]


def timed(path: str, name: str, **options):
    description = parse_paths([ROOT / path])
    package, root, _ = model_of(description, name, description_rules(description), TimeOptions(**options))
    return package, root


@pytest.mark.parametrize("package, root", [(enginekit.package("Hierarchy"), "Module()"),
                                           (enginekit.package("Hierarchy"), "System()"),
                                           (enginekit.package("NestedAny"), "System()"),
                                           (verifykit.package("Mix"), "Main()")])
def test_nested_connectors_have_the_same_successors(package, root):
    space = StateSpace(package, root)
    assert agree(space, compiled(space)) == len(space)


def test_nested_connectors_search_as_the_python_explorer():
    same_search((verifykit.package("Mix"), "Main()"))


@pytest.mark.parametrize("wcet", [0, 10_000, 40_000])
def test_timed_cruise_agrees_state_by_state_and_in_the_search(wcet):
    package, root = timed("tests/fixtures/timed/Cruise.gen", "Cruise", default_wcet_us=wcet)
    space = StateSpace(package, root)
    assert agree(space, compiled(space)) == len(space)
    same_search((package, root))


def test_timed_ndd_agrees_on_its_first_states_and_counts_as_python():
    package, root = timed(str(dala_without_wcets() / "NDD.gen"), "NDD")  # 0 ms codels
    space = StateSpace(package, root)
    assert agree(space, compiled(space), limit=1500) == 1500
    result = compiled(StateSpace(package, root)).explore()
    assert (result.states, result.transitions, result.depth, result.complete) == (279_040, 2_072_832, 38, True)


# -- floats and strings ------------------------------------------------------------------------------

FLOATS = """package Floats
  port type Port()
  port type FPort(float v)
  atom type A(float start)
    data float h, g
    data int n, k
    data bool b
    export port FPort out(h)
    export port FPort in(g)
    port Port halve(), grow(), cut()
    place s, t
    initial to s do { h = start; g = 0.0; }
    on halve from s to s provided (k < 5 && h > 1) do { h = h / 2.0; n = h; b = h; k = k + 1; }
    on grow from s to s provided (k < 5 && h < 100) do { h = h * 3.0 + 0.5; k = k + 1; }
    on cut from s to t provided (k < 5 && (n == h || h <= 2)) do { h = (h + 2.5) % 2.0; n = -h * 3.0; k = k + 1; }
    on out from t to s
    on in from t to t provided (k < 5 && g != h) do { h = g; k = k + 1; }
  end
  connector type Pass(FPort a, FPort b)
    define a b
    on a b provided (a.v >= b.v) down { b.v = a.v - 0.25; }
  end
  compound type Main()
    component A x(6.0), y(1.5)
    connector Pass xy(x.out, y.in)
  end
end
"""

STRINGS = """package Strings
  port type SPort(string m)
  atom type A()
    data string mode, seen
    export port SPort say(mode), hear(seen)
    place s
    initial to s do { mode = "idle"; }
    on say from s to s provided (mode != "done") do { if (mode == "idle") then mode = "run"; else mode = "done"; fi }
    on hear from s to s provided (seen != mode)
  end
  connector type Tell(SPort a, SPort b)
    define a b
    on a b down { b.m = a.m; }
  end
  compound type Main()
    component A x(), y()
    connector Tell xy(x.say, y.hear)
    connector Tell yx(y.say, x.hear)
  end
end
"""


@pytest.mark.parametrize("text", [FLOATS, STRINGS])
def test_floats_and_strings_have_the_same_successors_and_search(text):
    space = verifykit.text_space(text)
    assert agree(space, compiled(space), limit=3000) == min(len(space), 3000)
    python = verifykit.text_space(text)
    ours = compiled(verifykit.text_space(text)).explore()
    from runtime.explore import explore
    theirs = explore(python)
    assert (ours.states, ours.transitions, ours.deadlocks) == (theirs.states, theirs.transitions, theirs.deadlocks)
    assert ours.states > 3


EXACT = """package Exact
  port type Port()
  atom type A()
    data float h
    port Port p()
    place s, t
    initial to s do { h = 9007199254740992.0; }
    on p from s to t provided (h < 9007199254740993 && 9007199254740993 > h && h != 9007199254740993)
  end
  compound type Main()
    component A a()
  end
end
"""


def test_ints_and_floats_compare_exactly_as_python_compares_them():
    space = verifykit.text_space(EXACT)
    assert agree(space, compiled(space)) == len(space) == 2  # as doubles, 2**53 + 1 == 2**53: one state


def test_a_float_made_an_int_past_64_bits_gives_way_to_the_python_step():
    cs = compiled(verifykit.text_space(FLOATS.replace("n = -h * 3.0", "n = -h * 1e300")))
    with pytest.raises(native.Diverged):
        cs.explore()


def test_a_float_division_by_zero_is_the_engines_error_with_its_trace():
    text = FLOATS.replace("h = h / 2.0;", "h = h / (h - h);")
    python = verifykit.text_space(text)
    from runtime.explore import explore
    expected = explore(python).error
    got = compiled(verifykit.text_space(text)).explore().error
    assert got.message == expected.message and "division by zero" in got.message
    assert [str(s) for s in got.trace] == [str(s) for s in expected.trace]


@pytest.mark.parametrize("change, message", [
    ("h = h * 3.0 + 0.5;", "atom x (A), transition on grow from s to s (Inline.bip:14:8): an int value assigned to a "
                           "float variable (the Python step keeps it an int, with int arithmetic; write a float "
                           "constant such as 1.0)"),
    ("h = h * 3.0 + 0.5; n = n | h;", "atom x (A), transition on grow from s to s (Inline.bip:14:8): operator '|' on a "
                                      "float (the Python step fails there)"),
])
def test_refusals_name_the_construct_and_where_it_is(change, message):
    text = FLOATS.replace("h = h * 3.0 + 0.5;", change.replace("h = h * 3.0 + 0.5;", "h = 3;")
                          if "|" not in change else change)
    cs, note = native.compile_space(verifykit.text_space(text))
    assert (
        cs is None
        and note == f"compiled exploration does not take this model ({message}): exploring with the Python step"
    )


def test_strings_are_compared_for_equality_only():
    text = STRINGS.replace('provided (mode != "done")', 'provided (mode < "done")')
    cs, note = native.compile_space(verifykit.text_space(text))
    assert cs is None and "atom x (A), transition on say from s to s (Inline.bip:8:8): operator '<' on string and " \
        "string (strings are only compared with == and !=)" in note


#: Written with floats in the C step: Python's float arithmetic, comparisons and errors (a division by zero,
#: a float made an int past 64 bits) at the same states.  15 examples.
@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(models(floats=True))
def test_random_models_with_floats_have_the_same_successors(text):
    try:
        space = StateSpace(parse_text(text, "Random.bip"), "Main()")
    except EngineError:
        return
    cs, note = native.compile_space(space)
    assert cs is not None, note
    agree(space, cs, limit=500)


# -- verify --timed on the compiled explorer -------------------------------------------------------

def _verify(capsys, *argv):
    import re

    from genom2bip.cli import main

    code = main(["verify", *argv])
    out = capsys.readouterr().out
    return code, re.sub(r"\([\d,]+ states, [\d.]+ s\)", "(...)", out)


@pytest.mark.parametrize("argv", [
    ("tests/fixtures/timed/Cruise.gen", "--timed", "--schedulability"),
    ("tests/fixtures/timed/Cruise.gen", "--timed", "--schedulability", "-DPERIOD=15"),
    ("tests/fixtures/timed/Cruise.gen", "--timed", "--observers", "tests/fixtures/timed/observers.yaml",
     "-DPERIOD=15"),
])
def test_timed_verdicts_and_traces_are_the_python_explorers(capsys, argv):
    argv = (str(ROOT / argv[0]),) + tuple(str(ROOT / a) if a.endswith(".yaml") else a for a in argv[1:])
    code, out = _verify(capsys, *argv)
    expected_code, expected = _verify(capsys, *argv, "--engine", "python")
    assert (code, out) == (expected_code, expected)
    assert "note:" not in out and "reachable" in out


# -- connectors of many ports ------------------------------------------------------------------------

def wide(n: int, guarded: bool) -> str:
    """A broadcast of n receivers in pairs (a nested define), each receiver toggling; optionally guarded."""
    receivers = [f"r{i}" for i in range(n)]
    pairs = " ".join(f"({receivers[i]} {receivers[i + 1]})" if i + 1 < n else receivers[i] for i in range(0, n, 2))
    clause = "    on s r0 r1 provided (s.v + r0.v + r1.v < 2)\n" if guarded else ""
    comps = ", ".join(f"u{i}()" for i in range(n))
    args = ", ".join(f"u{i}.p" for i in range(n))
    return f"""package Wide
  port type IPort(int v)
  atom type U()
    data int v
    export port IPort p(v)
    place a, b
    initial to a
    on p from a to b do {{ v = 1 - v; }}
    on p from b to a provided (v == 0)
  end
  connector type Fan(IPort s, {', '.join(f'IPort {r}' for r in receivers)})
    define s' {pairs}
{clause}  end
  compound type Main()
    component U src(), {comps}
    connector Fan fan(src.p, {args})
  end
end
"""


@pytest.mark.parametrize("n, guarded", [(13, False), (19, False), (14, True), (20, True)])
def test_connectors_of_many_ports_have_the_same_successors(n, guarded):
    space = verifykit.text_space(wide(n, guarded))
    assert agree(space, compiled(space), limit=300) == min(len(space), 300)


def test_a_connector_past_32_ports_is_refused_by_name():
    cs, note = native.compile_space(verifykit.text_space(wide(33, False)))
    assert cs is None and "connector fan: 34 ports, more than the 32 bits of the compiled step's interaction masks" \
        in note


def guarded_chain(n_atoms: int, n_rules: int, cycle: bool = False) -> str:
    """Atoms toggling between two places (ports p, q) and counting x mod 3; one connector per port.

    ``n_rules`` compound priorities, each guarded by some atom's x, go from a connector to one later in the
    order p0 q0 p1 q1 ... (first the neighbours, then two apart), so the guards change along every run and the
    closure often passes through a connector that is not enabled (p and q of one atom never are together).
    ``cycle`` adds a rule back from p1 to p0 whose guard closes a cycle in some reachable states only.
    """
    conns = [f"{k}{i}" for i in range(n_atoms) for k in "pq"]
    pairs = [(conns[i], conns[i + gap]) for gap in (1, 2) for i in range(len(conns) - gap)][:n_rules]
    tests = ("!=", "==")
    prios = [f"    priority r{r} {lo}:* < {hi}:* provided (a{(3 * r + 1) % n_atoms}.x {tests[r % 2]} {r % 3})"
             for r, (lo, hi) in enumerate(pairs)]
    if cycle:
        prios.append("    priority back p1:* < p0:* provided (a0.x == 2 && a1.x == 2)")
    atoms = ", ".join(f"a{i}()" for i in range(n_atoms))
    connectors = "\n".join(f"    connector One p{i}(a{i}.p)\n    connector One q{i}(a{i}.q)" for i in range(n_atoms))
    rules = "\n".join(prios)
    return f"""package Guarded
  port type Port()
  atom type A()
    export data int x
    export port Port p(), q()
    place s, t
    initial to s
    on p from s to t do {{ x = (x + 1) % 3; }}
    on q from t to s
  end
  connector type One(Port a)
    define a
  end
  compound type Main()
    component A {atoms}
{connectors}
{rules}
  end
end
"""


def test_more_guarded_compound_priorities_than_the_tables_take_filter_as_the_python_step():
    """Past MAX_GUARDED guards the C step computes each rule closure when its guards' combination is first met."""
    space = verifykit.text_space(guarded_chain(4, 12))
    priorities = space.engine.namespace["_prio"].__self__
    assert len(priorities.guards) == 12 > cstep.MAX_GUARDED
    cs = compiled(space)
    assert "reach_of(key)" in cs.source  # the lazy closures, not the table of every combination
    assert agree(space, cs, limit=5000) == len(space) == 1188
    assert len(priorities.memo) >= 50  # combinations of the guards met by the Python step along the way


def test_a_priority_cycle_that_guards_close_late_in_the_run_stops_both_steps_at_the_same_state():
    space = verifykit.text_space(guarded_chain(4, 12, cycle=True))
    cs = compiled(space)
    assert "reach_of(key)" in cs.source
    met = agree(space, cs, limit=5000)  # up to and including the first state where the cycle is enabled
    with pytest.raises(EngineError, match="priority cycle between compound priorities .*back"):
        space.successors(met - 1)
    assert met > 10


def test_more_than_64_compound_priorities_filter_as_the_python_step():
    n = 70
    atoms = ", ".join(f"a{i}()" for i in range(n + 1))
    conns = "\n".join(f"    connector Sync c{i}(a{i}.p, a{i + 1}.q)" for i in range(n))
    prios = "\n".join(f"    priority r{i} c{i}:* < c{i + 1}:*" + (" provided (a0.x == 0)" if i == 3 else "")
                      for i in range(n - 1))
    text = f"""package Many
  port type Port()
  atom type A()
    export data int x
    export port Port p(), q()
    place s, t
    initial to s
    on p from s to t do {{ x = 1; }}
    on q from s to s
    on q from t to t
    on p from t to s do {{ x = 0; }}
  end
  connector type Sync(Port a, Port b)
    define a b
  end
  compound type Main()
    component A {atoms}
{conns}
{prios}
  end
end
"""
    space = verifykit.text_space(text)
    assert agree(space, compiled(space), limit=200) == len(space) >= 2  # 70 sources enabled, one kept
