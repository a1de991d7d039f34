"""Helpers of the compiled-exploration tests: compare the C step with the Python step state by state."""
from __future__ import annotations

import pytest
from hypothesis import strategies as st

from runtime.engine.errors import EngineError
from runtime.explore import StateSpace
from runtime.native.build import compiler
from runtime.native.compiled import CompiledSpace, compile_space

needs_cc = pytest.mark.skipif(compiler() is None, reason="no C compiler (gcc) on PATH")


def compiled(space: StateSpace) -> CompiledSpace:
    cs, note = compile_space(space, search=True)
    assert cs is not None, note
    return cs


def python_successors(space: StateSpace, sid: int) -> list[tuple[int, str, tuple]]:
    """(interaction index, label, next state) of state ``sid`` by the Python step, in its order."""
    space.successors(sid)  # numbers the targets, widens the codec if needed, words errors
    return [(i.index, i.label, space.codec.unpack(p)) for i, p in space._expand(space.packed[sid])]


def agree(space: StateSpace, cs: CompiledSpace, limit: int = 2000) -> int:
    """Walk the Python state space breadth-first; at each state both steps give the same successor list.

    A model error must be met by both at the same state.  Returns the number of states compared.
    """
    sid = 0
    while sid < len(space) and sid < limit:
        state = space.state(sid)
        try:
            expected = python_successors(space, sid)
        except EngineError:
            with pytest.raises(EngineError):
                cs.successors(state)
            return sid + 1
        got = [(via, space.interaction(via).label, s) for via, s in cs.successors(state)]
        assert got == expected, f"state {sid}: {state}"
        sid += 1
    return sid


@st.composite
def models(draw, atoms_range=(2, 3), connectors_range=(1, 3), floats: bool = False) -> str:
    """Small random models: atoms with guarded, counting transitions and priorities; rendezvous, broadcasts.

    With ``floats`` every atom also has a float ``f`` that its transitions compute, compare and truncate.
    """
    natoms = draw(st.integers(*atoms_range))
    atoms, comps = [], []
    for a in range(natoms):
        nplaces = draw(st.integers(1, 3))
        places = [f"P{k}" for k in range(nplaces)]
        lines = ["    export data int x"] + (["    data float f"] if floats else []) + [
                 "    export port IntPort p0(x), p1(x)", "    port Port q()",
                 f"    place {', '.join(places)}", f"    initial to P0 do {{ x = {draw(st.integers(0, 2))}; }}"]
        for port in ("p0", "p1", "q", None):
            for _ in range(draw(st.integers(0, 2 if port else 1))):
                src, dst = draw(st.sampled_from(places)), draw(st.sampled_from(places))
                guard = draw(st.sampled_from(["", " provided (x < 2)", " provided (x % 2 == 0)", " provided (x != 1)"]))
                if port is None:
                    if src == dst or guard == "":
                        continue  # an unguarded internal self-loop is a livelock in every state
                    guard = " provided (x == 0)"
                acts = ["", " do { x = (x + 1) % 3; }", " do { x = 2 - x; }", " do { if (x > 0) then x = x - 1; fi }"]
                if floats:
                    extra = draw(st.sampled_from(["", "f < 1.5", "x >= f", "f != 0.75"]))
                    if extra:
                        guard = f" provided ({guard[11:-1] + ' && ' if guard else ''}{extra})"
                    acts += [" do { f = 1.5 - f; }", " do { f = x * 0.75; }", " do { x = f + 0.5; }",
                             " do { f = f / 3.0; x = f * 4.0; }", " do { f = (f + 1.0) % 2.0; }",
                             " do { if (f > x) then f = 0.0; else f = -f; fi }", " do { f = f / x; }"]
                act = draw(st.sampled_from(acts))
                head = f"on {port}" if port else "internal"
                lines.append(f"    {head} from {src} to {dst}{guard}{act}")
        if draw(st.booleans()):
            lines.append("    priority r p0 < p1 provided (x > 0)")
        atoms.append(f"  atom type A{a}()\n" + "\n".join(lines) + "\n  end")
        comps.append(f"    component A{a} a{a}()")
    conns = []
    for c in range(draw(st.integers(*connectors_range))):
        i, j = draw(st.lists(st.integers(0, natoms - 1), min_size=2, max_size=2, unique=True))
        pi, pj = draw(st.sampled_from(["p0", "p1"])), draw(st.sampled_from(["p0", "p1"]))
        kind = draw(st.sampled_from(["Sync", "Bcast"]))
        conns.append(f"    connector {kind} c{c}(a{i}.{pi}, a{j}.{pj})")
    prios = []
    if len(conns) > 1 and draw(st.booleans()):
        prios.append("    priority pr c0:* < c1:* provided (a0.x == 1)")
    return f"""package Random
  port type Port()
  port type IntPort(int v)
{chr(10).join(atoms)}
  connector type Sync(IntPort a, IntPort b)
    define a b
    on a b provided (a.v + b.v < 4) down {{ a.v = b.v; }}
  end
  connector type Bcast(IntPort s, IntPort r)
    define s' r
    on s r down {{ r.v = s.v; }}
  end
  compound type Main()
{chr(10).join(comps)}
{chr(10).join(conns)}
{chr(10).join(prios)}
  end
end
"""
