"""Helpers of the compiled-exploration tests: compare the C step with the Python step state by state."""
from __future__ import annotations

import pytest

from runtime.engine.errors import EngineError
from runtime.explore import StateSpace
from runtime.native.build import compiler
from runtime.native.compiled import CompiledSpace, compile_space

needs_cc = pytest.mark.skipif(compiler() is None, reason="no C compiler (gcc) on PATH")


def compiled(space: StateSpace) -> CompiledSpace:
    cs, note = compile_space(space)
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
