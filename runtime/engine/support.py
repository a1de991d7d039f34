"""Run-time helpers the generated step calls where straight-line code would not pay off.

Atom priorities (memoised per atom), the generic enumeration and firing of
nested connectors, and compound priorities.  The common cases (rendezvous,
flat broadcasts, lone ports, atoms without priorities) are generated code.
"""
from __future__ import annotations

from itertools import product
from typing import Any, Callable, Sequence

from runtime.engine import defines
from runtime.engine.errors import ModelError
from runtime.engine.plan import Source, TreeNode

#: Most interactions a nested connector may offer in one state before the engine gives up.
GENERIC_LIMIT = 100_000


class AtomPriorities:
    """Maximal enabled ports of one atom: ports with an enabled transition, minus those below an enabled one.

    ``rules`` are ``(low port index, high port index, rule number)`` pairs after
    expanding ``*``; ``guarded[rule]`` tells whether the rule has a guard, in
    which case bit ``k`` of ``active`` (k counting guarded rules) says it holds.
    """

    def __init__(self, atom: str, ports: list[str], rules: list[tuple[int, int, int]], texts: list[str],
                 guarded: list[int]) -> None:
        self.atom, self.ports, self.rules, self.texts = atom, ports, rules, texts
        self.guard_bit = {r: 1 << k for k, r in enumerate(guarded)}
        self.memo: dict[tuple[int, int], int] = {}
        self(0, 0)  # unguarded cycles are found before the first step

    def __call__(self, raw: int, active: int) -> int:
        key = (raw, active)
        out = self.memo.get(key)
        if out is None:
            out = self.memo[key] = self._compute(raw, active)
        return out

    def _compute(self, raw: int, active: int) -> int:
        above: dict[int, set[int]] = {}
        for lo, hi, r in self.rules:
            bit = self.guard_bit.get(r)
            if bit is None or active & bit:
                above.setdefault(lo, set()).add(hi)
        closure: dict[int, set[int]] = {}
        for p in above:
            seen: set[int] = set()
            stack = list(above[p])
            while stack:
                q = stack.pop()
                if q not in seen:
                    seen.add(q)
                    stack.extend(above.get(q, ()))
            closure[p] = seen
            if p in seen:
                rules = sorted({self.texts[r] for lo, hi, r in self.rules if lo in seen | {p} and hi in seen | {p}})
                ports = ", ".join(self.ports[q] for q in sorted(seen))
                raise ModelError(f"priority cycle between ports {ports} ({'; '.join(rules)})", atom=self.atom)
        out = raw
        for p, higher in closure.items():
            if any(raw >> q & 1 for q in higher):
                out &= ~(1 << p)
        return out


class Clauses:
    """The generated guard/up/down functions of one connector type, by parameter mask."""

    def __init__(self, table: dict[int, tuple[Callable | None, Callable | None, Callable | None]],
                 defaults: list[Any], export_idx: tuple[int, ...]) -> None:
        self.table, self.defaults, self.export_idx = table, defaults, export_idx

    def get(self, mask: int):
        return self.table.get(mask, (None, None, None))


def generic_enabled(source: Source, s: tuple, enabled: Sequence[bool], slots: Sequence[tuple[int, ...]]) -> list[int]:
    """Maximal enabled interactions (leaf masks) of a connector with sub-connectors or merged exports.

    Enumerates every enabled interaction bottom-up: a parent sees all the
    interactions its sub-connectors offer, each with the values ``up`` computed
    for the exported port; maximal progress is then applied over leaf masks.
    """
    count = [0]
    offers = _offers(source.tree, s, enabled, slots, count)
    if not source.maximal:
        return sorted({m for m, _ in offers})
    return defines.maximal(m for m, _ in offers)


def _offers(node: TreeNode, s, enabled, slots, count) -> list[tuple[int, tuple]]:
    rt: Clauses = node.runtime
    options: list[list[tuple[int, Any]]] = []
    available = 0
    for i, alts in enumerate(node.params):
        row: list[tuple[int, Any]] = []
        for a in alts:
            if a.node is None:
                if enabled[a.port]:
                    row.append((a.mask, [s[k] for k in slots[a.port]]))
            else:
                sub = _offers(a.node, s, enabled, slots, count)
                if a.node.connector.scope != node.connector.scope:
                    # the port leaves its compound: as in the Verimag engine, the compound offers only the
                    # sub-connector's maximal interactions, before the outer guard is known
                    keep = set(defines.maximal(m for m, _ in sub))
                    sub = [o for o in sub if o[0] in keep]
                row.extend(sub)
        options.append(row)
        if row:
            available |= 1 << i
    out: list[tuple[int, tuple]] = []
    if not available:
        return out
    n = len(node.params)
    for pm in defines.subsets(node.info.tree, available):
        guard, up, _ = rt.get(pm)
        idx = [i for i in range(n) if pm >> i & 1]
        for combo in product(*(options[i] for i in idx)):
            count[0] += 1
            if count[0] > GENERIC_LIMIT:
                raise ModelError(f"connector {node.connector.path}: more than {GENERIC_LIMIT} interactions to "
                                 "enumerate in one state (nested connectors are enumerated exhaustively)")
            pv: list[Any] = [None] * n
            mask = 0
            for i, (m, vals) in zip(idx, combo):
                pv[i] = list(vals)
                mask |= m
            if guard is not None and not guard(pv):
                continue
            lv = list(rt.defaults)
            if up is not None:
                up(pv, lv)
            out.append((mask, tuple(lv[k] for k in rt.export_idx)))
    return out


def fire_tree(source: Source, L: list, mask: int, rec, slots, fire_port) -> None:
    """Fire the interaction ``mask`` of a nested connector: ``up`` bottom-up, ``down`` top first, then the atoms."""
    calls: list[tuple[int, list]] = []

    def up(node: TreeNode):
        rt: Clauses = node.runtime
        pv: list[Any] = [None] * len(node.params)
        pm = 0
        kids = []
        for i, alts in enumerate(node.params):
            for a in alts:
                if a.mask & mask:
                    pm |= 1 << i
                    if a.node is None:
                        pv[i] = [L[k] for k in slots[a.port]]
                        kids.append((i, a.port, None))
                    else:
                        child = up(a.node)
                        crt: Clauses = a.node.runtime
                        pv[i] = [child[1][k] for k in crt.export_idx]
                        kids.append((i, None, child))
                    break
        _, fup, fdown = rt.get(pm)
        lv = list(rt.defaults)
        if fup is not None:
            fup(pv, lv)
        return node, lv, pv, fdown, kids

    def down(frame) -> None:
        node, lv, pv, fdown, kids = frame
        if fdown is not None:
            fdown(pv, lv)
        for i, port, child in kids:
            if child is None:
                calls.append((port, pv[i]))
            else:
                for j, k in enumerate(child[0].runtime.export_idx):
                    child[1][k] = pv[i][j]
                down(child)

    down(up(source.tree))
    for port, vals in calls:
        fire_port[port](L, vals, rec)


class Priorities:
    """Compound priorities over the enabled interactions of one step.

    A rule ``L < H`` (whose guard holds) removes every interaction matching
    ``L`` while an interaction matching ``H``, or matching the high side of a
    rule reachable from it, is enabled.  Rules chain when the high side of one
    and the low side of the next can match the same interaction (same
    connector tree); an enabled cycle of rules is a model error.
    """

    def __init__(self, rules: list[tuple[str, tuple, tuple, Callable | None]], tops: dict[int, set[int]]) -> None:
        self.rules = rules
        self.names = [r[0] for r in rules]
        self.guards = [(i, g) for i, (_, _, _, g) in enumerate(rules) if g is not None]
        self.edges = rule_edges([(low, high) for _, low, high, _ in rules], tops)
        self.sides = RuleSides([(low, high) for _, low, high, _ in rules])
        self.memo: dict[tuple[bool, ...], int] = {}
        self.lmask: dict[int, int] = {}
        self.hmask: dict[int, int] = {}
        self._reach(tuple(False for _ in self.guards))  # cycles of unguarded rules: before the first step

    def _reach(self, key: tuple[bool, ...]) -> list[int]:
        got = self.memo.get(key)
        if got is not None:
            return got
        active = set(range(len(self.rules)))
        for (i, _), on in zip(self.guards, key):
            if not on:
                active.discard(i)
        reach = [0] * len(self.rules)
        for r in active:
            seen = {r}
            stack = [r]
            while stack:
                x = stack.pop()
                for y in self.edges[x]:
                    if y in active:
                        if y == r:
                            raise ModelError("priority cycle between compound priorities " +
                                             ", ".join(self.names[z] for z in sorted(seen)))
                        if y not in seen:
                            seen.add(y)
                            stack.append(y)
            reach[r] = sum(1 << y for y in seen)
        self.memo[key] = reach
        return reach

    def _masks(self, inter) -> tuple[int, int]:
        lm = self.lmask.get(inter.index)
        if lm is None:
            low, high = self.sides.of(inter.parts)
            lm, hm = sum(1 << r for r in low), sum(1 << r for r in high)
            self.lmask[inter.index], self.hmask[inter.index] = lm, hm
        return lm, self.hmask[inter.index]

    def filter(self, out: list, s: tuple) -> list:
        if not out:
            return out
        reach = self._reach(tuple(bool(g(s)) for _, g in self.guards))
        high = 0
        for inter in out:
            high |= self._masks(inter)[1]
        if not high:
            return out
        blocked = 0
        for r, rs in enumerate(reach):
            if rs & high:
                blocked |= 1 << r
        if not blocked:
            return out
        return [i for i in out if not (self._masks(i)[0] & blocked)]


class RuleSides:
    """Which compound priorities an interaction is low in and which it is high in.  Only the rules that name one of
    its connectors can match it, so each rule is listed under the connectors its sides name (DALA has 155 rules, an
    interaction meets a handful)."""

    def __init__(self, sides: Sequence[tuple[Sequence, Sequence]]) -> None:
        self.sides = list(sides)
        self.naming: dict[int, set[int]] = {}
        for r, (low, high) in enumerate(self.sides):
            for cid, _ in (*low, *high):
                self.naming.setdefault(cid, set()).add(r)

    def of(self, parts) -> tuple[list[int], list[int]]:
        """The rules ``parts`` (an interaction's (connector, port mask) pairs) is low in, and those it is high in."""
        named = sorted({r for c, _ in parts for r in self.naming.get(c, ())})
        return ([r for r in named if matches_low(parts, self.sides[r][0])],
                [r for r in named if _matches(parts, self.sides[r][1])])


def _matches(parts, entries) -> bool:
    """The high side ``C:I`` applies to the interactions of C that contain I (all of C's for ``C:*``)."""
    for cid, pm in entries:
        for c, m in parts:
            if c == cid and m & pm == pm:
                return True
    return False


def matches_low(parts, entries) -> bool:
    """The low side ``C:I`` applies to I and to the interactions of C inside I (maximal progress would drop them
    beside I anyway), as the Verimag engine reads a rule; ``C:*`` to all of C's."""
    for cid, pm in entries:
        for c, m in parts:
            if c == cid and (pm == 0 or m & ~pm == 0):
                return True
    return False


def top_connectors(sources) -> dict[int, set[int]]:
    """Connector id -> the top-level sources whose connector tree contains it."""
    tops: dict[int, set[int]] = {}
    for src in sources:
        if src.tree is not None:
            for cid in connector_ids(src.tree):
                tops.setdefault(cid, set()).add(src.index)
    return tops


def connector_ids(node) -> list[int]:
    """Ids of a connector tree's nodes, the root first."""
    out = [node.connector.id]
    for alts in node.params:
        for a in alts:
            if a.node is not None:
                out.extend(connector_ids(a.node))
    return out


def rule_edges(rules: list[tuple[tuple, tuple]], tops: dict[int, set[int]]) -> list[list[int]]:
    """``edges[i]``: rules whose low side can match an interaction that the high side of rule ``i`` matches.

    ``rules`` are ``(low entries, high entries)`` pairs of compound priorities.
    """
    n = len(rules)
    return [[j for j in range(n) if _overlap(rules[i][1], rules[j][0], tops)] for i in range(n)]


def _overlap(high, low, tops: dict[int, set[int]]) -> bool:
    """Can one interaction match both sides? On one connector when the high side's ports lie inside the low
    side's (``C:p < C:p,q`` chains, ``C:p,q < C:p,r`` does not); across connectors when they share a top."""
    for c1, m1 in high:
        for c2, m2 in low:
            if c1 == c2:
                if m2 == 0 or m1 & ~m2 == 0:
                    return True
            elif tops.get(c1, set()) & tops.get(c2, set()):
                return True
    return False
