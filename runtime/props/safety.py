"""``[R] F`` and ``<R> F`` with a fixed-point-free F, by breadth-first search of the state space times R.

These are the common safety shapes (``never``, ``precedes``, ``invariant``,
``deadlock free``, ``leads to ... within N steps``) and their duals.  R becomes
a nondeterministic automaton over action formulas (Thompson construction);
the search visits pairs (state, set of automaton states), so the first pair
where R has matched and F has the wrong value ends a *shortest* path matching
R: the counterexample of ``[R] F`` (or the witness of ``<R> F``), extended by
F's own evidence (a few steps for ``<true> true`` or a bounded response).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from runtime.props.actions import LabelTable
from runtime.props.formulas import Action, RAct, RAlt, Regular, RPlus, RSeq, RStar


@dataclass
class Automaton:
    """States 0..n-1; ``moves[q]`` = [(action index, q')], ``eps[q]`` = [q']; one start, one accepting state."""

    moves: list[list[tuple[int, int]]] = field(default_factory=list)
    eps: list[list[int]] = field(default_factory=list)
    start: int = 0
    accept: int = 0
    actions: list[Action] = field(default_factory=list)

    def state(self) -> int:
        self.moves.append([])
        self.eps.append([])
        return len(self.moves) - 1

    def closure(self, states) -> frozenset[int]:
        out = set(states)
        stack = list(states)
        while stack:
            q = stack.pop()
            for r in self.eps[q]:
                if r not in out:
                    out.add(r)
                    stack.append(r)
        return frozenset(out)


def automaton(r: Regular) -> Automaton:
    """Thompson's construction: one fragment (entry, exit) per regular operator."""
    a = Automaton()
    ids: dict[Action, int] = {}

    def frag(x: Regular) -> tuple[int, int]:
        if isinstance(x, RAct):
            k = ids.setdefault(x.action, len(ids))
            if k == len(a.actions):
                a.actions.append(x.action)
            i, o = a.state(), a.state()
            a.moves[i].append((k, o))
            return i, o
        if isinstance(x, RSeq):
            i1, o1 = frag(x.left)
            i2, o2 = frag(x.right)
            a.eps[o1].append(i2)
            return i1, o2
        if isinstance(x, RAlt):
            i, o = a.state(), a.state()
            for part in (x.left, x.right):
                pi, po = frag(part)
                a.eps[i].append(pi)
                a.eps[po].append(o)
            return i, o
        if isinstance(x, (RStar, RPlus)):
            i, o = a.state(), a.state()
            pi, po = frag(x.operand)
            a.eps[i].append(pi)
            a.eps[po].append(pi)
            a.eps[po].append(o)
            if isinstance(x, RStar):
                a.eps[i].append(o)
            return i, o
        raise TypeError(f"not a regular formula: {x!r}")

    a.start, a.accept = frag(r)
    return a


@dataclass
class Hit:
    """The first state where the automaton accepts and ``found`` says stop: the path there, and its labels."""

    states: list[int]
    labels: list[int]


def search(space, auto: Automaton, found, progress=None) -> Hit | None:
    """Breadth-first over (state, automaton states); ``found(sid)`` is asked where R has just matched."""
    table = LabelTable(auto.actions, space.labels)
    start = [(sid, auto.closure([auto.start])) for sid in space.initial_ids]
    parent: dict[tuple[int, frozenset[int]], tuple[tuple[int, frozenset[int]], int] | None] = {}
    queue = []
    for node in start:
        if node not in parent:
            parent[node] = None
            queue.append(node)
    head = 0
    step_cache: dict[tuple[frozenset[int], int], frozenset[int]] = {}
    while head < len(queue):
        node = queue[head]
        head += 1
        sid, qs = node
        if auto.accept in qs and found(sid):
            states, labels = [sid], []
            cur = node
            while parent[cur] is not None:
                prev, lab = parent[cur]
                labels.append(lab)
                states.append(prev[0])
                cur = prev
            return Hit(states[::-1], labels[::-1])
        succ = space.successors(sid)
        for k in range(0, len(succ), 2):
            lab, target = succ[k], succ[k + 1]
            key = (qs, lab)
            nq = step_cache.get(key)
            if nq is None:
                moved = [q2 for q in qs for (act, q2) in auto.moves[q] if table(act, lab)]
                nq = step_cache[key] = auto.closure(moved) if moved else frozenset()
            if nq:
                nxt = (target, nq)
                if nxt not in parent:
                    parent[nxt] = (node, lab)
                    queue.append(nxt)
        if progress is not None:
            progress.tick(len(space), space.transitions, len(queue) - head, space.memory)
    return None
