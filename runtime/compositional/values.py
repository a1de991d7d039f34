"""Set-valued evaluation of BIP guards and actions: what an expression may be, ``TOP`` when unknown.

The compositional analysis needs, for one atom on its own, every value a
variable may take.  An expression evaluates to a finite set of possible
values, or to ``TOP`` when it reads something that is not tracked (a
variable dropped from the abstraction, an extern that is not a codel) or when
the set grows past ``MAX_VALUES``.  Codel calls evaluate to their declared
outcomes, the environment's ``request_pending`` to true: the choices the
explorer branches on.  C semantics come from the engine's own helpers.
"""
from __future__ import annotations

from itertools import product
from typing import Any, Callable

from runtime.engine.cexpr import _cdiv, _cmod, coerce
from runtime.engine.errors import ModelError
from runtime.model.expressions import Assign, Binary, Call, Const, Do, Expr, If, PortData, Stmt, Unary, Var


class _Top:
    """The unknown value."""

    def __repr__(self) -> str:
        return "?"


TOP: Any = _Top()
MAX_VALUES = 32

Values = Any  # frozenset of concrete values, or TOP

_BINARY: dict[str, Callable[[Any, Any], Any]] = {
    "+": lambda a, b: a + b, "-": lambda a, b: a - b, "*": lambda a, b: a * b,
    "/": _cdiv, "%": _cmod,
    "==": lambda a, b: a == b, "!=": lambda a, b: a != b, "<": lambda a, b: a < b, "<=": lambda a, b: a <= b,
    ">": lambda a, b: a > b, ">=": lambda a, b: a >= b,
    "&": lambda a, b: a & b, "|": lambda a, b: a | b, "^": lambda a, b: a ^ b,
    "<<": lambda a, b: a << b, ">>": lambda a, b: a >> b,
}
_UNARY: dict[str, Callable[[Any], Any]] = {"-": lambda a: -a, "+": lambda a: +a, "!": lambda a: not a,
                                           "~": lambda a: ~a}


def truths(v: Values) -> frozenset[bool]:
    """The truth values a guard may have: ``{True}``, ``{False}`` or both (``TOP`` is both)."""
    if v is TOP:
        return frozenset((True, False))
    return frozenset(bool(x) for x in v)


def _limit(values: set) -> Values:
    return TOP if len(values) > MAX_VALUES else frozenset(values)


class Evaluator:
    """Evaluates expressions of one scope.

    ``lookup(name)`` gives a variable's values (or raises KeyError);
    ``port(p, x)`` those of port data; ``externs`` maps a function name to
    its possible results (a frozenset) or to None for an action without a
    result; an extern absent from it evaluates to ``TOP``.
    """

    def __init__(self, lookup: Callable[[str], Values], externs: dict[str, Values],
                 port: Callable[[str, str], Values] | None = None) -> None:
        self.lookup, self.externs, self.port = lookup, externs, port

    def value(self, e: Expr | None) -> Values:
        if e is None:
            return frozenset((True,))
        if isinstance(e, Const):
            return frozenset((e.value,))
        if isinstance(e, Var):
            return self.lookup(e.name)
        if isinstance(e, PortData):
            return self.port(e.port, e.name) if self.port is not None else TOP
        if isinstance(e, Call):
            for a in e.args:
                self.value(a)
            got = self.externs.get(e.function, TOP)
            return TOP if got is None else got
        if isinstance(e, Unary):
            v = self.value(e.operand)
            if v is TOP:
                return TOP
            return self._apply(lambda a: _UNARY[e.op](a), [v])
        if isinstance(e, Binary):
            return self._binary(e)
        return TOP

    def _binary(self, e: Binary) -> Values:
        left = self.value(e.left)
        if e.op in ("&&", "||"):
            lt = truths(left)
            short = False if e.op == "&&" else True
            if lt == {short}:
                return frozenset((short,))
            right = truths(self.value(e.right))
            out = {(a and b) if e.op == "&&" else (a or b) for a in lt for b in right}
            return frozenset(out)
        right = self.value(e.right)
        if left is TOP or right is TOP:
            return TOP
        return self._apply(_BINARY[e.op], [left, right])

    @staticmethod
    def _apply(fn: Callable, args: list[frozenset]) -> Values:
        out = set()
        for combo in product(*args):
            try:
                out.add(fn(*combo))
            except (ModelError, TypeError, ValueError, ZeroDivisionError):
                return TOP  # the engine would stop with a model error; stay conservative
        return _limit(out)


Env = tuple  # one entry per variable: a concrete value or TOP


def execute(body: list[Stmt] | tuple[Stmt, ...], env: Env, names: dict[str, int], types: list[str],
            make: Callable[[Env], Evaluator]) -> list[Env]:
    """Every environment ``body`` may end in from ``env`` (one per combination of possible values assigned)."""
    envs = [env]
    for stmt in body:
        nxt: list[Env] = []
        for e in envs:
            nxt.extend(_statement(stmt, e, names, types, make))
        envs = list(dict.fromkeys(nxt))
    return envs


def _statement(stmt: Stmt, env: Env, names, types, make) -> list[Env]:
    ev = make(env)
    if isinstance(stmt, Assign):
        if not isinstance(stmt.target, Var) or stmt.target.name not in names:
            ev.value(stmt.value)
            return [env]
        k = names[stmt.target.name]
        v = ev.value(stmt.value)
        if v is TOP:
            return [env[:k] + (TOP,) + env[k + 1:]]
        return [env[:k] + (coerce(x, types[k]),) + env[k + 1:] for x in v]
    if isinstance(stmt, If):
        out = []
        t = truths(ev.value(stmt.cond))
        if True in t:
            out.extend(execute(stmt.then, env, names, types, make))
        if False in t:
            out.extend(execute(stmt.orelse, env, names, types, make))
        return out
    if isinstance(stmt, Do):
        ev.value(stmt.call)
        return [env]
    return [env]
