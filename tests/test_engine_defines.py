"""``define`` semantics against a literal reading of the BIP2 reference, and the generic path against the fast one."""
import random
from itertools import product

import pytest
from enginekit import engine
from hypothesis import given, settings
from hypothesis import strategies as st

import runtime.engine.engine as engine_module
from runtime.engine import defines
from runtime.engine.defines import compile_define
from runtime.engine.plan import plan as real_plan
from runtime.model import DefineGroup, DefinePort


def family(node):
    """Every interaction of a define tree, straight from the reference's recursive definition."""
    if node[0] == "p":
        return {node[1]}
    subs = [family(sub) | {0} for sub, _ in node[1]]
    triggers = [t for _, t in node[1]]
    out = set()
    for combo in product(*subs):
        union = 0
        for m in combo:
            union |= m
        if not union:
            continue
        if any(t and m for t, m in zip(triggers, combo)) or all(combo):
            out.add(union)
    return out


def tree(text):
    """Parse ``(p q)' r s`` into a define tree over ports named by single letters."""
    tokens = text.replace("(", " ( ").replace(")", " ) ").replace("'", " ' ").split()
    names = sorted({t for t in tokens if t.isalpha()})

    def group(i):
        items = []
        while i < len(tokens) and tokens[i] != ")":
            if tokens[i] == "(":
                sub, i = group(i + 1)
                i += 1
            else:
                sub, i = DefinePort(tokens[i]), i + 1
            if i < len(tokens) and tokens[i] == "'":
                sub.trigger, i = True, i + 1
            items.append(sub)
        return DefineGroup(items), i

    g, _ = group(0)
    index = {n: k for k, n in enumerate(names)}
    return compile_define(g, index, "test"), index


def sets(masks, index):
    names = sorted(index, key=index.get)
    return sorted(",".join(n for n in names if m >> index[n] & 1) for m in masks)


def test_reference_examples():
    t, ix = tree("(p q)' r s")
    assert sets(family(t), ix) == sets(defines.subsets(t, 15), ix) == ["p,q", "p,q,r", "p,q,r,s", "p,q,s"]
    t, ix = tree("p' q r")
    assert sets(defines.subsets(t, 7), ix) == ["p", "p,q", "p,q,r", "p,r"]
    t, ix = tree("p q r")
    assert sets(defines.subsets(t, 7), ix) == ["p,q,r"] and defines.subsets(t, 3) == []


def test_broadcast_has_every_subset_with_the_trigger():
    t, ix = tree("s' a b c")
    s = 1 << ix["s"]
    assert len(defines.subsets(t, 15)) == 8 and all(m & s for m in defines.subsets(t, 15))
    assert defines.max_allowed(t, 15 & ~s) == 0


@st.composite
def define_trees(draw, depth=0):
    n = draw(st.integers(1, 3 if depth else 4))
    items = []
    for _ in range(n):
        if depth < 2 and draw(st.integers(0, 3)) == 0:
            items.append(draw(define_trees(depth + 1)))
        else:
            items.append("x")
    trig = [draw(st.booleans()) for _ in items]
    return ("G", list(zip(items, trig)))


def build(shape):
    counter = [0]

    def walk(s):
        if s == "x":
            counter[0] += 1
            return ("p", 1 << (counter[0] - 1))
        return ("g", tuple((walk(sub), t) for sub, t in s[1]))
    return walk(shape), counter[0]


@settings(max_examples=200, deadline=None)
@given(define_trees(), st.data())
def test_searches_agree_with_the_definition(shape, data):
    t, n = build(shape)
    fam = family(t)
    full = (1 << n) - 1
    enabled = data.draw(st.integers(0, full))
    inside = {m for m in fam if m & enabled == m}
    assert set(defines.subsets(t, enabled)) == inside
    assert all(defines.allowed(t, m) == (m in fam) for m in range(full + 1))
    top = defines.max_allowed(t, enabled)
    assert top == (max(inside, key=lambda m: bin(m).count("1")) if inside else 0)
    assert all(m & top == m for m in inside)                       # the largest contains every other
    blocked = set(data.draw(st.lists(st.sampled_from(sorted(fam)), max_size=6))) if fam else set()
    ok = {m for m in inside if m not in blocked}
    assert defines.maximal_enabled(t, enabled, blocked.__contains__) == defines.maximal(ok)


# -- the generic (enumerating) path computes what the inlined fast path computes ------------------------

def _generic_plan(flat, maximal_progress=True):
    infos, sources = real_plan(flat, maximal_progress)
    for s in sources:
        if s.kind in ("rendezvous", "flat"):
            s.kind = "generic"
    return infos, sources


@pytest.mark.parametrize("name, root", [("Dining", "Table3()"), ("Broadcast", "System()"), ("Priorities", "Low()"),
                                        ("Priorities", "High()"), ("Hierarchy", "System()"),
                                        ("NestedMax", "System(1, 5, 3)")])
def test_generic_path_matches_fast_path(monkeypatch, name, root):
    fast = engine(name, root)
    monkeypatch.setattr(engine_module, "plan", _generic_plan)
    slow = engine(name, root)
    assert "_generic(" in slow.source
    rng = random.Random(1)
    s = fast.initial_state()
    assert s == slow.initial_state()
    for _ in range(60):
        a, b = fast.enabled(s), slow.enabled(s)
        assert [i.label for i in a] == [i.label for i in b]
        if not a:
            break
        i = rng.randrange(len(a))
        s1, v1 = fast.fire_traced(s, a[i])
        s2, v2 = slow.fire_traced(s, b[i])
        assert (s1, v1) == (s2, v2)
        s = s1
