"""Guards and actions to C source text, with the values the Python step computes.

Values are ``int64_t`` (bools 0/1).  Where Python and C differ the generated
code calls a checked helper: overflow of ``+ - *`` and ``<<``, division by
zero, a negative shift all stop the step with an error code, and the Python
step then words the error (or, if Python computes a value, the compiled
search gives way to it: Python integers do not overflow).  Floats, strings
and externs other than choice points and the request externs are not
translated: :class:`Unsupported` says why, and the Python explorer runs.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from runtime.model.expressions import (
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

COMPARISONS = ("==", "!=", "<", "<=", ">", ">=")
CHECKED = {"+": "ADD", "-": "SUB", "*": "MUL", "/": "IDIV", "%": "IMOD", "<<": "SHL", ">>": "SHR"}


class Unsupported(Exception):
    """The model uses something the C back end does not translate; the message says what."""


@dataclass
class CName:
    """What a BIP name stands for in C: an lvalue or rvalue, its type, whether it may be assigned."""

    src: str
    type: str
    assignable: bool = False


@dataclass
class Externs:
    """How extern calls translate: choice points (index of their domain), request services, where a call may go."""

    choices: dict[str, int] = field(default_factory=dict)
    services: list[str] | None = None  # None: no budget, request_pending always holds
    returns: dict[str, str | None] = field(default_factory=dict)


@dataclass
class CScope:
    where: str
    externs: Externs
    variables: dict[str, CName] = field(default_factory=dict)
    ports: dict[tuple[str, str], CName] = field(default_factory=dict)
    constants: dict[str, tuple[Any, str]] = field(default_factory=dict)
    in_guard: bool = False


def literal(value: Any, where: str) -> tuple[str, str]:
    if isinstance(value, bool):
        return ("1" if value else "0"), "bool"
    if isinstance(value, int):
        if not -(1 << 63) <= value < (1 << 63):
            raise Unsupported(f"{where}: the constant {value} does not fit in 64 bits")
        return (f"INT64_C({value})" if value >= 0 else f"(INT64_C({value + 1}) - 1)"), "int"
    raise Unsupported(f"{where}: {type(value).__name__} values ({value!r}) are explored in Python only")


def expr(e: Expr, sc: CScope) -> tuple[str, str]:
    """C source for an expression and its type (``int`` or ``bool``)."""
    if isinstance(e, Const):
        return literal(e.value, sc.where)
    if isinstance(e, Var):
        if e.name in sc.variables:
            n = sc.variables[e.name]
            return n.src, n.type
        if e.name in sc.constants:
            value, _ = sc.constants[e.name]
            return literal(value, sc.where)
        raise Unsupported(f"{sc.where}: unknown name '{e.name}'")
    if isinstance(e, PortData):
        n = sc.ports.get((e.port, e.name))
        if n is None:
            raise Unsupported(f"{sc.where}: unknown port data '{e.port}.{e.name}'")
        return n.src, n.type
    if isinstance(e, Unary):
        s, t = expr(e.operand, sc)
        if e.op == "!":
            return f"(!{s})", "bool"
        if e.op == "-":
            return f"NEG({s})", "int"
        if e.op == "+":
            return s, t
        if e.op == "~":
            return f"(~{s})", "int"
        raise Unsupported(f"{sc.where}: unknown unary operator '{e.op}'")
    if isinstance(e, Binary):
        ls, lt = expr(e.left, sc)
        rs, rt = expr(e.right, sc)
        op = e.op
        if op in ("&&", "||"):
            return f"(({ls} != 0) {op} ({rs} != 0))", "bool"
        if op in COMPARISONS:
            return f"({ls} {op} {rs})", "bool"
        if op in ("&", "|", "^"):
            return f"({ls} {op} {rs})", "bool" if lt == rt == "bool" else "int"
        if op in CHECKED:
            return f"{CHECKED[op]}({ls}, {rs})", "int"
        raise Unsupported(f"{sc.where}: unknown operator '{op}'")
    if isinstance(e, Call):
        return call(e, sc)
    raise Unsupported(f"{sc.where}: not an expression: {e!r}")


def call(e: Call, sc: CScope) -> tuple[str, str]:
    ex = sc.externs
    if e.function in ex.choices:
        if sc.in_guard:
            raise Unsupported(f"{sc.where}: choice extern {e.function} called in a guard")
        return f"choice({ex.choices[e.function]})", "int"
    if e.function in ("request_pending", "take_request"):
        if ex.services is None:
            return ("1", "bool") if e.function == "request_pending" else ("0", "int")
        if not (e.args and isinstance(e.args[0], Const) and e.args[0].value in ex.services):
            raise Unsupported(f"{sc.where}: {e.function} needs a known service name as a constant")
        k = ex.services.index(e.args[0].value)
        return (f"PENDING({k})", "bool") if e.function == "request_pending" else (f"TAKE({k})", "int")
    raise Unsupported(f"{sc.where}: extern {e.function} is bound to Python code")


def condition(e: Expr | None, sc: CScope) -> str:
    if e is None:
        return "1"
    s, t = expr(e, sc)
    return s if t == "bool" else f"({s} != 0)"


def statements(body, sc: CScope, indent: str) -> list[str]:
    out: list[str] = []
    for st in body:
        if isinstance(st, Assign):
            if isinstance(st.target, Var):
                n = sc.variables.get(st.target.name)
            else:
                n = sc.ports.get((st.target.port, st.target.name))
            if n is None or not n.assignable:
                raise Unsupported(f"{sc.where}: assignment the Python step refuses")
            vs, vt = expr(st.value, sc)
            if n.type == "bool" and vt != "bool":
                vs = f"({vs} != 0)"
            out.append(f"{indent}{n.src} = {vs};")
        elif isinstance(st, If):
            out.append(f"{indent}if ({condition(st.cond, sc)}) {{")
            out.extend(statements(st.then, sc, indent + "    "))
            if st.orelse:
                out.append(f"{indent}}} else {{")
                out.extend(statements(st.orelse, sc, indent + "    "))
            out.append(f"{indent}}}")
        elif isinstance(st, Do):
            out.append(f"{indent}(void){expr(st.call, sc)[0]};")
        else:
            raise Unsupported(f"{sc.where}: not a statement: {st!r}")
    return out


def c_type(type_name: str, where: str) -> str:
    """``int`` or ``bool``; anything else is explored in Python only."""
    if type_name in ("int", "bool"):
        return type_name
    raise Unsupported(f"{where}: {type_name} data are explored in Python only")


__all__ = ["CName", "CScope", "Externs", "Stmt", "Unsupported", "c_type", "condition", "expr", "literal",
           "statements"]
