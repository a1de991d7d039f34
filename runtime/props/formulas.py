"""Typed formulas: action, regular and state formulas, state predicates, and the pattern shorthands.

Every node keeps the :class:`~runtime.diagnostics.Span` of the text it comes
from (not compared), so that later checks (alternation, unknown places) point
at the right column.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Union

from runtime.diagnostics import NOWHERE, Span


def _span() -> Span:
    return field(default=NOWHERE, compare=False, repr=False)


# --- action formulas: predicates on interaction labels ---------------------------------------------

@dataclass(frozen=True)
class ALabel:
    """``"text"``: a label equal to text, or to ``M.text`` for one leading module name; ``*``/``?`` are wildcards."""

    text: str
    span: Span = _span()
    optional: bool = False  # written ``optional "text"``: matching no label of the model is intended


@dataclass(frozen=True)
class ARegex:
    """``'re'``: a label matched in full by a Python regular expression."""

    pattern: str
    span: Span = _span()
    optional: bool = False  # written ``optional 're'``


@dataclass(frozen=True)
class AConst:
    value: bool
    span: Span = _span()


@dataclass(frozen=True)
class ANot:
    operand: "Action"
    span: Span = _span()


@dataclass(frozen=True)
class AAnd:
    left: "Action"
    right: "Action"
    span: Span = _span()


@dataclass(frozen=True)
class AOr:
    left: "Action"
    right: "Action"
    span: Span = _span()


Action = Union[ALabel, ARegex, AConst, ANot, AAnd, AOr]


# --- regular formulas: sequences of actions ---------------------------------------------------------

@dataclass(frozen=True)
class RAct:
    action: Action
    span: Span = _span()


@dataclass(frozen=True)
class RSeq:
    left: "Regular"
    right: "Regular"
    span: Span = _span()


@dataclass(frozen=True)
class RAlt:
    left: "Regular"
    right: "Regular"
    span: Span = _span()


@dataclass(frozen=True)
class RStar:
    operand: "Regular"
    span: Span = _span()


@dataclass(frozen=True)
class RPlus:
    operand: "Regular"
    span: Span = _span()


Regular = Union[RAct, RSeq, RAlt, RStar, RPlus]


# --- state predicates: places and variables ---------------------------------------------------------

@dataclass(frozen=True)
class PAt:
    """``atom @ PLACE``: the place is marked."""

    atom: str
    place: str
    span: Span = _span()


@dataclass(frozen=True)
class PCmp:
    """``atom.var OP value`` (``atom.var`` alone: ``!= false``); ``path`` is split into atom and variable on binding."""

    path: str
    op: str
    value: int | bool
    span: Span = _span()


@dataclass(frozen=True)
class PConst:
    value: bool
    span: Span = _span()


@dataclass(frozen=True)
class PNot:
    operand: "Pred"
    span: Span = _span()


@dataclass(frozen=True)
class PAnd:
    left: "Pred"
    right: "Pred"
    span: Span = _span()


@dataclass(frozen=True)
class POr:
    left: "Pred"
    right: "Pred"
    span: Span = _span()


Pred = Union[PAt, PCmp, PConst, PNot, PAnd, POr]


# --- state formulas ----------------------------------------------------------------------------------

@dataclass(frozen=True)
class SConst:
    value: bool
    span: Span = _span()


@dataclass(frozen=True)
class SPred:
    pred: Pred
    span: Span = _span()


@dataclass(frozen=True)
class SNot:
    operand: "State"
    span: Span = _span()


@dataclass(frozen=True)
class SAnd:
    left: "State"
    right: "State"
    span: Span = _span()


@dataclass(frozen=True)
class SOr:
    left: "State"
    right: "State"
    span: Span = _span()


@dataclass(frozen=True)
class SImplies:
    left: "State"
    right: "State"
    span: Span = _span()


@dataclass(frozen=True)
class SDia:
    """``<R> F``: some path matching R leads to a state satisfying F."""

    path: Regular
    operand: "State"
    span: Span = _span()


@dataclass(frozen=True)
class SBox:
    """``[R] F``: every path matching R leads to a state satisfying F."""

    path: Regular
    operand: "State"
    span: Span = _span()


@dataclass(frozen=True)
class SFix:
    """``mu X . F`` (``sign == "mu"``, least) or ``nu X . F`` (greatest)."""

    sign: str
    var: str
    body: "State"
    span: Span = _span()
    var_span: Span = _span()


@dataclass(frozen=True)
class SVar:
    name: str
    span: Span = _span()


State = Union[SConst, SPred, SNot, SAnd, SOr, SImplies, SDia, SBox, SFix, SVar]


@dataclass
class Property:
    """A named property: its formula, the text form of a shorthand it came from, and where it is written."""

    name: str
    formula: State
    span: Span
    pattern: str = ""  # "never", "precedes", "leads to", "invariant", "deadlock free", or "" for a formula
    text: str = ""  # the property as written in its file
    meaning: str = ""  # what a shorthand means, where its formula is too long to read (``only while``)


def show_action(a: Action) -> str:
    if isinstance(a, ALabel):
        return f'"{a.text}"'
    if isinstance(a, ARegex):
        return f"'{a.pattern}'"
    if isinstance(a, AConst):
        return "true" if a.value else "false"
    if isinstance(a, ANot):
        return f"not {_wrap_action(a.operand)}"
    if isinstance(a, AAnd):
        return f"{_wrap_action(a.left)} and {_wrap_action(a.right)}"
    return f"{_wrap_action(a.left)} or {_wrap_action(a.right)}"


def _wrap_action(a: Action) -> str:
    text = show_action(a)
    return f"({text})" if isinstance(a, (AAnd, AOr)) else text


def show_regular(r: Regular) -> str:
    if isinstance(r, RAct):
        return show_action(r.action)
    if isinstance(r, RSeq):
        return f"{show_regular(r.left)} . {show_regular(r.right)}"
    if isinstance(r, RAlt):
        return f"({show_regular(r.left)} | {show_regular(r.right)})"
    inner = show_regular(r.operand)
    if not isinstance(r.operand, RAct) or isinstance(r.operand.action, (ANot, AAnd, AOr)):
        inner = f"({inner})"
    return inner + ("*" if isinstance(r, RStar) else "+")


def show(f: State) -> str:
    """The formula as text (MCL-like), for reports."""
    if isinstance(f, SConst):
        return "true" if f.value else "false"
    if isinstance(f, SPred):
        return "{" + show_pred(f.pred) + "}"
    if isinstance(f, SNot):
        return f"not {_wrap(f.operand)}"
    if isinstance(f, SAnd):
        return f"{_wrap(f.left)} and {_wrap(f.right)}"
    if isinstance(f, SOr):
        return f"{_wrap(f.left)} or {_wrap(f.right)}"
    if isinstance(f, SImplies):
        return f"{_wrap(f.left)} implies {_wrap(f.right)}"
    if isinstance(f, SDia):
        return f"<{show_regular(f.path)}> {_wrap(f.operand)}"
    if isinstance(f, SBox):
        return f"[{show_regular(f.path)}] {_wrap(f.operand)}"
    if isinstance(f, SFix):
        return f"{f.sign} {f.var} . {show(f.body)}"
    return f.name


def _wrap(f: State) -> str:
    text = show(f)
    return f"({text})" if isinstance(f, (SAnd, SOr, SImplies, SFix)) else text


def show_pred(p: Pred) -> str:
    if isinstance(p, PAt):
        return f"{p.atom} @ {p.place}"
    if isinstance(p, PCmp):
        v = str(p.value).lower() if isinstance(p.value, bool) else str(p.value)
        return f"{p.path} {p.op} {v}"
    if isinstance(p, PConst):
        return "true" if p.value else "false"
    if isinstance(p, PNot):
        return f"not {show_pred(p.operand)}"
    if isinstance(p, PAnd):
        return f"({show_pred(p.left)} and {show_pred(p.right)})"
    return f"({show_pred(p.left)} or {show_pred(p.right)})"
