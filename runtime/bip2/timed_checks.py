"""Checks of timed BIP2 in an atom, each mirroring a rule of the Verimag compiler (named in docs/bip2.md).

Clocks are visible in guards, invariants, ``resume`` guards and actions; the
shape rules keep every timing constraint an interval of time, which is what
the engine computes (runtime/engine/timed.py).
"""
from __future__ import annotations

from runtime.bip2.scope import Scope, suggestion
from runtime.model import AtomType, Binary, Call, If, Rate, Unary, Var

_COMPARISON = {"==", "!=", "<", "<=", ">", ">="}


def uses_clock(e, clocks: set[str]) -> bool:
    """True when expression ``e`` reads one of ``clocks``."""
    if isinstance(e, Var):
        return e.name in clocks
    if isinstance(e, Unary):
        return uses_clock(e.operand, clocks)
    if isinstance(e, Binary):
        return uses_clock(e.left, clocks) or uses_clock(e.right, clocks)
    if isinstance(e, Call):
        return any(uses_clock(a, clocks) for a in e.args)
    return False


def check_atom_timing(checker, a: AtomType, where: str, scope: Scope) -> None:
    """Report misuse of clocks, rates, invariants and resume guards in atom type ``a``."""
    clocks = {c.name for c in a.clocks}
    loc, error = checker.loc, checker.error
    for inv in a.invariants:
        if inv.places:
            checker._places(a, inv, "places", inv.places)
        checker.exprs.guard(inv.guard, scope, loc.at(inv))
        constraint_shape(checker, inv.guard, clocks, loc.at(inv), f"invariant {inv.name} of {where}")
    checker.unique(a.invariants, "invariant", where)
    resumes = [(a.initial, "the initial transition")] if a.initial is not None else []
    for t in a.transitions:
        label = "an internal transition" if t.port is None else f"the transition on {t.port}"
        if t.guard is not None:
            if t.port is None and uses_clock(t.guard, clocks):
                # Verimag: noClocksInUntimedGuard
                error(_first_clock(loc, t.guard, clocks, loc.at(t)),
                      f"{where}: an internal transition's guard cannot read a clock",
                      hint="internal transitions are untimed in BIP2: move the constraint to a port transition")
            constraint_shape(checker, t.guard, clocks, loc.at(t), f"the guard of {label} in {where}")
        resumes.append((t, label))
        rates(checker, t.action, clocks, where, loc.at(t))
    if a.initial is not None:
        rates(checker, a.initial.action, clocks, where, loc.at(a.initial))
    for t, label in resumes:
        if t.resume is not None and t.resume.guard is not None:
            at = loc.at(t.resume)
            checker.exprs.guard(t.resume.guard, scope, at)
            constraint_shape(checker, t.resume.guard, clocks, at, f"the resume guard of {label} in {where}")
    for pr in a.priorities:
        if pr.guard is not None and uses_clock(pr.guard, clocks):
            error(_first_clock(loc, pr.guard, clocks, loc.at(pr)), f"priority {pr.name} of {where}: a priority guard "
                  "cannot read a clock")  # Verimag: noClocksInUntimedGuard


def rates(checker, stmts, clocks: set[str], where: str, at) -> None:
    """``x' = e`` only for a clock ``x``, with a rate that does not itself read a clock."""
    for s in stmts:
        if isinstance(s, Rate):
            span = checker.loc.at(s, default=at)
            if s.clock not in clocks:
                checker.error(span, f"'{s.clock}' is not a clock of {where}: only a clock has a rate "
                                    f"({s.clock}' = ...)", hint=suggestion(s.clock, clocks))
            elif uses_clock(s.value, clocks):
                checker.error(span, f"the rate of clock '{s.clock}' in {where} reads a clock")
        elif isinstance(s, If):
            rates(checker, s.then, clocks, where, at)
            rates(checker, s.orelse, clocks, where, at)


def constraint_shape(checker, e, clocks: set[str], at, what: str) -> None:
    """The Verimag TimeValidator rules, plus linearity (which the engine needs to solve constraints in time)."""
    if not clocks or e is None:
        return

    def report(node, message, hint=None):
        checker.error(_first_clock(checker.loc, node, clocks, at), f"{what}: {message}", hint)

    def walk(node, in_comparison: bool) -> None:
        if isinstance(node, Unary):
            if node.op == "!" and uses_clock(node.operand, clocks):
                report(node, "operator '!' applied to an expression involving clocks",  # noClocksInLogicalNot
                       hint="write the opposite comparison instead, e.g. x > 5 for !(x <= 5)")
                return
            walk(node.operand, in_comparison)
        elif isinstance(node, Binary):
            left, right = uses_clock(node.left, clocks), uses_clock(node.right, clocks)
            if node.op == "||" and left and right:
                report(node, "clocks found on both sides of '||'")  # clocksOnOneSideOfLogicalOr
                return
            if node.op == "!=" and (left or right):
                report(node, "operator '!=' applied to expressions involving clocks")  # invalidNotEqualOnClocks
                return
            if node.op in _COMPARISON and (left or right):
                if in_comparison:
                    # Verimag: nestedComparisonOnClocks
                    report(node, "nested comparison applied to an expression involving clocks")
                    return
                walk(node.left, True)
                walk(node.right, True)
                return
            if (left or right) and not in_comparison and node.op not in ("&&", "||"):
                report(node, f"a clock is read outside a comparison (operator '{node.op}')")
                return
            if node.op == "*" and left and right or node.op in ("/", "%") and right or \
                    node.op in ("/", "%", "&", "|", "^", "<<", ">>") and left:
                report(node, f"operator '{node.op}' makes the constraint non-linear in the clocks",
                       hint="a timing constraint compares sums of clocks times constants")
                return
            walk(node.left, in_comparison)
            walk(node.right, in_comparison)
        elif isinstance(node, Call) and uses_clock(node, clocks):
            report(node, f"a clock is passed to '{node.function}': the engine cannot solve it in time")
        elif isinstance(node, Var) and node.name in clocks and not in_comparison:
            report(node, f"clock '{node.name}' used as a condition; compare it (e.g. {node.name} >= 1)")

    walk(e, False)


def _first_clock(loc, e, clocks, default):
    """The span of the first clock read in ``e`` (else ``default``), so that errors point at a clock."""
    stack = [e]
    while stack:
        node = stack.pop(0)
        if isinstance(node, Var) and node.name in clocks:
            return loc.at(node, default=default)
        if isinstance(node, Unary):
            stack.append(node.operand)
        elif isinstance(node, Binary):
            stack += [node.left, node.right]
        elif isinstance(node, Call):
            stack += list(node.args)
    return default
