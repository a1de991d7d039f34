"""Interaction numbers of the compiled search: a rendezvous of any width, models past 32-bit numbers, both layouts."""
from __future__ import annotations

import pytest

from runtime.engine import flatten
from runtime.explore import StateSpace, explore
from runtime.native.compiled import compile_space
from runtime.native.numbering import Numbering
from runtime.native.properties import compiled_check
from runtime.props import check, read_properties
from tests import enginekit, verifykit
from tests.nativekit import agree, compiled, needs_cc
from tests.test_native_cover import timed, wide

pytestmark = needs_cc


def chain(n: int) -> str:
    """A token handed down n workers, a counter of 3 ticks, all on one tick rendezvous (n + 1 ports).

    The tick is low in a priority against a pass, and a broadcast gives a source of several interactions.
    Deadlock: the token at the last worker and the counter at 3; shortest after n passes, a tick and the
    ping that takes the counter from 1 to 3.
    """
    workers = "\n".join(f"    component W w{i}()" for i in range(n))
    passes = "\n".join(f"    connector Pair pass{i}(w{i}.give, w{i + 1}.take)" for i in range(n - 1))
    ticks = ", ".join(f"w{i}.tick" for i in range(n))
    return f"""package Chain
  port type Port()
  atom type W()
    export port Port tick(), give(), take(), ping()
    place IDLE, HOLD
    initial to IDLE
    on tick from IDLE to IDLE
    on tick from HOLD to HOLD
    on take from IDLE to HOLD
    on give from HOLD to IDLE
    on ping from HOLD to HOLD
  end
  atom type First()
    export port Port tick(), give(), ping()
    data int c
    place START, GONE
    initial to START
    on give from START to GONE
    on tick from START to START provided (c < 3) do {{ c = c + 1; }}
    on tick from GONE to GONE provided (c < 3) do {{ c = c + 1; }}
    on ping from GONE to GONE provided (c == 1) do {{ c = 3; }}
  end
  connector type Pair(Port a, Port b)
    define a b
  end
  connector type Tick(Port f, {', '.join(f'Port p{i}' for i in range(n))})
    define f {' '.join(f'p{i}' for i in range(n))}
  end
  connector type Bcast(Port s, Port a, Port b)
    define s' a b
  end
  compound type Main()
    component First f()
{workers}
    connector Pair start(f.give, w0.take)
{passes}
    connector Tick tick(f.tick, {ticks})
    connector Bcast ping(f.ping, w1.ping, w2.ping)
    priority late tick:* < pass2:*
  end
end
"""


def same_search(make, wide_numbers: bool = False) -> tuple:
    """The Python and the compiled search of ``make()``: same counts, deadlocks and traces; every state agrees."""
    python = make()
    ours = explore(python)
    cs, note = compile_space(make(), wide_numbers=wide_numbers)
    assert cs is not None, note
    theirs = cs.explore()
    assert (theirs.states, theirs.transitions, theirs.depth, theirs.complete) == \
        (ours.states, ours.transitions, ours.depth, ours.complete)
    assert theirs.deadlocks == ours.deadlocks
    for sid in ours.deadlocks + [ours.states - 1]:
        assert [str(s) for s in cs.trace_to(sid)] == [str(s) for s in python.trace_to(sid)]
    space = make()
    assert agree(space, compiled(space), limit=ours.states) == ours.states
    return ours, theirs, cs


@pytest.mark.parametrize("wide_numbers", [False, True])
def test_a_tick_over_41_ports_and_42_sources_searches_as_the_python_step(wide_numbers):
    ours, theirs, cs = same_search(lambda: verifykit.text_space(chain(40)), wide_numbers)
    assert (ours.states, ours.depth, len(ours.deadlocks)) == (164, 42, 1)
    trace = [str(s) for s in cs.trace_to(ours.deadlocks[0])]
    assert trace[-3:] == ["pass38", "tick", "ping[f.ping]"] and len(trace) == 42  # start, 39 passes, tick, ping
    sources = cs.engine.sources
    tick = next(s for s in sources if s.connector is not None and s.connector.path == "tick")
    assert len(tick.leaves) == 41 and tick.full * len(sources) >= 1 << 32  # past both of the old limits
    assert cs.lib.c_via_bits() == (64 if wide_numbers else 32)


def test_a_rendezvous_past_64_ports_is_searched():
    """The rendezvous' mask (71 bits) is never computed in C: the search takes it as any other."""
    cs = compiled(verifykit.text_space(chain(70)))
    result = cs.explore()
    assert (result.states, result.depth, len(result.deadlocks)) == (284, 72, 1)
    trace = [str(s) for s in cs.trace_to(result.deadlocks[0])]
    assert trace[:2] == ["start", "pass0"] and trace[-3:] == ["pass68", "tick", "ping[f.ping]"] and len(trace) == 72


def test_observers_and_priorities_over_a_wide_rendezvous_give_the_python_verdicts():
    pkg = verifykit.text_space(chain(40)).engine.flat.package
    text = ('early: [ (not "tick")* . "pass5" ] false; '
            'pinged: [ true* . optional "ping[f.ping]" ] false; '
            'all_three: [ true* . "ping" ] false; '  # w1 and w2 never hold the token at once
            'last: invariant not w39 @ HOLD; '
            'ticked: [ true* . "tick" . "tick" . "tick" . "tick" ] false')
    items, _ = read_properties(text, "p.mcl", flatten(pkg, "Main()"))
    observed = set().union(*(i.observed for i in items))
    found = {}
    for item in items:
        ours = check(StateSpace(pkg, "Main()", observed=observed), item)
        theirs = compiled_check(StateSpace(pkg, "Main()", observed=observed), item)
        assert theirs is not None, item.name
        assert theirs.holds == ours.holds, item.name
        assert [str(s) for s in theirs.trace] == [str(s) for s in ours.trace], item.name
        found[item.name] = (theirs.holds, len(theirs.trace))
    assert found == {"early": (False, 7), "pinged": (False, 3), "all_three": (True, 0), "last": (False, 40),
                     "ticked": (True, 0)}


def test_a_timed_level_with_a_tick_over_37_ports_agrees_with_the_python_step():
    package, root = timed("tests/fixtures/timed/Fleet.gen", "Fleet")
    space = StateSpace(package, root)
    tick = next(s for s in space.engine.sources if s.connector is not None and s.connector.label == "tick")
    assert len(tick.leaves) == 37 and tick.full * len(space.engine.sources) >= 1 << 32
    assert agree(space, compiled(space), limit=400) == 400
    # depth 6: 27,861 states and 124,423 transitions, every tick's 37 ports taking part many times (depth 8's
    # 158,421 states took the Python reference 20 s of the suite's ten minutes, depth 12's 1.5 M three minutes)
    ours = explore(StateSpace(package, root), max_depth=6)
    theirs = compiled(StateSpace(package, root)).explore(max_depth=6)
    assert (theirs.states, theirs.transitions, theirs.stopped_by) == (ours.states, ours.transitions, "max-depth")


def test_numbers_past_32_bits_take_the_64_bit_layout():
    """A broadcast of 32 ports has 2^32 masks: its numbers do not fit in 32 bits, the search stores 64."""
    space = verifykit.text_space(wide(31, False))
    cs = compiled(space)
    assert (cs.model.numbering.bits, cs.model.numbering.total, cs.lib.c_via_bits()) == (64, 1 << 32, 64)
    assert agree(space, cs) == len(space) == 2
    result = cs.explore()
    assert result.states == 2
    assert [str(s) for s in cs.trace_to(1)] == [str(s) for s in space.trace_to(1)]


@pytest.mark.parametrize("make", [
    lambda: verifykit.text_space(chain(40)),
    lambda: StateSpace(enginekit.package("Hierarchy"), "System()"),
    lambda: StateSpace(enginekit.package("NestedAny"), "System()"),
    lambda: StateSpace(*verifykit.ndd_model()),
    lambda: StateSpace(*timed("tests/fixtures/timed/Fleet.gen", "Fleet")),
], ids=["chain", "hierarchy", "nested", "ndd", "fleet"])
def test_every_interaction_number_round_trips(make):
    space = make()
    engine = space.engine
    cs = compiled(space)
    numbering = cs.model.numbering
    seen = set()
    for src in engine.sources:
        masks = [src.full] if src.kind in ("rendezvous", "port") else range(1, src.full + 1)
        for mask in masks:
            number = numbering.number(src.index, mask)
            assert numbering.interaction(number) == (src.index, mask)
            assert cs.interaction_index(number) == engine._make(src.index, mask).index
            seen.add(number)
    # dense: every number names an interaction, the empty masks aside
    empties = {numbering.offsets[s.index] for s in engine.sources if s.kind not in ("rendezvous", "port")}
    assert seen | empties == set(range(numbering.total)) and not seen & empties


def test_numbers_that_name_no_interaction_are_refused():
    numbering = Numbering.of(verifykit.text_space(chain(5)).engine.sources)
    assert (numbering.total, numbering.bits) == (6 + 8, 32)  # 6 rendezvous, then a broadcast of 3 ports from 6
    assert numbering.interaction(5) == (5, 63) and numbering.interaction(6 + 5) == (6, 5)
    for bad, message in ((-1, "interaction number -1 out of 0..13"), (14, "interaction number 14 out of 0..13"),
                         (6, "interaction number 6 is the empty interaction of source 6")):
        with pytest.raises(ValueError) as err:
            numbering.interaction(bad)
        assert str(err.value) == message
