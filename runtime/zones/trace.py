"""A symbolic path made concrete: the time of each step, then the steps replayed on the tick model.

The zone explorer keeps, for each symbolic state, its parent, the interaction
and the clock bounds of the step (runtime/zones/search.py).  Along a path the
clock values are differences of step times (a clock is the time since its last
reset), so every bound is a difference constraint between step times;
Bellman–Ford gives integer times that meet them all, and a goal at the end
(``c >= 7``: the largest value a response time reaches).  The steps are then
replayed on the model with ticks, the reference semantics: the trace printed
is the tick model's own, and the goal is checked on its last state.
"""
from __future__ import annotations

import weakref
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from runtime.explore.space import StateSpace, Step
from runtime.zones import dbm
from runtime.zones.node import Node
from runtime.zones.search import ZoneExplorer
from runtime.zones.tickstep import tick_steps


class ConcretizeError(Exception):
    """The path's bounds have no integer solution (an extrapolated zone), or its replay went elsewhere."""


@dataclass
class TimedStep:
    ticks: int  # ticks before the step
    step: Step


def paths_to(z: ZoneExplorer, node: int, goal: list | None = None, limit: int = 64,
             need: np.ndarray | None = None) -> Iterator[list[Node]]:
    """Paths from an initial state to ``node`` along parent links, each merged zone on the way replaced by the
    part the path goes through, at most ``limit`` of them.  The search goes backwards with the clock values the
    rest of the path needs (the past of time passing, the values before a reset, the step's bounds): a part
    they miss is not tried, so the first path is almost always one that :func:`times` makes concrete.
    ``need``: the values wanted at ``node`` (a lasso's loop from there, :func:`loop_needs`)."""
    made = 0
    want = need if need is not None else dbm.free_all(z.n)
    want = dbm.constrain_all(want, goal) if goal else want
    if want is None:
        return
    stack: list[tuple[int, np.ndarray, tuple]] = [(node, want, ())]
    while stack and made < limit:
        k, need, after = stack.pop()
        for a in reversed(_parts(z, k)):
            m = z.nodes[a]
            here = dbm.intersect(m.reached, need)
            if here is None:
                continue  # this part holds none of the values the rest of the path needs
            if m.parent < 0:
                made += 1
                yield [m] + _unfold(after)
                continue
            before = _before(z, m, here)
            if before is not None:
                stack.append((m.parent, before, (m, after)))


def loop_needs(z: ZoneExplorer, loop: list[Node]) -> np.ndarray | None:
    """The clock values at a lasso's entry from which one round of ``loop`` can be taken."""
    need = dbm.free_all(z.n)
    for m in reversed(loop):
        zone = m.reached
        here = dbm.intersect(zone, need) if zone is not None else need
        if here is None:
            return None
        grown = m.grown
        if zone is None and grown:  # a step into a covered zone: time passes there only as far as :func:`times` lets it
            limits = _limits(z, m)
            grown = limits is not None
            here = dbm.constrain_all(here, limits[1]) if grown else here
            if here is None:
                return None
        need = _before(z, m, here, grown)
        if need is None:
            return None
    return need


def _unfold(linked: tuple) -> list[Node]:
    out = []
    while linked:
        head, linked = linked
        out.append(head)
    return out


def _before(z: ZoneExplorer, m: Node, here: np.ndarray, grown: bool | None = None) -> np.ndarray | None:
    """The clock values at the step into ``m``'s state from which it reaches ``here`` (its parent's side); ``grown``:
    whether time passes in the state after the step (``m.grown`` unless said)."""
    zone = dbm.down(here) if (m.grown if grown is None else grown) else here
    idle = z.idle(m.state)
    if idle:
        zone = dbm.free_many(zone, idle)
    for c, v in z.guard(m.via, z.nodes[m.parent].state)[1]:
        zone = dbm.constrain_all(zone, [(c, 0, v), (0, c, -v)])
        if zone is None:
            return None
        zone = dbm.free_many(zone, [c])
    return dbm.constrain_all(zone, m.guard)


def _parts(z: ZoneExplorer, k: int) -> list[int]:
    """``k`` and, depth first, the nodes merged into it."""
    out = [k]
    for m in z.nodes[k].members:
        out += _parts(z, m)
    return out


def _covering(z: ZoneExplorer, k: int) -> np.ndarray:
    """The zone of node ``k`` that a step into a covered zone went into; if a larger zone covered ``k`` before it
    was expanded (its zone then let go), that one's, up the chain of covers."""
    while z.nodes[k].stored is None:
        k = z.nodes[k].by
    return z.nodes[k].zone


def _limits(z: ZoneExplorer, n: Node) -> tuple[list, list] | None:
    """How far time may pass at ``n``'s state after the step into it (:meth:`ZoneExplorer.limits` of the zone it
    reached, or of the one covering it); None when it does not pass there."""
    if not n.grown:
        return None
    return z.limits(n.state, n.reached if n.stored is not None else _covering(z, n.by))


def times(z: ZoneExplorer, path: list[Node], goal: list[tuple[int, int, float]]) -> tuple[list[int], int]:
    """Integer times of the steps of ``path`` (each record: the step into it, the first one initial) and the time
    after the last step where ``goal`` holds."""
    k = len(path)
    end, zero = k, k + 1  # time variables: one per step, the goal's time, the constant 0
    edges: list[tuple[int, int, float]] = []  # (w, u, d): u - w <= d

    def le(u, w, d):
        edges.append((w, u, d))

    origin = {c: (zero, v) for c, v in z.model.initial.items()}  # clock -> (step time var, value at reset)
    for c in range(1, z.n + 1):
        origin.setdefault(c, (zero, 0))
    le(0, zero, 0)
    le(zero, 0, 0)

    def bound(i, j, c, at):
        """``xi - xj <= c`` at time variable ``at`` (index 0 is the constant 0)."""
        if i and j:
            (ti, vi), (tj, vj) = origin[i], origin[j]
            le(tj, ti, c - vi + vj)  # (at - ti + vi) - (at - tj + vj) <= c
        elif i:
            ti, vi = origin[i]
            le(at, ti, c - vi)
        elif j:
            tj, vj = origin[j]
            le(tj, at, c + vj)

    for step in range(k):
        n = path[step]
        if step:
            le(step - 1, step, 0)  # time goes forward
            for i, j, c in n.guard:
                bound(i, j, c, step)
            for c, v in z.guard(n.via, path[step - 1].state)[1]:
                origin[c] = (step, v)
        nxt = step + 1 if step + 1 < k else end
        limits = _limits(z, n)
        if limits is None:
            le(nxt, step, 0)
            continue
        for i, j, c in limits[1]:
            bound(i, j, c, nxt)
    le(k - 1, end, 0)
    for i, j, c in goal:
        bound(i, j, c, end)
    dist = _shortest(k + 2, edges)
    base = dist[zero]
    return [int(dist[s] - base) for s in range(k)], int(dist[end] - base)


def _shortest(n: int, edges: list[tuple[int, int, float]]) -> list[float]:
    """Bellman–Ford from a virtual source at distance 0 of every variable; raises on a negative cycle.

    Each round relaxes every edge at once in numpy (a path's few thousand bounds: about 9 times faster than a
    loop over them in Python, the same distances, as shortest distances are unique)."""
    if not edges:
        return [0.0] * n
    e = np.asarray(edges, dtype=np.float64)
    w, u, d = e[:, 0].astype(np.intp), e[:, 1].astype(np.intp), e[:, 2]
    dist = np.zeros(n)
    for _ in range(n + 1):  # a shortest path has at most n - 1 edges: one more round shows they are all found
        new = dist.copy()
        np.minimum.at(new, u, dist[w] + d)
        if np.array_equal(new, dist):
            return dist.tolist()
        dist = new
    raise ConcretizeError("the path's clock bounds have no solution")


#: Per zone explorer, the erased state of each tick model state its traces went through.
_ERASED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def replay(z: ZoneExplorer, path: list[Node], goal: list[tuple[int, int, float]],
           space: StateSpace) -> tuple[list[TimedStep], tuple]:
    """``path`` (:func:`paths_to`, or a lasso's prefix and loop) on the tick model ``space``: steps with the ticks
    before each, and the last state.  Each step and each tick is one of the tick model's successors where the
    trace is (runtime/zones/tickstep.py: computed once per state for every trace of the model)."""
    at, end = times(z, path, goal)
    steps = tick_steps(space, z.externs)
    state = space.state(space.initial_ids[0])
    ticks_before, out = 0, []
    clocks = {z.flat.atoms[a].slot(v) for a, v in z.model.clocks}

    errors = {}
    for a, (watching, _, _) in z.model.observers.items():  # the erased model has no observer in ERROR
        fa = z.flat.atoms[a]
        if "ERROR" in fa.places:
            errors[fa.offset] = (fa.place_mask(["ERROR"]), fa.place_mask([watching]))

    memo = _ERASED.setdefault(z, {})  # the traces of one search meet the same states

    def erased(full: tuple) -> tuple:
        got = memo.get(full)
        if got is not None:
            return got
        values = list(full[:z.space.width])
        for s in clocks:
            values[s] = 0
        for offset, (error, watching) in errors.items():
            if values[offset] == error:
                values[offset] = watching
        got = memo[full] = z.space.canonical(tuple(values) + tuple(full[z.space.width:]))
        return got

    def tick(s: tuple, count: int) -> tuple:
        for _ in range(count):
            nxt = [n for inter, n in steps.successors(s) if inter.label == "tick"]
            if len(nxt) != 1:
                raise ConcretizeError("time cannot pass where the zones said it could")
            s = nxt[0]
        return s

    for step in range(1, len(path)):
        n = path[step]
        wait = at[step] - at[step - 1]
        state = tick(state, wait)
        _, ports, label = z.interaction(n.via)
        target = z.space.canonical(n.state)
        for inter, nxt in steps.successors(state):
            if inter.label == label and erased(nxt) == target:
                out.append(TimedStep(wait, steps.step(state, inter, nxt)))
                state = nxt
                break
        else:
            raise ConcretizeError(f"step {step} ({label}) has no counterpart on the tick model")
    state = tick(state, end - at[-1])
    ticks_before = end - at[-1]
    if ticks_before:
        out.append(TimedStep(ticks_before, Step("", -1, (), ())))
    return out, state
