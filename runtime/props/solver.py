"""On-the-fly evaluation of an alternation-free formula: a local fixed-point algorithm per block, and evidence.

A *node* is a subformula at a state (``state * len(eq) + subformula``).  The
nodes of one block of least fixed points are solved by Liu and Smolka's local
algorithm: explore only the nodes the answer needs, stop as soon as the root
is proven.  A block of greatest fixed points is solved as the least fixed
point of its negation (the *dual view*: and/or, box/diamond, true/false
swap).  Nodes of other blocks are solved first, recursively (alternation-free
formulas never loop back), and their values cached.  The state space is
expanded only as the algorithm asks for successors.

Evidence follows the reasons recorded while solving: which disjunct or
successor made a node true in its view.  It is a path (a witness for a true
formula, a counterexample for a false one); where the reason is "every
successor", the path stops; where it loops, it ends with the loop.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Callable

from runtime.explore.space import StateSpace
from runtime.props.actions import LabelTable
from runtime.props.normal import AND, BOX, DIA, FF, FIX, OR, PRED, TT, Equations


@dataclass
class Evidence:
    """A path through the state space: states, and the label ids of the transitions between them.

    ``loop`` is the index in ``states`` where the path loops back to (or -1).
    """

    states: list[int]
    labels: list[int]
    loop: int = -1


class Solver:
    """Evaluates the nodes of ``eq`` on ``space``; ``preds`` are the bound state predicates of ``eq.preds``."""

    def __init__(self, eq: Equations, space: StateSpace, preds: list[Callable[[tuple], bool]]) -> None:
        self.eq = eq
        self.space = space
        self.preds = preds
        self.n = len(eq)
        self.labels = LabelTable(eq.actions, space.labels)
        self.final: dict[int, bool] = {}
        self.why: dict[int, int] = {}
        self.nodes = 0  # nodes explored, for statistics

    # -- the view of a node: an OR or an AND of child nodes ----------------------------------------------
    def children(self, key: int) -> tuple[bool, list[int]]:
        """``(is_or, children)`` of a node in the original polarity."""
        n = self.n
        sid, node = divmod(key, n)
        kind = self.eq.kind[node]
        if kind == TT:
            return False, []
        if kind == FF:
            return True, []
        if kind == PRED:
            holds = self.preds[self.eq.arg[node]](self.space.engine_state(sid))
            return (False, []) if holds else (True, [])
        if kind in (AND, OR):
            base = sid * n
            return kind == OR, [base + k for k in self.eq.kids[node]]
        if kind == FIX:
            return True, [sid * n + self.eq.kids[node][0]]
        succ = self.space.successors(sid)
        action = self.eq.arg[node]
        child = self.eq.kids[node][0]
        match = self.labels
        out = []
        for k in range(0, len(succ), 2):
            if match(action, succ[k]):
                out.append(succ[k + 1] * n + child)
        return kind == DIA, out

    # -- solving ------------------------------------------------------------------------------------------
    def value(self, key: int) -> bool:
        """The value of a node (original polarity), solving its block as far as needed."""
        got = self.final.get(key)
        if got is not None:
            return got
        node = key % self.n
        block = self.eq.block[node]
        dual = self.eq.sign[node] == "nu"
        self._local(key, block, dual)
        return self.final[key]

    def _local(self, root: int, block: int, dual: bool) -> None:
        """Liu-Smolka local least fixed point of the block's (possibly dual) view, from ``root``."""
        n = self.n
        eq_block = self.eq.block
        final = self.final
        true: set[int] = set()
        seen = {root}
        deps: dict[int, list[tuple[int, tuple[int, ...], bool]]] = {}
        work: deque[tuple[int, tuple[int, ...], bool]] = deque()

        def edges(key: int) -> None:
            is_or, kids = self.children(key)
            self.nodes += 1
            if is_or != dual:  # an OR in this view: one edge per child
                for c in kids:
                    work.append((key, (c,), True))
            else:  # an AND in this view: one edge over all children (none: true at once)
                work.append((key, tuple(kids), False))

        edges(root)
        complete = True
        while work:
            v, targets, single = work.popleft()
            if v in true:
                continue
            waiting = None
            dead = False
            for t in targets:
                if t in true:
                    continue
                known = final.get(t)
                if known is None and eq_block[t % n] != block:
                    known = self.value(t)
                if known is not None:
                    if known != dual:  # true in this view
                        continue
                    dead = True
                    break
                waiting = t
                break
            if dead:
                continue
            if waiting is None:
                true.add(v)
                if single and targets:
                    self.why[v] = targets[0]
                if v == root:
                    complete = not work and not deps.get(v)
                    break
                for e in deps.pop(v, ()):
                    work.append(e)
                continue
            deps.setdefault(waiting, []).append((v, targets, single))
            if waiting not in seen:
                seen.add(waiting)
                edges(waiting)
        for k in true:
            final[k] = not dual
        if root not in true or complete:
            for k in seen:
                if k not in true:
                    final.setdefault(k, dual)

    # -- evidence -----------------------------------------------------------------------------------------
    def evidence(self, root: int) -> Evidence:
        """A path supporting the value of ``root``: a witness when it holds, a counterexample when not."""
        n = self.n
        states = [root // n]
        labels: list[int] = []
        visited: dict[int, int] = {}
        cur = root
        while True:
            if cur in visited:
                return Evidence(states, labels, visited[cur])
            visited[cur] = len(states) - 1
            want = self.final.get(cur)
            if want is None:
                break
            nxt = self._reason(cur, want)
            if nxt is None:
                break
            sid, node = divmod(cur, n)
            nsid = nxt // n
            if self.eq.kind[node] in (DIA, BOX):
                labels.append(self._label(sid, nsid, self.eq.arg[node]))
                states.append(nsid)
            cur = nxt
        return Evidence(states, labels)

    def _reason(self, key: int, want: bool) -> int | None:
        """The child that carries the evidence of ``key`` having value ``want``, or None where the path ends."""
        why = self.why.get(key)
        node = key % self.n
        kind = self.eq.kind[node]
        if why is not None and self.final.get(why) == want:
            return why
        if kind in (TT, FF, PRED):
            return None
        is_or, kids = self.children(key)
        # a universal reason (every child) ends the path, unless one child is the obvious continuation
        if (is_or and not want) or (not is_or and want):
            if kind in (DIA, BOX) or not kids:
                return None
            known = [c for c in kids if self.final.get(c) == want]
            return max(known, key=self._weight) if known else None
        candidates = [c for c in kids if self.final.get(c) == want]
        return candidates[0] if candidates else None

    def _weight(self, key: int) -> int:
        """Prefer continuing into subformulas that still have steps to show."""
        kind = self.eq.kind[key % self.n]
        return {DIA: 3, BOX: 3, FIX: 2, OR: 1, AND: 1}.get(kind, 0)

    def _label(self, src: int, dst: int, action: int) -> int:
        succ = self.space.successors(src)
        for k in range(0, len(succ), 2):
            if succ[k + 1] == dst and self.labels(action, succ[k]):
                return succ[k]
        raise ValueError(f"no transition from {src} to {dst} matching action {action}")
