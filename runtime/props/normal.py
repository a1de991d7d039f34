"""Formulas ready to check: negations pushed to the leaves, regular modalities unfolded, alternation refused.

``compile_formula`` gives a :class:`Equations` table: one node per
subformula (shared subformulas once), each an AND or OR of children with a
fixed-point *block*.  Unfolding follows the MCL reading:
``<R1.R2>F = <R1><R2>F``, ``<R1|R2>F = <R1>F or <R2>F``, ``<R*>F = mu Z.(F or <R>Z)``,
``<R+>F = <R><R*>F`` and dually for ``[R]`` with ``nu`` and ``and``.  A formula is
alternation-free when no fixed point refers to a variable bound by an
enclosing fixed point of the other sign; same-sign fixed points nested in
each other form one block, solved together.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from runtime.diagnostics import Diagnostic, Span
from runtime.props.formulas import (
    Action,
    AConst,
    Pred,
    PNot,
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
    show_regular,
)

# Node kinds of the equation table.
TT, FF, PRED, AND, OR, DIA, BOX, FIX = range(8)
KIND_NAMES = ("true", "false", "pred", "and", "or", "diamond", "box", "fix")


# --- positive normal form ---------------------------------------------------------------------------

def positive(f: State, negate: bool = False) -> State:
    """``f`` (or ``not f``) without ``not``/``implies`` above predicates; needs monotone variables."""
    sp = f.span
    if isinstance(f, SConst):
        return SConst(f.value != negate, sp)
    if isinstance(f, SPred):
        return SPred(PNot(f.pred, sp), sp) if negate else f
    if isinstance(f, SNot):
        return positive(f.operand, not negate)
    if isinstance(f, SImplies):
        return positive(SOr(SNot(f.left, sp), f.right, sp), negate)
    if isinstance(f, SAnd):
        cls = SOr if negate else SAnd
        return cls(positive(f.left, negate), positive(f.right, negate), sp)
    if isinstance(f, SOr):
        cls = SAnd if negate else SOr
        return cls(positive(f.left, negate), positive(f.right, negate), sp)
    if isinstance(f, SDia):
        cls = SBox if negate else SDia
        return cls(f.path, positive(f.operand, negate), sp)
    if isinstance(f, SBox):
        cls = SDia if negate else SBox
        return cls(f.path, positive(f.operand, negate), sp)
    if isinstance(f, SFix):
        sign = {"mu": "nu", "nu": "mu"}[f.sign] if negate else f.sign
        return SFix(sign, f.var, positive(f.body, negate), sp, f.var_span)
    if isinstance(f, SVar):
        return f  # not (sigma X. F) = dual-sigma X. not F[not X / X]: the occurrence stays X
    raise TypeError(f"not a state formula: {f!r}")


# --- unfolding regular modalities --------------------------------------------------------------------

@dataclass
class _Fresh:
    n: int = 0

    def __call__(self) -> str:
        self.n += 1
        return f"_R{self.n}"


def unfold(f: State, fresh: _Fresh | None = None) -> State:
    """Replace ``<R>``/``[R]`` with regular R by modalities on single actions and fixed points."""
    fresh = fresh or _Fresh()
    sp = f.span
    if isinstance(f, (SAnd, SOr)):
        return type(f)(unfold(f.left, fresh), unfold(f.right, fresh), sp)
    if isinstance(f, SFix):
        return SFix(f.sign, f.var, unfold(f.body, fresh), sp, f.var_span)
    if isinstance(f, (SDia, SBox)):
        return _modal(isinstance(f, SDia), f.path, unfold(f.operand, fresh), fresh, sp)
    return f


def _modal(dia: bool, r: Regular, then: State, fresh: _Fresh, sp: Span) -> State:
    cls = SDia if dia else SBox
    if isinstance(r, RAct):
        return cls(r, then, sp)
    if isinstance(r, RSeq):
        return _modal(dia, r.left, _modal(dia, r.right, then, fresh, sp), fresh, sp)
    if isinstance(r, RAlt):
        join = SOr if dia else SAnd
        return join(_modal(dia, r.left, then, fresh, sp), _modal(dia, r.right, then, fresh, sp), sp)
    if isinstance(r, (RStar, RPlus)):
        z = fresh()
        join = SOr if dia else SAnd
        star = SFix("mu" if dia else "nu", z, join(then, _modal(dia, r.operand, SVar(z, r.span), fresh, sp), sp),
                    r.span, r.span)
        object.__setattr__(star, "origin", show_regular(r))
        if isinstance(r, RPlus):
            return _modal(dia, r.operand, star, fresh, sp)
        return star
    raise TypeError(f"not a regular formula: {r!r}")


# --- alternation ---------------------------------------------------------------------------------------

def _describe_fix(fix: SFix) -> str:
    origin = getattr(fix, "origin", None)
    if origin is not None:
        kind = "least" if fix.sign == "mu" else "greatest"
        return f"the iteration {origin} (a {kind} fixed point, {fix.sign})"
    return f"{fix.sign} {fix.var}"


def check_alternation(f: State, problems: list[Diagnostic]) -> None:
    """A fixed point referring to a variable of an enclosing fixed point of the other sign is an error."""
    reported: set[tuple[int, int]] = set()

    def walk(g: State, stack: list[SFix]) -> None:
        if isinstance(g, SVar):
            for k in range(len(stack) - 1, -1, -1):
                if stack[k].var == g.name:
                    binder = stack[k]
                    for inner in stack[k + 1:]:
                        if inner.sign != binder.sign and (id(binder), id(inner)) not in reported:
                            reported.add((id(binder), id(inner)))
                            bs = binder.var_span
                            problems.append(Diagnostic(
                                inner.span, f"alternation: {_describe_fix(inner)} depends on {binder.var}, bound by "
                                            f"{binder.sign} {binder.var} at {bs.line}:{bs.column}; only "
                                            "alternation-free formulas can be checked",
                                hint="a least and a greatest fixed point must not depend on each other"))
                    return
        elif isinstance(g, (SAnd, SOr)):
            walk(g.left, stack)
            walk(g.right, stack)
        elif isinstance(g, (SDia, SBox)):
            walk(g.operand, stack)
        elif isinstance(g, SFix):
            walk(g.body, stack + [g])

    walk(f, [])


# --- the equation table ----------------------------------------------------------------------------------

@dataclass
class Equations:
    """Subformula nodes: ``kind``, ``arg`` (action or predicate index, or -1), ``kids``, ``block`` and ``sign``.

    ``actions`` and ``preds`` list the distinct action formulas and state
    predicates.  Node 0 is the whole formula.  A FIX node is the identity
    on its body: variable occurrences point to their FIX node.
    """

    kind: list[int] = field(default_factory=list)
    arg: list[int] = field(default_factory=list)
    kids: list[tuple[int, ...]] = field(default_factory=list)
    block: list[int] = field(default_factory=list)
    sign: list[str] = field(default_factory=list)
    text: list[str] = field(default_factory=list)
    actions: list[Action] = field(default_factory=list)
    preds: list[Pred] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.kind)

    def local(self, node: int) -> bool:
        """True when the node needs no fixed point: its value at a state is a finite unrolling."""
        seen = set()
        stack = [node]
        while stack:
            n = stack.pop()
            if n in seen:
                continue
            seen.add(n)
            if self.kind[n] == FIX:
                return False
            stack.extend(self.kids[n])
        return True


def compile_formula(f: State) -> Equations:
    """The equation table of a positive, unfolded, alternation-free formula."""
    eq = Equations()
    action_ids: dict[Action, int] = {}
    pred_ids: dict[Pred, int] = {}
    memo: dict[tuple[int, tuple[int, ...]], int] = {}

    def new(kind: int, arg: int, block: int, sign: str, text: str) -> int:
        eq.kind.append(kind)
        eq.arg.append(arg)
        eq.kids.append(())
        eq.block.append(block)
        eq.sign.append(sign)
        eq.text.append(text)
        return len(eq.kind) - 1

    def block_of(stack: list[tuple[SFix, int]]) -> tuple[int, str]:
        if not stack:
            return -1, "mu"
        sign = stack[-1][0].sign
        k = len(stack) - 1
        while k > 0 and stack[k - 1][0].sign == sign:
            k -= 1
        return stack[k][1], sign

    def walk(g: State, stack: list[tuple[SFix, int]]) -> int:
        key = (id(g), tuple(n for _, n in stack))
        if key in memo:
            return memo[key]
        block, sign = block_of(stack)
        if isinstance(g, SConst):
            n = new(TT if g.value else FF, -1, block, sign, "true" if g.value else "false")
        elif isinstance(g, SPred):
            n = new(PRED, pred_ids.setdefault(g.pred, len(pred_ids)), block, sign, "pred")
            if n is not None and len(eq.preds) < len(pred_ids):
                eq.preds.append(g.pred)
        elif isinstance(g, (SAnd, SOr)):
            n = new(AND if isinstance(g, SAnd) else OR, -1, block, sign, "and" if isinstance(g, SAnd) else "or")
            eq.kids[n] = (walk(g.left, stack), walk(g.right, stack))
        elif isinstance(g, (SDia, SBox)):
            a = g.path.action if isinstance(g.path, RAct) else AConst(True)
            aid = action_ids.setdefault(a, len(action_ids))
            if len(eq.actions) < len(action_ids):
                eq.actions.append(a)
            n = new(DIA if isinstance(g, SDia) else BOX, aid, block, sign, "dia" if isinstance(g, SDia) else "box")
            eq.kids[n] = (walk(g.operand, stack),)
        elif isinstance(g, SFix):
            n = len(eq.kind)
            inner = stack + [(g, n)]
            b, s = block_of(inner)
            new(FIX, -1, b, s, f"{g.sign} {g.var}")
            memo[key] = n
            eq.kids[n] = (walk(g.body, inner),)
            return n
        elif isinstance(g, SVar):
            for fix, node in reversed(stack):
                if fix.var == g.name:
                    return node
            raise ValueError(f"unbound variable {g.name}")
        else:
            raise TypeError(f"not a normal formula: {g!r}")
        memo[key] = n
        return n

    walk(f, [])
    return eq


def normalize(f: State, problems: list[Diagnostic]) -> State:
    """Positive normal form with regular modalities unfolded; alternation problems are appended."""
    g = unfold(positive(f))
    check_alternation(g, problems)
    return g
