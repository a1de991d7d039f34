"""The state space of a model, discovered lazily: numbered packed states, their successors, their parents.

``StateSpace`` owns an :class:`~runtime.engine.Engine` built with choice-point
externs, and a successor function generated for the model that unpacks a
state, asks the engine for the enabled interactions, fires each one once per
combination of codel outcomes, and packs the results.  Every state gets a
number in order of discovery (0 is the initial state), a parent and the
interaction that first reached it: breadth-first discovery makes the path
back to 0 a shortest one.  Successor lists are kept when asked (exports,
properties) as flat tuples ``(label, target, label, target, ...)``.
"""
from __future__ import annotations

import sys
from array import array
from dataclasses import dataclass
from typing import Any, Iterable

from runtime.engine import Engine, Interaction
from runtime.engine.emit import PythonWriter
from runtime.engine.errors import ExternError, ModelError
from runtime.engine.extern_ports import refuse_extern_data
from runtime.engine.source import compile_generated
from runtime.explore.choices import (
    Environment,
    ExploreError,
    Oracle,
    bind_for_exploration,
    outcome_vectors,
    request_services,
    unbound_message,
)
from runtime.explore.codec import Codec, Widen
from runtime.explore.layout import Slot, layout
from runtime.model import Package


class LimitReached(Exception):
    """The state budget is spent: the answer being computed is not known on the whole state space."""


@dataclass(frozen=True)
class Step:
    """One transition of a trace: the interaction's label and index, and the codel outcomes it took."""

    label: str
    index: int
    outcomes: tuple[tuple[str, int], ...] = ()  # (codel/extern name, position in its domain)
    outcome_names: tuple[str, ...] = ()  # "nddPlan -> arrived"

    def __str__(self) -> str:
        return self.label + (f"  [{', '.join(self.outcome_names)}]" if self.outcome_names else "")


class StateSpace:
    """A model's reachable states, numbered as they are discovered.

    ``package``/``root`` as for the engine; ``externs`` binds extern functions
    that are neither codels nor the request externs (a :class:`Choice` makes
    one a choice point); ``requests`` bounds the requests each service may
    receive (None: any number, one at a time as the model allows);
    ``reduce`` resets dead variables; ``observed`` lists ``(atom, variable)``
    pairs that must stay exact (a property reads them); ``keep_edges`` keeps
    every successor list; ``max_states`` bounds the states numbered.
    """

    def __init__(self, package: Package, root: str, externs: dict[str, Any] | None = None,
                 requests: int | None = None, reduce: bool = True, observed: Iterable[tuple[str, str]] = (),
                 keep_edges: bool = False, max_states: int | None = None) -> None:
        self.oracle = Oracle()
        self.environment = Environment(requests)
        bound = bind_for_exploration(package, externs, self.oracle, self.environment)
        try:
            self.engine = Engine(package, root, bound)
        except ExternError as err:
            raise ExploreError(unbound_message(err.missing)) from None
        refuse_extern_data(self.engine.flat)  # a dataless extern port is an environment choice
        self.services = request_services(package) if requests is not None else []
        for k, name in enumerate(self.services):
            self.environment.services[name] = k
        self.width = self.engine.flat.state_size
        self.slots: list[Slot] = layout(self.engine.flat, reduce, observed, len(self.services))
        self.codec = Codec.build(self.slots)
        self._expand = self._generate()
        self.keep_edges = keep_edges
        self.max_states = max_states
        self.ids: dict[int, int] = {}
        self.packed: list[int] = []
        self.parent = array("q")
        self.via = array("q")
        self.edges: dict[int, tuple[int, ...]] = {}
        self.labels: list[str] = []
        self._label_ids: dict[str, int] = {}
        self._label_of: dict[int, int] = {}
        self.transitions = 0
        self._initial()

    # -- states ----------------------------------------------------------------------------------
    def _pack(self, state: tuple) -> int:
        while True:
            try:
                return self.codec.pack(state)
            except Widen as w:
                self._widen(w.slot)

    def canonical(self, state: tuple) -> tuple:
        """``state`` as the explorer keeps it (slots it holds constant at their value).  Packing comes first: it
        may widen the codec, and the packed number means something only to the codec that made it."""
        packed = self._pack(state)
        return self.codec.unpack(packed)

    def _widen(self, slot: int) -> None:
        """Regenerate the codec with a wider field for ``slot`` and re-pack every stored state."""
        old = self.codec
        new = old.widened(slot)
        states = [old.unpack(p) for p in self.packed]
        self.codec = new
        self.packed = [new.pack(s) for s in states]
        self.ids = {p: i for i, p in enumerate(self.packed)}
        self._expand = self._generate()

    def _generate(self):
        """The model's successor function: packed state -> [(interaction, packed next state)], one per outcome vector.

        Generated so that the common case (an interaction that calls no codel)
        is one call of the engine's compiled ``enabled`` and of its firing
        function, and one ``pack``; codel calls divert to the odometer.
        """
        width, env = self.width, bool(self.services)
        w = PythonWriter()
        with w.block("def expand(p)"):
            w("s = _unpack(p)")
            if env:
                w(f"base = s[:{width}]")
                w(f"counts = s[{width}:]")
                w("_env.current = counts")
            else:
                w("base = s")
            w("_oracle.in_guard = True")
            with w.block("try"):
                w("en = _enabled(base)")
            with w.block("finally"):
                w("_oracle.in_guard = False")
            w.if_then("_oracle.guard_call is not None", "_guard()")
            w("out = []")
            with w.block("for I in en"):
                w("_calls.clear()")
                w("_script.clear()")
                if env:
                    w("_env.taken.clear()")
                w("t = _FIRE[I.source](base, I.mask, None)")
                w.if_then("_calls", "_branches(base, I, out)")
                w.else_then("out.append((I, _pack(t + _env.after(counts))))" if env else "out.append((I, _pack(t)))")
            w("return out")
        self.expand_source = w.source()
        ns = {"_unpack": self.codec.unpack, "_pack": self.codec.pack, "_env": self.environment,
              "_oracle": self.oracle, "_enabled": self.engine.step.enabled,
              "_FIRE": self.engine.step.fire, "_calls": self.oracle.calls, "_script": self.oracle.script,
              "_guard": self._guard_error, "_branches": self._branches}
        exec(compile_generated(self.expand_source, "explorer successors"), ns)  # noqa: S102 - generated here
        return ns["expand"]

    def _guard_error(self) -> None:
        name, self.oracle.guard_call = self.oracle.guard_call, None
        raise ExploreError(f"extern {name} has a finite set of outcomes and is called in a guard; "
                           "exploration can branch only in actions")

    def _branches(self, base: tuple, inter: Interaction, out: list) -> None:
        """Every outcome vector of ``inter`` at ``base`` (the odometer), appended to ``out`` packed."""
        counts = self.environment.current
        fire = self.engine.step.fire[inter.source]
        oracle, env = self.oracle, self.environment
        oracle.start()
        while True:
            env.taken.clear()
            nxt = fire(base, inter.mask, None)
            if self.services:
                nxt = nxt + env.after(counts)
            out.append((inter, self.codec.pack(nxt)))
            script = oracle.next_script()
            if script is None:
                return
            oracle.start(script)

    def _add(self, packed: int, parent: int, via: int) -> int:
        got = self.ids.get(packed)
        if got is not None:
            return got
        n = len(self.packed)
        if self.max_states is not None and n >= self.max_states:
            raise LimitReached(n)
        self.ids[packed] = n
        self.packed.append(packed)
        self.parent.append(parent)
        self.via.append(via)
        return n

    def state(self, sid: int) -> tuple:
        """The explorer's state number ``sid`` (engine slots, then request counts)."""
        return self.codec.unpack(self.packed[sid])

    def engine_state(self, sid: int) -> tuple:
        return self.state(sid)[: self.width]

    def __len__(self) -> int:
        return len(self.packed)

    def _initial(self) -> None:
        env = (0,) * len(self.services)
        self.environment.current = env
        starts = []
        for state, _ in outcome_vectors(self.oracle, self.engine.initial_state):
            starts.append(self._pack(state + self.environment.after(env)))
        self.initial_ids = []
        for p in starts:
            self.initial_ids.append(self._add(p, -1, -1))

    # -- successors --------------------------------------------------------------------------------
    def label_id(self, inter: Interaction) -> int:
        got = self._label_of.get(inter.index)
        if got is None:
            label = inter.label
            got = self._label_ids.get(label)
            if got is None:
                got = self._label_ids[label] = len(self.labels)
                self.labels.append(label)
            self._label_of[inter.index] = got
        return got

    def _fire_all(self, state: tuple) -> list[tuple[Interaction, tuple, tuple]]:
        """Every (interaction, next explorer state, choices made) from an explorer state."""
        engine, oracle, env = self.engine, self.oracle, self.environment
        base = state[: self.width]
        counts = state[self.width:]
        env.current = counts
        oracle.in_guard = True
        try:
            enabled = engine.enabled(base)
        finally:
            oracle.in_guard = False
        if oracle.guard_call is not None:
            raise ExploreError(f"extern {oracle.guard_call} has a finite set of outcomes and is called in a guard; "
                               "exploration can branch only in actions")
        out = []
        for inter in enabled:
            out += [(inter, nxt, made) for nxt, made in self._outcomes(base, counts, inter)]
        return out

    def fire_one(self, state: tuple, inter: Interaction) -> list[tuple[tuple, tuple]]:
        """``(next explorer state, choices made)`` of one interaction enabled at ``state``, per outcome vector
        (what :meth:`_fire_all` gives for it, without enumerating the others)."""
        self.environment.current = state[self.width:]
        return self._outcomes(state[: self.width], state[self.width:], inter)

    def _outcomes(self, base: tuple, counts: tuple, inter: Interaction) -> list[tuple[tuple, tuple]]:
        engine, oracle, env = self.engine, self.oracle, self.environment
        out = []
        oracle.start()
        while True:
            env.taken.clear()
            nxt = engine.fire(base, inter)
            out.append((nxt + env.after(counts), oracle.made()))
            script = oracle.next_script()
            if script is None:
                return out
            oracle.start(script)

    def successors(self, sid: int) -> tuple[int, ...]:
        """``(label, target, label, target, ...)`` of state ``sid``; new targets are numbered on the way."""
        got = self.edges.get(sid)
        if got is not None:
            return got
        out: list[int] = []
        seen: set[tuple[int, int]] = set()
        packed = self.packed[sid]
        while True:
            try:
                pairs = self._expand(packed)
                break
            except Widen as w:
                self._widen(w.slot)
                packed = self.packed[sid]
            except Exception:
                self._fire_all(self.state(sid))  # the engine's own API words the error
                raise
        for inter, target_packed in pairs:
            target = self._add(target_packed, sid, inter.index)
            lab = self.label_id(inter)
            if (lab, target) not in seen:
                seen.add((lab, target))
                out.append(lab)
                out.append(target)
        self.transitions += len(out) // 2
        result = tuple(out)
        if self.keep_edges:
            self.edges[sid] = result
        return result

    # -- traces ---------------------------------------------------------------------------------------
    def interaction(self, index: int) -> Interaction:
        n = len(self.engine.sources)
        return self.engine.step.interaction(index % n, index // n)

    def step(self, src: int, index: int, dst: int) -> Step:
        """The step from ``src`` to ``dst`` by interaction ``index``, with the codel outcomes that lead there."""
        state = self.state(src)
        target = self.packed[dst]
        for inter, nxt, made in self._fire_all(state):
            if inter.index == index and self._pack(nxt) == target:
                return Step(inter.label, index, tuple((c.name, pos) for c, pos in made),
                            tuple(c.describe(pos) for c, pos in made))
        raise ModelError(f"internal: no step from state {src} to {dst} by interaction {index}")

    def path_to(self, sid: int) -> list[int]:
        """State numbers from an initial state to ``sid`` along discovery parents."""
        path = [sid]
        while self.parent[path[-1]] >= 0:
            path.append(self.parent[path[-1]])
        return path[::-1]

    def trace_to(self, sid: int) -> list[Step]:
        """The steps of the discovery path to ``sid`` (a shortest one after breadth-first discovery)."""
        path = self.path_to(sid)
        return [self.step(a, self.via[b], b) for a, b in zip(path, path[1:])]

    def steps_along(self, states: list[int], labels: list[str] | None = None) -> list[Step]:
        """The steps of a path given by its states (and, to choose among parallel transitions, their labels)."""
        out = []
        for k, (a, b) in enumerate(zip(states, states[1:])):
            for inter, nxt, made in self._fire_all(self.state(a)):
                if self._pack(nxt) == self.packed[b] and (labels is None or inter.label == labels[k]):
                    out.append(Step(inter.label, inter.index, tuple((c.name, pos) for c, pos in made),
                                    tuple(c.describe(pos) for c, pos in made)))
                    break
            else:
                raise ModelError(f"internal: no transition from state {a} to state {b}")
        return out

    def follow(self, sid: int, index: int, outcomes: tuple[int, ...] | list[int]) -> tuple[Step, int]:
        """The step from ``sid`` by interaction ``index`` taking these outcome positions, and the state reached."""
        for inter, nxt, made in self._fire_all(self.state(sid)):
            if inter.index == index and tuple(pos for _, pos in made) == tuple(outcomes):
                target = self._add(self._pack(nxt), sid, index)
                return Step(inter.label, index, tuple((c.name, pos) for c, pos in made),
                            tuple(c.describe(pos) for c, pos in made)), target
        enabled = ", ".join(sorted({i.label for i, _, _ in self._fire_all(self.state(sid))})) or "none"
        raise ModelError(f"the trail does not replay: interaction {self.interaction(index).label} with outcomes "
                         f"{list(outcomes)} is not possible in state {sid} (enabled: {enabled})")

    def concrete(self, steps: list[Step]) -> tuple:
        """The engine's own state at the end of a trace (dead variables as execution leaves them).

        Replays the steps with the engine and the recorded codel outcomes,
        without the explorer's packing or reduction.
        """
        engine, oracle, env = self.engine, self.oracle, self.environment
        starts = [state for state, _ in outcome_vectors(oracle, engine.initial_state)]
        error: Exception | None = None
        for start in starts:
            state, counts = start, (0,) * len(self.services)
            try:
                for step in steps:
                    env.current = counts
                    oracle.in_guard = True
                    try:
                        enabled = {i.index: i for i in engine.enabled(state)}
                    finally:
                        oracle.in_guard = False
                    inter = enabled.get(step.index)
                    if inter is None:
                        raise ModelError(f"step {step.label} is not enabled")
                    oracle.start([pos for _, pos in step.outcomes])
                    env.taken.clear()
                    state = engine.fire(state, inter)
                    counts = env.after(counts)
                return state
            except ModelError as err:
                error = err
        raise error if error else ModelError("no initial state")

    def replay_markers(self, markers: list[tuple[str, int]]) -> tuple[list[Step], int]:
        """Steps from ``@@i``/``@@o`` markers (a SPIN trail), replayed from the initial state; and the end state."""
        groups: list[tuple[int, list[int]]] = []
        for kind, value in markers:
            if kind == "i":
                groups.append((value, []))
            elif groups:
                groups[-1][1].append(value)
        last_error: Exception | None = None
        for start in self.initial_ids:
            try:
                steps, sid = [], start
                for index, outs in groups:
                    step, sid = self.follow(sid, index, outs)
                    steps.append(step)
                return steps, sid
            except ModelError as err:
                last_error = err
        raise last_error if last_error else ModelError("empty trail")

    # -- reporting -------------------------------------------------------------------------------------
    def memory(self, sample: int = 2000) -> int:
        """Bytes held by the visited set (dict, packed states, numbers, parents), estimated from a sample of keys."""
        n = len(self.packed)
        if n == 0:
            return 0
        step = max(1, n // sample)
        picked = self.packed[::step]
        keys = sum(sys.getsizeof(p) for p in picked) * n / len(picked)
        numbers = 28 * max(0, n - 257)  # the dict's values: ints above the small-int cache
        total = sys.getsizeof(self.ids) + sys.getsizeof(self.packed) + keys + numbers
        total += self.parent.buffer_info()[1] * self.parent.itemsize * 2
        return int(total)
