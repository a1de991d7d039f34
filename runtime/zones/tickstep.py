"""The tick model's steps as a trace's replay asks for them: each state's successors once, the codel outcomes of
the steps taken.

A trace of the zone search is replayed on the tick model (runtime/zones/trace.py): at each of its states it
needs the tick model's successors, to find the step the path takes and to see that time may pass.  They are
the tick model's own (enabled interactions after maximal progress and priorities), in the order
``StateSpace._fire_all`` gives them, computed once per state for all the traces of one check: by the model's
compiled step where it compiles (the same semantics, generated from the same flat model, without the Python
engine's enumeration of every nested connector in every state), else by the Python engine.  The codel
outcomes of a step taken are the Python engine's, firing that one interaction.
"""
from __future__ import annotations

from typing import Any

from runtime.engine import Interaction
from runtime.engine.errors import EngineError
from runtime.explore.space import StateSpace, Step


class TickSteps:
    """Successors of the states of a tick model ``space`` (explorer states), kept per state."""

    def __init__(self, space: StateSpace, externs: dict[str, Any] | None = None, compiled: bool = True) -> None:
        self.space, self.externs = space, externs
        self._want_compiled = compiled
        self._compiled = None
        self._tried = False
        self._succ: dict[tuple, list[tuple[Interaction, tuple]]] = {}
        self._steps: dict[tuple, Step] = {}  # the traces of one model share their beginnings
        self._made: dict[tuple, list[tuple]] = {}  # Python's successors where they were computed: their outcomes
        self.note = ""

    def compiled(self):
        """The tick model's compiled step (built on first use), or None where it does not compile."""
        if not self._tried:
            self._tried = True
            if self._want_compiled:
                from runtime.native.compiled import compile_space

                self._compiled, self.note = compile_space(self.space, self.externs, wide_fields=True)
        return self._compiled

    def successors(self, state: tuple) -> list[tuple[Interaction, tuple]]:
        """``(interaction, next state)`` of every step of the tick model from ``state``, in the engine's order."""
        got = self._succ.get(state)
        if got is None:
            cs = self.compiled()
            got = None
            if cs is not None:
                try:
                    got = [(self.space.interaction(i), nxt) for i, nxt in cs.successors(state)]
                except EngineError:
                    got = None  # the C step stopped (an error it reports by a code): the engine's own words
            if got is None:
                fired = self.space._fire_all(state)
                self._made[state] = fired
                got = [(inter, nxt) for inter, nxt, _ in fired]
            self._succ[state] = got
        return got

    def step(self, state: tuple, inter: Interaction, nxt: tuple) -> Step:
        """The trace step of ``inter`` from ``state`` to ``nxt`` (one of :meth:`successors`), with the codel outcomes
        that lead there."""
        key = (state, inter.index, nxt)
        got = self._steps.get(key)
        if got is None:
            got = self._steps[key] = self._step(state, inter, nxt)
        return got

    def _step(self, state: tuple, inter: Interaction, nxt: tuple) -> Step:
        fired = self._made.get(state)
        if fired is not None:
            for i, n, made in fired:
                if i is inter and n == nxt:
                    return _step(inter, made)
        space = self.space
        fired = space.fire_one(state, inter)
        if len(fired) == 1 and sum(1 for i, _ in self.successors(state) if i is inter) == 1:
            return _step(inter, fired[0][1])  # one outcome vector on both sides: the same step
        want = space.canonical(nxt)
        for n, made in fired:
            if space.canonical(n) == want:
                return _step(inter, made)
        raise EngineError(f"internal: the tick model's step {inter.label} does not fire again to the same state")


def _step(inter: Interaction, made: tuple) -> Step:
    return Step(inter.label, inter.index, tuple((c.name, p) for c, p in made), tuple(c.describe(p) for c, p in made))


def tick_steps(space: StateSpace, externs: dict[str, Any] | None = None) -> TickSteps:
    """The :class:`TickSteps` of ``space``, made on first use and kept on it (they go with it)."""
    got = getattr(space, "tick_steps", None)
    if got is None:
        got = space.tick_steps = TickSteps(space, externs)
    return got
