"""From untyped trees to typed formulas: which parts are state, regular or action formulas; shorthands; static checks.

Checks done here (each an error with ``file:line:column``): a construct used
where another kind of formula is expected, an unbound variable, a variable
under an odd number of negations (not monotone), an invalid regular
expression.  Alternation is checked after the regular modalities are
unfolded into fixed points (:mod:`runtime.props.normal`).
"""
from __future__ import annotations

import re
from functools import reduce
from typing import Callable

from runtime.diagnostics import Diagnostic, Span
from runtime.props.formulas import (
    AAnd,
    AConst,
    Action,
    ALabel,
    ANot,
    AOr,
    ARegex,
    PAnd,
    PAt,
    PCmp,
    PConst,
    PNot,
    POr,
    Pred,
    Property,
    RAct,
    RAlt,
    Regular,
    RPlus,
    RSeq,
    RStar,
    SAnd,
    SBox,
    SConst,
    SDia,
    SFix,
    SImplies,
    SNot,
    SOr,
    SPred,
    State,
    SVar,
    show_action,
)
from runtime.props.syntax import Raw, RawProperty

REGULAR_OPS = {"choice": "'|'", "concat": "'.'", "star": "'*'", "plus": "'+'"}


class TypeProblem(Exception):
    def __init__(self, span: Span, message: str) -> None:
        super().__init__(message)
        self.span = span
        self.message = message


def _what(raw: Raw) -> str:
    return {
        "label": "a label",
        "regex": "a regular expression on labels",
        "optional": "an optional label",
        "var": f"the variable {raw.args[0]}",
        "state": "a state predicate",
        "diamond": "a <...> modality",
        "box": "a [...] modality",
        "mu": "a mu fixed point",
        "nu": "a nu fixed point",
        "implies": "'implies'",
    }.get(raw.op, REGULAR_OPS.get(raw.op, raw.op))


def _quoted(raw: Raw) -> str:
    """The source form of a label, a regular expression or an optional one."""
    if raw.op == "optional":
        return "optional " + _quoted(raw.args[0])
    return f'"{raw.args[0]}"' if raw.op == "label" else f"'{raw.args[0]}'"


def action(raw: Raw) -> Action:
    op, a, sp = raw.op, raw.args, raw.span
    if op == "label":
        return ALabel(a[0], sp)
    if op == "optional":
        inner = action(a[0])
        return ALabel(inner.text, sp, True) if isinstance(inner, ALabel) else ARegex(inner.pattern, sp, True)
    if op == "regex":
        try:
            re.compile(a[0])
        except re.error as err:
            raise TypeProblem(sp, f"invalid regular expression '{a[0]}': {err}") from None
        return ARegex(a[0], sp)
    if op in ("true", "false"):
        return AConst(op == "true", sp)
    if op == "not":
        return ANot(action(a[0]), sp)
    if op == "and":
        return AAnd(action(a[0]), action(a[1]), sp)
    if op == "or":
        return AOr(action(a[0]), action(a[1]), sp)
    if op == "implies":
        return AOr(ANot(action(a[0]), sp), action(a[1]), sp)
    if op in REGULAR_OPS:
        raise TypeProblem(sp, f"{REGULAR_OPS[op]} builds a regular formula, but an action formula is expected "
                              "here ('not', 'and', 'or' combine single actions; put iterations outside them)")
    if op == "var":
        raise TypeProblem(sp, f"'{a[0]}' is not an action: labels are written in double quotes (\"{a[0]}\")")
    raise TypeProblem(sp, f"{_what(raw)} is a state formula, but an action formula is expected here")


def regular(raw: Raw) -> Regular:
    op, a, sp = raw.op, raw.args, raw.span
    if op == "choice":
        return RAlt(regular(a[0]), regular(a[1]), sp)
    if op == "concat":
        return RSeq(regular(a[0]), regular(a[1]), sp)
    if op == "star":
        return RStar(regular(a[0]), sp)
    if op == "plus":
        return RPlus(regular(a[0]), sp)
    if op in ("or", "and", "not", "implies"):
        for sub in a:
            if isinstance(sub, Raw) and _is_regular(sub):
                raise TypeProblem(sub.span, f"'{'not' if op == 'not' else op}' combines action formulas, not "
                                            "regular ones: use '|' for a choice of paths, or move '*', '+', '.' out")
    return RAct(action(raw), sp)


def _is_regular(raw: Raw) -> bool:
    return raw.op in REGULAR_OPS or (raw.op in ("or", "and", "not") and any(
        isinstance(x, Raw) and _is_regular(x) for x in raw.args))


def state(raw: Raw) -> State:
    op, a, sp = raw.op, raw.args, raw.span
    if op in ("true", "false"):
        return SConst(op == "true", sp)
    if op == "var":
        return SVar(a[0], sp)
    if op == "state":
        return SPred(pred(a[0]), sp)
    if op == "not":
        return SNot(state(a[0]), sp)
    if op == "and":
        return SAnd(state(a[0]), state(a[1]), sp)
    if op == "or":
        return SOr(state(a[0]), state(a[1]), sp)
    if op == "implies":
        return SImplies(state(a[0]), state(a[1]), sp)
    if op == "diamond":
        return SDia(regular(a[0]), state(a[1]), sp)
    if op == "box":
        return SBox(regular(a[0]), state(a[1]), sp)
    if op in ("mu", "nu"):
        name, body, name_span = a
        if name in ("T", "F"):
            raise TypeProblem(name_span, f"'{name}' means {'true' if name == 'T' else 'false'} and cannot name a "
                                         "variable")
        return SFix(op, name, state(body), sp, name_span)
    if op in ("label", "regex", "optional"):
        text = _quoted(raw)
        raise TypeProblem(sp, f"{text} is an action formula, but a state formula is expected here "
                              f"(write <{text}> true for 'possible next', [{text}] false for 'impossible next')")
    if op in REGULAR_OPS:
        raise TypeProblem(sp, f"{REGULAR_OPS[op]} builds a regular formula, which belongs inside <...> or [...]")
    raise TypeProblem(sp, f"unexpected {op}")


def pred(raw: Raw) -> Pred:
    op, a, sp = raw.op, raw.args, raw.span
    if op == "p_or":
        return POr(pred(a[0]), pred(a[1]), sp)
    if op == "p_and":
        return PAnd(pred(a[0]), pred(a[1]), sp)
    if op == "p_not":
        return PNot(pred(a[0]), sp)
    if op == "p_at":
        return PAt(a[0].args[0], a[1], sp)
    if op == "p_cmp":
        path, cmp, value = a
        return PCmp(path.args[0], cmp, value.args[0], sp)
    if op == "p_var":
        return PCmp(a[0].args[0], "!=", False, sp)
    if op in ("true", "false"):
        return PConst(op == "true", sp)
    raise TypeProblem(sp, f"unexpected {op} in a state predicate")


# --- shorthands ----------------------------------------------------------------------------------

def never(r: Regular, sp: Span) -> State:
    """``never R`` = ``[true* . R] false``: no path contains R."""
    return SBox(RSeq(RStar(RAct(AConst(True, sp), sp), sp), r, sp), SConst(False, sp), sp)


def precedes(a: Action, b: Action, sp: Span) -> State:
    """``A precedes B`` = ``[(not A)* . B] false``: B cannot happen before A has happened."""
    return SBox(RSeq(RStar(RAct(ANot(a, sp), sp), sp), RAct(b, sp), sp), SConst(False, sp), sp)


def within(b: Action, n: int, sp: Span) -> State:
    """``W_n``: on every path, B is one of the next ``n`` transitions (and no deadlock comes before it)."""
    f: State = SConst(False, sp)
    for _ in range(n):
        f = SAnd(SDia(RAct(AConst(True, sp), sp), SConst(True, sp), sp),
                 SBox(RAct(ANot(b, sp), sp), f, sp), sp)
    return f


def leads_to(r: Regular, b: Action, n: int, sp: Span) -> State:
    """``R leads to B within N steps`` = ``[true* . R] W_N``."""
    return SBox(RSeq(RStar(RAct(AConst(True, sp), sp), sp), r, sp), within(b, n, sp), sp)


def only_while(a: Action, service: str, cancels: list[str], sp: Span) -> State:
    """``A only while "M.S" runs`` = ``[B . A] false``, B every path after which service M.S does not run.

    A request of S runs from the request it accepts (T, ``trigger``) to its end (E: ``finish``, ``fail``,
    ``interrupted``), or to the start of a service that interrupts S (X, ``cancels``) if that comes before the
    request has started (``start``).  A T while a request runs renews the run: the new request is accepted before
    the old one ends (GenoM3's ``interrupts`` naming the service itself), so the old request's E leaves the new
    one running.  B follows S's controller by these events, the others (O) anywhere:
    ``(O | X | T.O*.X | T.O*.S.(O | X | T.O*.X | T.O*.E.O*.S)*.(E | T.O*.E.O*.X))*``.
    """
    def one(port: str) -> Action:
        return ALabel(f"{service}:{port}", sp)

    def any_of(actions: list[Action]) -> Action:
        return reduce(lambda x, y: AOr(x, y, sp), actions)

    def seq(*parts: Regular) -> Regular:
        return reduce(lambda x, y: RSeq(x, y, sp), parts)

    def alt(*parts: Regular) -> Regular:
        return reduce(lambda x, y: RAlt(x, y, sp), parts)

    ends = any_of([one(p) for p in ("finish", "fail", "interrupted")])
    cancel = any_of([ALabel(label, sp) for label in cancels]) if cancels else None
    named = any_of([one("trigger"), one("start"), ends] + ([cancel] if cancel is not None else []))
    t, s, e, o = (RAct(f, sp) for f in (one("trigger"), one("start"), ends, ANot(named, sp)))
    os_ = RStar(o, sp)
    if cancel is None:  # nothing interrupts S but S itself
        inner = alt(o, seq(t, os_, e, os_, s))
        back = alt(o, seq(t, os_, s, RStar(inner, sp), e))
    else:
        x = RAct(cancel, sp)
        inner = alt(o, x, seq(t, os_, x), seq(t, os_, e, os_, s))
        back = alt(o, x, seq(t, os_, x), seq(t, os_, s, RStar(inner, sp), alt(e, seq(t, os_, e, os_, x))))
    return SBox(RSeq(RStar(back, sp), RAct(a, sp), sp), SConst(False, sp), sp)


def invariant(p: Pred, sp: Span) -> State:
    """``invariant P`` = ``[true*] {P}``: P holds in every reachable state."""
    return SBox(RStar(RAct(AConst(True, sp), sp), sp), SPred(p, sp), sp)


def deadlock_free(sp: Span) -> State:
    """``deadlock free`` = ``[true*] <true> true``."""
    return SBox(RStar(RAct(AConst(True, sp), sp), sp), SDia(RAct(AConst(True, sp), sp), SConst(True, sp), sp), sp)


#: Largest N of ``leads to ... within N steps`` (the formula grows linearly with N).
MAX_WITHIN = 10_000


#: What interrupts a service, for ``only while "M.S" runs``: the labels of the interactions that cancel a request of
#: M.S before it starts (None: there is no such service).  Read from the model (runtime/props/check.py).
Cancels = Callable[[str], "list[str] | None"]


def property_of(raw: RawProperty, cancels: Cancels | None = None) -> Property:
    body = raw.body
    op, a, sp = body.op, body.args, body.span
    if op == "formula":
        return Property(raw.name, state(a[0]), raw.span)
    if op == "never":
        return Property(raw.name, never(regular(a[0]), sp), raw.span, "never")
    if op == "precedes":
        return Property(raw.name, precedes(action(a[0]), action(a[1]), sp), raw.span, "precedes")
    if op == "leads_to":
        n = a[2]
        if n < 1 or n > MAX_WITHIN:
            raise TypeProblem(sp, f"'within {n} steps': the bound must be between 1 and {MAX_WITHIN}")
        return Property(raw.name, leads_to(regular(a[0]), action(a[1]), n, sp), raw.span, "leads to")
    if op == "only_while":
        service = a[1]
        if cancels is None:
            raise TypeProblem(sp, f'only while "{service}" runs: what interrupts {service} is read from a model; '
                                  "check this property against one")
        labels = cancels(service)
        if labels is None:
            raise TypeProblem(sp, f'only while "{service}" runs: the model has no service {service} '
                                  "(write it MODULE.SERVICE)")
        guarded = action(a[0])
        cancelled = f", or to {' or '.join(labels)} before it starts" if labels else ""
        meaning = (f'[B . {show_action(guarded)}] false, B a path after which "{service}" does not run (a request runs '
                   f"from {service}:trigger to its finish, fail or interrupted{cancelled}; a trigger while one runs "
                   "renews it)")
        return Property(raw.name, only_while(guarded, service, labels, sp), raw.span, "only while", meaning=meaning)
    if op == "invariant":
        return Property(raw.name, invariant(pred(a[0]), sp), raw.span, "invariant")
    if op == "deadlock_free":
        return Property(raw.name, deadlock_free(sp), raw.span, "deadlock free")
    raise TypeProblem(sp, f"unexpected {op}")


# --- static checks ---------------------------------------------------------------------------------

def check_variables(f: State, problems: list[Diagnostic]) -> None:
    """Unbound variables, and variables under an odd number of negations from their binder (not monotone)."""

    def walk(g: State, env: dict[str, tuple[bool, SFix]], positive: bool, negations: list[Span]) -> None:
        if isinstance(g, SVar):
            bound = env.get(g.name)
            if bound is None:
                problems.append(Diagnostic(g.span, f"unbound variable {g.name}: no enclosing 'mu {g.name} .' or "
                                                   f"'nu {g.name} .'"))
            elif bound[0] != positive:
                fix = bound[1]
                where = f" (the negation at {negations[-1].line}:{negations[-1].column})" if negations else ""
                problems.append(Diagnostic(
                    g.span, f"{g.name} occurs under an odd number of negations{where}: {fix.sign} {g.name} "
                            f"(at {fix.var_span.line}:{fix.var_span.column}) is not monotone",
                    hint="a fixed-point variable must occur positively; move the negation inside, e.g. "
                         "not <a> X becomes [a] not X only with X replaced by its negation"))
        elif isinstance(g, SNot):
            walk(g.operand, env, not positive, negations + [g.span])
        elif isinstance(g, SImplies):
            walk(g.left, env, not positive, negations + [g.span])
            walk(g.right, env, positive, negations)
        elif isinstance(g, (SAnd, SOr)):
            walk(g.left, env, positive, negations)
            walk(g.right, env, positive, negations)
        elif isinstance(g, (SDia, SBox)):
            walk(g.operand, env, positive, negations)
        elif isinstance(g, SFix):
            walk(g.body, {**env, g.var: (positive, g)}, positive, negations)

    walk(f, {}, True, [])


def type_properties(raws: list[RawProperty], problems: list[Diagnostic],
                    cancels: Cancels | None = None) -> list[Property]:
    """Typed properties; problems are appended (several per file are reported together).  ``cancels``: the
    model's interrupters, for ``only while ... runs``."""
    out = []
    seen: dict[str, Span] = {}
    for raw in raws:
        try:
            prop = property_of(raw, cancels)
            prop.text = raw.text
        except TypeProblem as err:
            problems.append(Diagnostic(err.span, err.message))
            continue
        if raw.name in seen:
            first = seen[raw.name]
            problems.append(Diagnostic(raw.span, f"property {raw.name} is defined twice (first at "
                                                 f"{first.line}:{first.column})"))
        seen[raw.name] = raw.span
        check_variables(prop.formula, problems)
        out.append(prop)
    return out
