"""How far the partial-order reduction reaches: minimal observers, ports that only read, the cycle provisos.

Every reduction here is checked against the full search: same deadlocks, same verdicts.
"""
from __future__ import annotations

import random

from hypothesis import HealthCheck, given, settings

from runtime.bip2 import parse_text
from runtime.engine import flatten
from runtime.engine.errors import EngineError
from runtime.explore import StateSpace
from runtime.export.interactions import all_interactions
from runtime.export.monitors import build_monitor
from runtime.native import por
from runtime.native.observers import minimal
from runtime.native.properties import compiled_check
from runtime.props import read_properties
from tests import verifykit
from tests.nativekit import models, needs_cc
from tests.test_native_por import same_deadlocks

STOP = ('stop: [ true* . "NDD.Stop:start" . (not "NDD.GoTo:trigger")* . "NDD.GoTo:exec_plan" ] false;'
        ' after: "NDD.SetSpeed:finish" precedes "NDD.GoTo:trigger";'
        ' next: [ true* . "NDD.SetSpeed:finish" . "NDD.GoTo:trigger" ] false')


def ndd_observers():
    pkg, root = verifykit.ndd_model()
    space = StateSpace(pkg, root)
    items, _ = read_properties(STOP, "p.mcl", flatten(pkg, root))
    statics = all_interactions(space.engine)
    return space, statics, {i.name: build_monitor(i, statics, "p")[0] for i in items}


def accepts(mon, word) -> bool:
    q = mon.initial
    for k in word:
        if q in mon.accepting:
            return True
        q = mon.delta[k].get(q, q)
    return q in mon.accepting


def test_minimal_observers_accept_the_same_runs_and_ignore_what_they_do_not_name():
    _, statics, monitors = ndd_observers()
    named = {"stop": {"NDD.Stop:start", "NDD.GoTo:trigger", "NDD.GoTo:exec_plan"},
             "after": {"NDD.SetSpeed:finish", "NDD.GoTo:trigger"}}
    rng = random.Random(7)
    for name, mon in monitors.items():
        small = minimal(mon)
        assert small.states <= mon.states
        for _ in range(300):
            word = [rng.randrange(len(statics)) for _ in range(rng.randrange(1, 12))]
            assert accepts(small, word) == accepts(mon, word), (name, word)
        for k, st in enumerate(statics):
            moves = any(q2 != q for q, q2 in small.delta[k].items())
            if name != "next":  # stutter-invariant: only the named interactions move the observer
                assert moves == (st.label in named[name]), (name, st.label)
    # the subset construction alone moves on every interaction: nothing would be invisible
    raw = monitors["after"]
    assert all(any(q2 != q for q, q2 in raw.delta[k].items()) for k in range(len(statics)))
    # "a immediately followed by b" is not stutter-invariant: every interaction stays visible
    nxt = minimal(monitors["next"])
    assert all(any(q2 != q for q, q2 in nxt.delta[k].items()) for k in range(len(statics)))


def test_only_the_named_interactions_sources_are_visible():
    space, statics, monitors = ndd_observers()
    sources, flat = space.engine.sources, space.engine.flat
    visible = por.visible_sources(sources, flat, [(minimal(monitors["after"]), statics)])
    named = {st.source.index for st in statics if st.label in ("NDD.SetSpeed:finish", "NDD.GoTo:trigger")}
    assert {i for i, v in enumerate(visible) if v} == named
    assert all(por.visible_sources(sources, flat, [(monitors["after"], statics)]))


LOOK = """package Look
  port type Port()
  port type Status(bool busy)
  atom type Worker()
    data bool busy
    export port Port go(), done()
    export port Status status(busy)
    place IDLE, RUN
    initial to IDLE do { busy = false; }
    on go from IDLE to RUN do { busy = true; }
    on done from RUN to IDLE do { busy = false; }
    on status from IDLE to IDLE
    on status from RUN to RUN
  end
  atom type Boss()
    data int n
    export port Port order()
    place WAIT, DONE
    initial to WAIT do { n = 0; }
    on order from WAIT to WAIT provided (n < 2) do { n = n + 1; }
    on order from WAIT to DONE provided (n >= 2)
  end
  connector type One(Port a)
    define a
  end
  connector type Rule(Port a, Status s1, Status s2)
    define a s1 s2
    on a s1 s2 provided (!s1.busy && !s2.busy)
  end
  connector type Tell(Port a, Status s1, Status s2)
    define a s1 s2
    on a s1 s2 down { s1.busy = true; }
  end
  compound type Main()
    component Worker w1()
    component Worker w2()
    component Worker w3()
    component Boss b()
    connector One g1(w1.go)
    connector One d1(w1.done)
    connector One g2(w2.go)
    connector One d2(w2.done)
    connector One g3(w3.go)
    connector One d3(w3.done)
    connector CONN rule(b.order, w1.status, w2.status)
  end
end
"""


def look(conn: str = "Rule") -> StateSpace:
    return StateSpace(parse_text(LOOK.replace("CONN", conn), "Look.bip"), "Main()")


def test_a_status_port_is_read_not_written_unless_the_connector_writes_its_data():
    space = look()
    flat = space.engine.flat
    rule = next(s for s in space.engine.sources if s.connector is not None and s.connector.path.endswith("rule"))
    names = lambda atoms: sorted(flat.atoms[a].name for a in atoms)  # noqa: E731
    assert names(por.written_atoms(rule, flat)) == ["b"]
    assert names(por.source_atoms(rule, flat)) == ["b", "w1", "w2"]
    tell = look("Tell")
    src = next(s for s in tell.engine.sources if s.connector is not None and s.connector.path.endswith("rule"))
    assert names(por.written_atoms(src, tell.engine.flat)) == ["b", "w1"]  # down writes s1.busy


def test_rule_model_properties_keep_their_verdicts_under_every_proviso():
    props = ('early: [ true* . "rule" . (not "d1")* . "g1" ] false; '
             'late: [ true* . "g3" . (not "d3")* . "rule" ] false; '
             'busy: [ true* . "g1" ] {not b @ DONE}; free: deadlock free')
    pkg = parse_text(LOOK.replace("CONN", "Rule"), "Look.bip")
    items, _ = read_properties(props, "p.mcl", flatten(pkg, "Main()"))
    observed = set().union(*(i.observed for i in items))
    verdicts = {}
    for item in items:
        full = compiled_check(StateSpace(pkg, "Main()", observed=observed), item)
        for kw in ({"por": True}, {"por": True, "dfs": True}, {"por": True, "store": "compact"},
                   {"por": True, "workers": 2}):
            red = compiled_check(StateSpace(pkg, "Main()", observed=observed), item, **kw)
            assert red.holds == full.holds, (item.name, kw)
            assert not full.holds or red.states <= full.states, (item.name, kw)  # complete searches
        verdicts[item.name] = full.holds
    assert verdicts == {"early": False, "late": False, "busy": False, "free": True}
    same_deadlocks(look)


#: Written with the reduction's provisos for regular properties (observers of runs); 8 examples.
@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(models(atoms_range=(2, 4), connectors_range=(2, 4)))
def test_random_models_keep_their_regular_verdicts(text):
    try:
        pkg = parse_text(text, "Random.bip")
        StateSpace(pkg, "Main()")
    except EngineError:
        return
    props = 'r1: "c1" precedes "c0"; r2: [ (not "a0.q")* . "c1" . (not "c0")* . "a1.q" ] false'
    try:
        items, _ = read_properties(props, "p.mcl", flatten(pkg, "Main()"))
    except Exception:  # a label the drawn model lacks
        return
    observed = set().union(*(i.observed for i in items))
    for item in items:
        full = compiled_check(StateSpace(pkg, "Main()", observed=observed), item)
        if full is None or full.error:
            continue
        for kw in ({"por": True}, {"por": True, "dfs": True}, {"por": True, "store": "compact"}):
            got = compiled_check(StateSpace(pkg, "Main()", observed=observed), item, **kw)
            assert got.holds == full.holds or got.error, (item.name, kw)


pytestmark = needs_cc
