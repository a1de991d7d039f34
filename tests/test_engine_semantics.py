"""The engine's step on hand-checked models: one test per construct and semantic rule."""
from enginekit import atom, engine, labels, walk

from runtime.engine import Engine, first


# -- rendezvous -----------------------------------------------------------------------------------

def test_rendezvous_enabled_and_first_policy_trace():
    e = engine("Dining", "Table3()")
    s = e.initial_state()
    assert labels(e, s) == ["eat0", "eat1", "eat2"]
    s1 = walk(e, "eat1")
    # f1 and f2 are busy: only philosopher 1 can put them back
    assert labels(e, s1) == ["done1"]
    from runtime.engine import MemoryTracer
    tr = MemoryTracer()
    summary = e.run(first, limit=6, tracer=tr)
    assert tr.labels == ["eat0", "done0"] * 3
    assert summary.outcome == "limit" and summary.steps == 6
    assert atom(e, summary.state, "p0") == {"places": ["think"], "data": {"meals": 3}}


def test_interaction_identity_is_stable():
    e1, e2 = engine("Dining", "Table3()"), engine("Dining", "Table3()")
    a = e1.enabled(e1.initial_state())
    b = e2.enabled(e2.initial_state())
    assert [i.index for i in a] == [i.index for i in b]
    assert a[0] == b[0] and hash(a[0]) == hash(b[0])
    assert a[0].connector == "eat0"
    assert a[0].ports == ("f0.take", "p0.eat", "f1.take")


# -- broadcast ------------------------------------------------------------------------------------

def test_broadcast_maximal_progress_and_down_values():
    e = engine("Broadcast")
    s = e.initial_state()
    assert labels(e, s) == ["bc"]          # {s,r1,r2,r3} hides its 7 subsets with the trigger
    s, values = e.fire_traced(s, e.find(s, "bc"))
    assert values == {"snd.snd": {"v": 0}, "r1.rcv": {"v": 0}, "r2.rcv": {"v": 0}, "r3.rcv": {"v": 0}}
    assert [atom(e, s, r)["data"]["x"] for r in ("r1", "r2", "r3")] == [0, 0, 0]
    assert atom(e, s, "snd")["data"] == {"v": 1}
    # all receivers busy: the trigger alone, and the receivers' lone ports
    assert labels(e, s) == ["bc[snd.snd]", "r1.work", "r2.work", "r3.work"]
    s = walk(e, "r2.work", state=s)
    assert labels(e, s) == ["bc[snd.snd,r2.rcv]", "r1.work", "r3.work"]
    s = walk(e, "bc[snd.snd,r2.rcv]", state=s)
    assert atom(e, s, "r2") == {"places": ["busy"], "data": {"x": 1}}
    assert atom(e, s, "snd")["data"] == {"v": 2}


def test_broadcast_guard_false_on_largest_gives_the_next_maximal_ones():
    e = engine("Broadcast")
    s = walk(e, "bc", "bc[snd.snd]", "r1.work", "r2.work", "r3.work")
    assert atom(e, s, "snd")["data"] == {"v": 2}
    # s.v == 2 disables the full interaction: the three 3-port ones are maximal
    assert labels(e, s) == ["bc[snd.snd,r1.rcv,r2.rcv]", "bc[snd.snd,r1.rcv,r3.rcv]", "bc[snd.snd,r2.rcv,r3.rcv]"]
    s = walk(e, "bc[snd.snd,r1.rcv,r3.rcv]", state=s)
    assert [atom(e, s, r) for r in ("r1", "r2", "r3")] == [
        {"places": ["busy"], "data": {"x": 2}},
        {"places": ["ready"], "data": {"x": 0}},
        {"places": ["busy"], "data": {"x": 2}},
    ]


# -- hierarchical connectors ----------------------------------------------------------------------

def test_nested_connector_max_up_and_down():
    for root, expected in (("System(3, 7, 5)", 7), ("System(3, 7, 9)", 9), ("System(8, 7, 5)", 8)):
        e = engine("NestedMax", root)
        s = e.initial_state()
        assert labels(e, s) == ["top"]     # inner exports a port: it never fires on its own
        s, values = e.fire_traced(s, e.find(s, "top"))
        assert values == {"a.p": {"x": expected}, "b.p": {"x": expected}, "c.p": {"x": expected}}
        assert {n: st["data"]["x"] for n, st in e.describe_state(s).items()} == {
            "a": expected,
            "b": expected,
            "c": expected,
        }
        assert labels(e, s) == []


def test_nested_connector_through_a_compound_export():
    e = engine("NestedMax", "Boxed(3, 7, 9)")
    s = e.initial_state()
    (top,) = e.enabled(s)
    assert top.label == "top" and top.ports == ("pair.a.p", "pair.b.p", "c.p")
    s = e.fire(s, top)
    assert [st["data"]["x"] for st in e.describe_state(s).values()] == [9, 9, 9]


def test_maximal_progress_through_sub_connectors_with_guard_on_up_value():
    e = engine("NestedAny")
    s = e.initial_state()
    assert labels(e, s) == ["top[x.p,y.p]", "top[x.p,z.p]", "top[y.p,z.p]"]
    inter = e.find(s, "top[x.p,z.p]")
    assert inter.ports == ("x.p", "z.p")
    assert e.run(first, limit=3).steps == 3


def test_exported_but_unused_connector_and_ports_never_fire():
    e = engine("NestedAny", "Dangling()")
    summary = e.run(first)
    assert summary.outcome == "deadlock" and summary.steps == 0


# -- atom priorities -------------------------------------------------------------------------------

def test_atom_priorities_guarded_and_transitive():
    e = engine("AtomPriorities")
    s = e.initial_state()
    # x = 0: lo < hi is off, hi < mid has mid disabled; st: a, b < c
    assert labels(e, s) == ["p.lo", "p.hi", "p.inc", "st.c"]
    s = walk(e, "p.inc", state=s)                    # x = 1: lo < hi holds
    assert labels(e, s) == ["p.hi", "p.inc", "st.c"]
    s = walk(e, "p.inc", "p.inc", state=s)           # x = 3: hi disabled, yet lo < hi < mid blocks lo
    assert labels(e, s) == ["p.mid", "p.inc", "st.c"]
    s = walk(e, "p.inc", state=s)                    # x = 4: hi enabled but below mid
    assert labels(e, s) == ["p.mid", "p.inc", "st.c"]


# -- compound priorities ---------------------------------------------------------------------------

def test_compound_priority_low_side_names_an_interaction_and_those_inside_it_guard_each_step():
    e = engine("Priorities", "Low()")
    s = e.initial_state()
    assert labels(e, s) == ["bc", "tk"]              # t = 0 even, but the full bc is not inside S.snd, R1.rcv
    s = walk(e, "tk", "bc", state=s)
    assert labels(e, s) == ["bc[S.snd]", "tk", "R1.work", "R2.work"]   # t = 1: rule off
    s1 = walk(e, "R1.work", "tk", state=s)           # t = 2: rule on, bc[S.snd,R1.rcv] is the low side itself
    assert labels(e, s1) == ["tk", "R2.work"]
    s2 = walk(e, "R2.work", "tk", state=s)           # t = 2: bc[S.snd,R2.rcv] is not inside the low side
    assert labels(e, s2) == ["bc[S.snd,R2.rcv]", "tk", "R1.work"]


def test_compound_priority_high_side_containment():
    e = engine("Priorities", "High()")
    s = e.initial_state()
    assert labels(e, s) == ["bc"]
    s = walk(e, "bc", state=s)
    assert labels(e, s) == ["bc[S.snd]", "tk", "R1.work", "R2.work"]
    s = walk(e, "R1.work", state=s)                  # bc[S.snd,R1.rcv] does not contain R2.rcv
    assert labels(e, s) == ["bc[S.snd,R1.rcv]", "tk", "R2.work"]
    s = walk(e, "R2.work", state=s)
    assert labels(e, s) == ["bc"]


def test_compound_priority_star_and_nested_compound():
    e = engine("Priorities", "Star()")
    s = e.initial_state()
    assert labels(e, s) == ["tk"]
    e = engine("Priorities", "Nested()")
    s = e.initial_state()
    assert labels(e, s) == ["low.bc", "low.tk"]
    assert labels(e, walk(e, "low.tk", "low.bc", "low.R1.work", "low.tk")) == ["low.tk", "low.R2.work"]


# -- internal transitions --------------------------------------------------------------------------

def test_eager_chained_internal_transitions():
    e = engine("Chain")
    s = e.initial_state()
    # y = 7 from its declaration; b -> c (x = 1, y = 6) -> a at initialisation
    assert atom(e, s, "ch") == {"places": ["a"], "data": {"x": 1, "y": 6}}
    s = walk(e, "ch.go", state=s)                                     # a -> b -> c (x = 2: then branch) -> a
    assert atom(e, s, "ch") == {"places": ["a"], "data": {"x": 2, "y": 10}}
    s = walk(e, "ch.go", state=s)                                     # b -> c -> d
    assert atom(e, s, "ch") == {"places": ["d"], "data": {"x": 3, "y": 9}}
    summary = e.run(first)
    assert (summary.outcome, summary.steps) == ("deadlock", 2)


# -- compound exports, labels ---------------------------------------------------------------------

def test_merged_export_alternatives_and_label_annotation():
    e = engine("Hierarchy")
    s = e.initial_state()
    en = e.enabled(s)
    assert [i.label for i in en] == ["Mod.Pass:take[src.a.out,sink.take]", "Mod.Pass:take[src.b.out,sink.take]"]
    assert en[1].ports == ("m.src.b.out", "m.sink.take") and en[1].connector == "m.pass"
    s, values = e.fire_traced(s, en[1])
    assert values == {"m.src.b.out": {"v": 2}, "m.sink.take": {"v": 2}}
    assert atom(e, s, "m.sink") == {"places": ["full"], "data": {"got": 2}}
    assert labels(e, s) == ["m.sink.reset"]
    from runtime.engine import MemoryTracer
    tr = MemoryTracer()
    summary = e.run(first, tracer=tr)
    assert tr.labels == ["Mod.Pass:take[src.a.out,sink.take]", "m.sink.reset",
                         "Mod.Pass:take[src.b.out,sink.take]", "m.sink.reset"]
    assert summary.outcome == "deadlock"


# -- data: C semantics and externs ----------------------------------------------------------------

def _ext():
    calls = []
    return calls, {"twice": lambda x: 2 * x, "log": calls.append}


def test_c_arithmetic():
    calls, ext = _ext()
    e = engine("Arith", "System()", ext)
    data = atom(e, e.initial_state(), "c")["data"]
    assert data == {
        "q": 3,
        "r": 1,
        "q2": -3,
        "r2": -1,
        "t": 3,
        "f": 14,
        "land": False,
        "lnot": False,
        "h": 3.5,
        "w": 16,
    }
    e = engine("Arith", "Neg()", ext)
    data = atom(e, e.initial_state(), "c")["data"]
    assert (data["q"], data["r"], data["q2"], data["r2"]) == (-3, 1, 3, -1)


def test_externs_in_guards_and_actions():
    calls, ext = _ext()
    e = engine("Arith", "System()", ext)
    s = walk(e, "c.step")
    assert calls == [14]
    assert atom(e, s, "c") == {"places": ["t2"], "data": {"q": 3, "r": 1, "q2": -3, "r2": -1, "t": 3, "f": 16,
                                                           "land": False, "lnot": False, "h": 3.5, "w": 16}}


def test_externs_from_a_module_file():
    from enginekit import FIXTURES
    e = engine("Arith", "System()", str(FIXTURES / "arith_externs.py"))
    assert atom(e, e.initial_state(), "c")["data"]["f"] == 14


def test_state_is_a_flat_hashable_tuple():
    e = engine("Broadcast")
    s = e.initial_state()
    assert isinstance(s, tuple) and hash(s) is not None
    # snd: marking, v; then each receiver: marking, x
    assert s == (1, 0, 1, -1, 1, -1, 1, -1)
    assert e.fire(s, e.enabled(s)[0]) == (1, 1, 2, 0, 2, 0, 2, 0)
    assert s == (1, 0, 1, -1, 1, -1, 1, -1)       # fire is pure


# -- priorities: '*:*' beside a sub-connector -------------------------------------------------------

def test_star_ranges_over_connectors_that_fire_on_their_own():
    """No cycle: '*:*' beside 'all' names no connector, since 'pair' only fires inside 'all'."""
    e = engine("StarBesideSub")
    s = e.initial_state()
    assert labels(e, s) == ["all"]
    assert labels(e, walk(e, "all")) == []


# -- a rendezvous of sub-connectors that only gather ports -----------------------------------------

GATHERED = """package Gathered
  port type Port()
  connector type Pair(Port a, Port b)
    export port Port e()
    define a b
  end
  connector type Two(Port a, Port b)
    define a b
  end
  connector type Picky(Port a, Port b)
    define a b
    on a b provided (false)
  end
  atom type Step()
    data int n
    export port Port p()
    place S
    initial to S do { n = 0; }
    on p from S to S provided (n < 2) do { n = n + 1; }
  end
  compound type Task()
    component Step timer(), scheduler()
    connector Pair tick(timer.p, scheduler.p)
    export port tick.e as tick
  end
  compound type System()
    component Task task()
    component Step poster(), other()
    connector Two run(task.tick, poster.p)
    connector Picky never(task.tick, other.p)
  end
end
"""


def test_a_rendezvous_of_gathering_sub_connectors_is_one_rendezvous_of_its_leaves():
    from runtime.bip2 import parse_text
    from runtime.engine import Engine

    e = Engine(parse_text(GATHERED), "System()")
    kinds = {src.connector.path: src.kind for src in e.sources if src.connector is not None}
    assert kinds == {"run": "rendezvous", "never": "rendezvous"}  # a guard on the top connector collapses too
    never = next(src for src in e.sources if src.connector is not None and src.connector.path == "never")
    assert [p.path for p in map(e.flat.ports.__getitem__, never.leaves)] == ["task.timer.p", "task.scheduler.p",
                                                                             "other.p"]
    s = e.initial_state()
    (run,) = e.enabled(s)
    assert run.ports == ("task.timer.p", "task.scheduler.p", "poster.p")
    s = e.fire(e.fire(s, run), run)
    assert e.enabled(s) == []
    assert [atom(e, s, a)["data"]["n"] for a in ("task.timer", "task.scheduler", "poster", "other")] == [2, 2, 2, 0]


CARRIED = """package Carried
  port type Port()
  port type Flag(bool x)
  port type Bools1(bool v1)
  connector type Up(Flag a, Port b)
    data bool v1
    export port Bools1 e(v1)
    define a b
    on a b up { v1 = a.x; }
  end
  connector type Guarded(Bools1 t, Port c)
    define t c
    on t c provided (t.v1)
  end
  atom type Holder()
    data bool x
    export port Flag f(x)
    export port Port flip()
    place S
    initial to S do { x = false; }
    on f from S to S
    on flip from S to S do { x = !x; }
  end
  atom type Step()
    export port Port p()
    place S
    initial to S
    on p from S to S
  end
  compound type Group()
    component Holder h()
    component Step s()
    connector Up gather(h.f, s.p)
    export port gather.e as e
    export port h.flip as flip
  end
  connector type One(Port a)
    define a
  end
  compound type System()
    component Group g()
    component Step c()
    connector Guarded go(g.e, c.p)
    connector One flip(g.flip)
  end
end
"""


def test_a_guard_reading_data_carried_up_by_sub_connectors_reads_the_ports_themselves():
    from runtime.bip2 import parse_text
    from runtime.engine import Engine

    e = Engine(parse_text(CARRIED), "System()")
    kinds = {src.connector.path: src.kind for src in e.sources if src.connector is not None}
    assert kinds["go"] == "rendezvous"  # collapsed: one guarded rendezvous of the three atom ports
    s = e.initial_state()
    assert [i.label for i in e.enabled(s)] == ["flip"]  # g.h.x is false: the guard refuses go
    s = e.fire(s, e.enabled(s)[0])
    assert sorted(i.label for i in e.enabled(s)) == ["flip", "go"]
    (go,) = [i for i in e.enabled(s) if i.label == "go"]
    assert go.ports == ("g.h.f", "g.s.p", "c.p")


# -- maximal progress off (the Verimag engine's --disable-maximal-progress) --------------------------

def test_without_maximal_progress_every_enabled_interaction_is_offered():
    from enginekit import package
    e = Engine(package("Broadcast"), "System()", maximal_progress=False)
    got = labels(e, e.initial_state())
    assert len(got) == 8 and got[0] == "bc[snd.snd]" and got[-1] == "bc"   # every subset with the trigger
    e = Engine(package("Priorities"), "High()", maximal_progress=False)
    assert labels(e, e.initial_state()) == ["bc[S.snd]", "bc[S.snd,R1.rcv]", "bc[S.snd,R2.rcv]", "bc"]  # tk still waits


# -- merged atom port export (export port T p(), q() as e) ---------------------------------------

def test_merged_atom_ports_offer_each_enabled_port_with_its_own_data():
    from runtime.bip2 import parse_file
    from enginekit import FIXTURES
    e = Engine(parse_file(FIXTURES.parent / "bip" / "roundtrip" / "rt_merged.bip"), "Top()")
    s = e.initial_state()
    got = e.enabled(s)
    assert [i.ports for i in got] == [("src.p", "snk.in")]   # r's guard is false, q < p
    new, values = e.fire_traced(s, got[0])
    assert values["snk.in"] == {"d": 1}                       # x, carried by p
    assert e.describe_state(new)["src"]["places"] == ["Done"]


def test_a_compound_offers_only_the_maximal_interactions_of_an_exported_connector_port():
    e = engine("ExportedProgress", "Top()")
    assert labels(e, e.initial_state()) == ["in.high[a.p,d.p]", "in.high[b.p,d.p]"]   # no single[in.a.p]
