"""Guards and actions back to BIP2 text with the fewest parentheses the reader needs.

The rules mirror bip2.lark: binary operators associate to the left, comparisons
do not chain, a unary operator applies to a primary or a call only, and a
negative number is read as one literal.  The writer uses this printer; the
engine may use it to show a guard or an action in a message.
"""
from __future__ import annotations

from runtime.bip2.literals import format_literal
from runtime.model.expressions import (
    BINARY_PRECEDENCE,
    Assign,
    Binary,
    Call,
    Const,
    Do,
    Expr,
    If,
    PortData,
    Stmt,
    Unary,
    Var,
)
from runtime.model.timing import Rate

_ATOM = 100          # names, calls, non-negative literals, parenthesised expressions
_UNARY = 50          # -x, !x, ~x and negative literals
_NON_ASSOCIATIVE = {"==", "!=", "<", "<=", ">", ">="}


def _precedence(e: Expr) -> int:
    if isinstance(e, Binary):
        return BINARY_PRECEDENCE[e.op]
    if isinstance(e, Unary):
        return _UNARY
    if isinstance(e, Const) and not isinstance(e.value, (bool, str)) and _is_negative(e.value):
        return _UNARY
    return _ATOM


def _is_negative(number: int | float) -> bool:
    return number < 0 or (isinstance(number, float) and str(number).startswith("-"))


def expr(e: Expr) -> str:
    """BIP2 text of an expression."""
    if isinstance(e, Const):
        return format_literal(e.value)
    if isinstance(e, Var):
        return e.name
    if isinstance(e, PortData):
        return f"{e.port}.{e.name}"
    if isinstance(e, Call):
        return f"{e.function}({', '.join(expr(a) for a in e.args)})"
    if isinstance(e, Unary):
        # "-5" reads back as the literal -5, so the negation of a literal keeps its parentheses: "-(5)"
        literal = isinstance(e.operand, Const) and not isinstance(e.operand.value, (bool, str))
        return f"{e.op}{_wrap(e.operand, _precedence(e.operand) < _ATOM or (e.op == '-' and literal))}"
    if isinstance(e, Binary):
        prec = BINARY_PRECEDENCE[e.op]
        left_tight = _precedence(e.left) < prec or (e.op in _NON_ASSOCIATIVE and _precedence(e.left) == prec)
        right_tight = _precedence(e.right) <= prec
        return f"{_wrap(e.left, left_tight)} {e.op} {_wrap(e.right, right_tight)}"
    raise TypeError(f"not an expression: {e!r}")


def _wrap(e: Expr, parenthesise: bool) -> str:
    text = expr(e)
    return f"({text})" if parenthesise else text


def stmt_lines(stmts: list[Stmt] | tuple[Stmt, ...], indent: str = "  ") -> list[str]:
    """One line per simple statement; ``if``/``else``/``fi`` on their own lines, bodies indented."""
    lines: list[str] = []
    for s in stmts:
        if isinstance(s, Assign):
            lines.append(f"{expr(s.target)} = {expr(s.value)};")
        elif isinstance(s, Do):
            lines.append(f"{expr(s.call)};")
        elif isinstance(s, Rate):
            lines.append(f"{s.clock}' = {expr(s.value)};")
        elif isinstance(s, If):
            lines.append(f"if ({expr(s.cond)}) then")
            lines += [indent + line for line in stmt_lines(s.then, indent)]
            if s.orelse:
                lines.append("else")
                lines += [indent + line for line in stmt_lines(s.orelse, indent)]
            lines.append("fi")
        else:
            raise TypeError(f"not a statement: {s!r}")
    return lines


def action(stmts: list[Stmt] | tuple[Stmt, ...], margin: str = "", indent: str = "  ", width: int = 88) -> str:
    """``{ ... }`` on one line when short and without ``if``, else one statement a line under ``margin``."""
    lines = stmt_lines(stmts, indent)
    flat = "{ " + " ".join(lines) + " }" if lines else "{ }"
    if not any(isinstance(s, If) for s in stmts) and len(margin) + len(flat) <= width:
        return flat
    body = "\n".join(f"{margin}{indent}{line}" for line in lines)
    return "{\n" + body + "\n" + margin + "}"
