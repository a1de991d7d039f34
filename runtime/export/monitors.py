"""Safety properties as observers for SPIN: ``[R] false`` and ``[R] {P}`` become deterministic automata.

Interactions are known statically, so every action formula has a fixed truth
value per interaction: R's automaton (runtime.props.safety) is determinised
over the interactions themselves.  The observer is a ``byte`` in the Promela
state, advanced at the end of each atomic step; reaching a state where R has
matched asserts the predicate (``false`` for ``never``/``precedes``).
"""
from __future__ import annotations

from runtime.export.interactions import Static
from runtime.export.promela_base import Monitor, PromelaError
from runtime.props.actions import matcher
from runtime.props.check import Checkable
from runtime.props.formulas import PAnd, PAt, PCmp, PConst, PNot, POr, Pred, SBox, SConst, SPred
from runtime.props.normal import positive
from runtime.props.safety import automaton

#: Most observer states a byte holds.
MAX_STATES = 255


def spin_shape(item: Checkable) -> str:
    """``deadlock`` (deadlock freedom), ``observer`` ([R] false / [R] {P}), or "" when SPIN cannot check it here."""
    if item.property.pattern == "deadlock free":
        return "deadlock"
    top = positive(item.property.formula)
    if isinstance(top, SBox) and (isinstance(top.operand, SPred) or
                                  (isinstance(top.operand, SConst) and not top.operand.value)):
        return "observer"
    return ""


def build_monitor(item: Checkable, statics: list[Static], name: str) -> tuple[Monitor, Pred | None]:
    """The observer of ``[R] F`` over these interactions, and F's predicate (None for false)."""
    top = positive(item.property.formula)
    if not isinstance(top, SBox):
        raise PromelaError(f"property {item.name}: SPIN checks [R] false and [R] {{P}} shapes only")
    auto = automaton(top.path)
    matches = [matcher(a) for a in auto.actions]
    table = [[m(s.label) for m in matches] for s in statics]
    start = auto.closure([auto.start])
    ids = {start: 0}
    order = [start]
    delta: list[dict[int, int]] = [dict() for _ in statics]
    head = 0
    while head < len(order):
        qs = order[head]
        head += 1
        for k in range(len(statics)):
            moved = [q2 for q in qs for (act, q2) in auto.moves[q] if table[k][act]]
            nq = auto.closure(moved) if moved else frozenset()
            if nq not in ids:
                ids[nq] = len(order)
                order.append(nq)
                if len(order) > MAX_STATES:
                    raise PromelaError(f"property {item.name}: the observer needs more than {MAX_STATES} states")
            delta[k][ids[qs]] = ids[nq]
    accepting = {i for q, i in ids.items() if auto.accept in q}
    pred = top.operand.pred if isinstance(top.operand, SPred) else None
    return Monitor(name, len(order), delta, accepting, "false", 0, pred), pred


def promela_pred(p: Pred, writer) -> str:
    """A state predicate over the Promela globals the writer declared."""
    flat = writer.flat
    if isinstance(p, PConst):
        return "true" if p.value else "false"
    if isinstance(p, PAt):
        fa = next(a for a in flat.atoms if a.name == p.atom)
        return f"((m{fa.index} & {1 << fa.places.index(p.place)}) != 0)"
    if isinstance(p, PCmp):
        from runtime.props.predicates import split_path
        fa, var = split_path(flat, p.path)
        value = ("true" if p.value else "false") if isinstance(p.value, bool) else str(p.value)
        return f"({writer.names[fa.slot(var)]} {p.op} {value})"
    if isinstance(p, PNot):
        return f"(!{promela_pred(p.operand, writer)})"
    if isinstance(p, PAnd):
        return f"({promela_pred(p.left, writer)} && {promela_pred(p.right, writer)})"
    if isinstance(p, POr):
        return f"({promela_pred(p.left, writer)} || {promela_pred(p.right, writer)})"
    raise PromelaError(f"cannot translate predicate {p!r}")


def equivalent_states(mon: Monitor) -> list[int]:
    """The block of each state of ``mon`` in its minimal automaton: Moore's partition refinement, from accepting
    against not, over every interaction (a state without an entry for one stays where it is)."""
    ks = range(len(mon.delta))
    block = [int(q in mon.accepting) for q in range(mon.states)]
    while True:
        sig = [(block[q], *(block[mon.delta[k].get(q, q)] for k in ks)) for q in range(mon.states)]
        ids: dict[tuple, int] = {}
        refined = [ids.setdefault(s, len(ids)) for s in sig]
        if len(ids) == len(set(block)):
            return refined
        block = refined
