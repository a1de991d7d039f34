"""Safety observers in the compiled search: the automata the Promela export builds, stepped after every interaction.

An observer of ``[R] false`` or ``[R] {P}`` (runtime.export.monitors) is a
deterministic automaton over the model's interactions; its state becomes one
more slot of the explorer's state, and a successor is a violation when the
observer reaches an accepting state where ``P`` does not hold.  Breadth-first,
the first violation met ends a shortest counterexample.
"""
from __future__ import annotations

from dataclasses import replace

from runtime.engine.emit import CWriter
from runtime.export.monitors import equivalent_states
from runtime.export.promela_base import Monitor
from runtime.native.cexpr import Unsupported
from runtime.props.formulas import PAnd, PAt, PCmp, PConst, PNot, POr, Pred
from runtime.props.predicates import split_path

#: Largest number of leaves of a flat connector whose interactions get an observer table.
MAX_LEAVES = 12


def c_pred(p: Pred | None, flat, state: str = "L") -> str:
    """A state predicate over the C state vector.

    ``1`` for None: ``[R] false`` fails wherever R matches (see the caller).
    """
    if p is None:
        return "0"
    if isinstance(p, PConst):
        return "1" if p.value else "0"
    if isinstance(p, PAt):
        fa = next(a for a in flat.atoms if a.name == p.atom)
        return f"(({state}[{fa.offset}] >> {fa.places.index(p.place)}) & 1)"
    if isinstance(p, PCmp):
        got = split_path(flat, p.path)
        if got is None:
            raise Unsupported(f"predicate on unknown data {p.path}")
        fa, var = got
        if not any(d.name == var for d in fa.variables) or not isinstance(p.value, (bool, int)):
            raise Unsupported(f"predicate on {p.path}")
        return f"({state}[{fa.slot(var)}] {p.op} {int(p.value)})"
    if isinstance(p, PNot):
        return f"(!{c_pred(p.operand, flat, state)})"
    if isinstance(p, PAnd):
        return f"({c_pred(p.left, flat, state)} && {c_pred(p.right, flat, state)})"
    if isinstance(p, POr):
        return f"({c_pred(p.left, flat, state)} || {c_pred(p.right, flat, state)})"
    raise Unsupported(f"predicate {p!r}")


def minimal(mon: Monitor) -> Monitor:
    """The same observer with language-equivalent states merged (Moore's refinement), reachable ones only.

    The subset construction keeps states that differ as sets but not in what they accept (the start set and
    the set after one ``true*`` step): merged, an interaction the property does not name leaves the state
    alone, which is what makes it invisible to the partial-order reduction and saves observer states.  For
    ``[R] false`` (no predicate) reaching an accepting state is the violation, which ends the search: its
    way out is never taken, so accepting states become one sink first.
    """
    ks = range(len(mon.delta))
    if mon.pred is None:
        mon = replace(mon, delta=[{q: q if q in mon.accepting else t for q, t in d.items()} for d in mon.delta])
    block = equivalent_states(mon)
    order = {block[mon.initial]: 0}
    stack = [mon.initial]
    rep = {block[mon.initial]: mon.initial}
    while stack:
        q = stack.pop()
        for k in ks:
            t = mon.delta[k].get(q, q)
            if block[t] not in order:
                order[block[t]] = len(order)
                rep[block[t]] = t
                stack.append(t)
    delta = [{order[b]: order[block[mon.delta[k].get(q, q)]] for b, q in rep.items()} for k in ks]
    accepting = {order[b] for b, q in rep.items() if q in mon.accepting}
    return replace(mon, states=len(order), delta=delta, accepting=accepting, initial=0)


def gen_observers(w: CWriter, monitors, sources, flat, base: int) -> None:
    """``observe(s, L, src, mask)`` and ``observe_initial(L)``: advance every observer, 1 when one is violated.

    ``monitors`` are ``(Monitor, statics)`` pairs; observer ``m`` lives in slot ``base + m``.
    """
    w(f"#define NMON {len(monitors)}")
    if not monitors:
        w("static int observe(const V *s, V *L, uint32_t src, uint32_t mask) "
          "{ (void)s; (void)L; (void)src; (void)mask; return 0; }")
        w("static int observe_initial(const V *L) { (void)L; return 0; }")
        return
    statics = monitors[0][1]
    by_index = {st.index: k for k, st in enumerate(statics)}
    nsrc = len(sources)
    with w.block("static int KOF(uint32_t src, uint32_t mask)", "the observers' number of interaction mask of src"):
        w("(void)mask;")
        w("switch (src) {")
        for src in sources:
            masks = sorted(st.mask for st in statics if st.source.index == src.index)
            if len(masks) == 1:
                w(f"case {src.index}: return {by_index[masks[0] * nsrc + src.index]};")
                continue
            if len(src.leaves) > MAX_LEAVES:
                raise Unsupported(f"connector {src.connector.path}: too many interactions for an observer table")
            table = [by_index.get(m * nsrc + src.index, 0) for m in range(1 << len(src.leaves))]
            w(f"case {src.index}: {{ static const int T[] = {{{', '.join(map(str, table))}}}; return T[mask]; }}")
        w("}")
        w("return 0;")
    for m, (mon, _) in enumerate(monitors):
        rows = []
        for k in range(len(statics)):
            rows.append("{" + ", ".join(str(mon.delta[k].get(q, q)) for q in range(mon.states)) + "}")
        w(f"static const uint8_t D{m}[{len(statics)}][{mon.states}] = {{{', '.join(rows)}}};")
        w(
            f"static const uint8_t A{m}[{mon.states}] = "
            f"{{{', '.join('1' if q in mon.accepting else '0' for q in range(mon.states))}}};"
        )
        w(f"static int P{m}(const V *L) {{ return {c_pred(mon.pred, flat)}; }}")
    with w.block("static int observe(const V *s, V *L, uint32_t src, uint32_t mask)"):
        w("int k = KOF(src, mask), bad = 0;")
        for m in range(len(monitors)):
            w(f"L[{base + m}] = D{m}[k][s[{base + m}]];")
            w.if_then(f"A{m}[L[{base + m}]] && !P{m}(L)", "bad = 1")
        w("return bad;")
    with w.block("static int observe_initial(const V *L)"):
        w("int bad = 0;")
        for m in range(len(monitors)):
            w.if_then(f"A{m}[L[{base + m}]] && !P{m}(L)", "bad = 1")
        w("return bad;")
