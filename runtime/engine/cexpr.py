"""Guards and actions to Python source text, with C semantics where Python differs.

Differences handled here (documented in docs/engine.md):
``/`` on two ints truncates toward zero and ``%`` takes the sign of the
dividend (C99); ``&&``, ``||``, ``!`` give bools; a float assigned to an
``int`` variable is truncated.  Integers do not overflow (Python ints):
a model that relies on wrap-around behaves differently here.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable

from runtime.engine.errors import EngineError, FlattenError, ModelError
from runtime.model.expressions import Assign, Binary, Call, Const, Do, Expr, If, PortData, Stmt, Unary, Var

NUMERIC = ("int", "float")
COMPARISONS = ("==", "!=", "<", "<=", ">", ">=")
BITWISE = ("&", "|", "^", "<<", ">>")


def default_value(type_name: str) -> Any:
    """The value a variable of this type has before anything assigns it (C leaves it undefined)."""
    return {"int": 0, "bool": False, "float": 0.0, "string": ""}.get(type_name)


def coerce(value: Any, type_name: str) -> Any:
    """Convert a constant to a declared native type, as a C assignment would."""
    if type_name == "int" and isinstance(value, (bool, float)):
        return int(value)
    if type_name == "float" and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    if type_name == "bool" and isinstance(value, (int, float)):
        return bool(value)
    return value


# --- helpers the generated code calls -------------------------------------------------

def _idiv(a: int, b: int) -> int:
    """C integer division: truncates toward zero."""
    if b == 0:
        raise ModelError("integer division by zero")
    q = abs(a) // abs(b)
    return q if (a >= 0) == (b > 0) else -q


def _imod(a: int, b: int) -> int:
    """C remainder: same sign as the dividend, so that a == (a/b)*b + a%b."""
    if b == 0:
        raise ModelError("integer remainder by zero")
    return a - b * _idiv(a, b)


def _cdiv(a, b):
    """``/`` when the operand types are not known statically."""
    if isinstance(a, int) and isinstance(b, int):
        return _idiv(a, b)
    if b == 0:
        raise ModelError("division by zero")
    return a / b


def _cmod(a, b):
    """``%`` when the operand types are not known statically."""
    if isinstance(a, int) and isinstance(b, int):
        return _imod(a, b)
    if b == 0:
        raise ModelError("remainder by zero")
    return math.fmod(a, b)


HELPERS: dict[str, Callable] = {"_idiv": _idiv, "_imod": _imod, "_cdiv": _cdiv, "_cmod": _cmod}


# --- translation ------------------------------------------------------------------------

@dataclass
class Name:
    """What a BIP name stands for in one context: Python source, its type, whether it may be assigned."""

    src: str
    type: str | None
    assignable: bool = False


@dataclass
class Scope:
    """How the names of one context (an atom, a connector, a priority guard) translate to Python.

    ``variables`` maps plain names; ``ports`` maps ``(port, field)`` of connector
    port data (or ``(component, data)`` in compound priority guards); constants
    are inlined as literals; calls go to ``_x_<name>`` bound to the externs.
    """

    where: str
    variables: dict[str, Name] = field(default_factory=dict)
    ports: dict[tuple[str, str], Name] = field(default_factory=dict)
    constants: dict[str, tuple[Any, str]] = field(default_factory=dict)
    externs: dict[str, str | None] = field(default_factory=dict)  # name -> return type
    called: set[str] = field(default_factory=set)

    def error(self, message: str) -> EngineError:
        return FlattenError(f"{self.where}: {message}")


def literal(value: Any) -> str:
    """Python source for a constant value."""
    if isinstance(value, float) and (math.isinf(value) or math.isnan(value)):
        return f"float({str(value)!r})"
    return repr(value)


def expr(e: Expr, scope: Scope) -> tuple[str, str | None]:
    """Python source for an expression and its static type (None when unknown)."""
    if isinstance(e, Const):
        v = e.value
        t = (
            "bool"
            if isinstance(v, bool)
            else "int"
            if isinstance(v, int)
            else "float"
            if isinstance(v, float)
            else "string"
        )
        return literal(v), t
    if isinstance(e, Var):
        if e.name in scope.variables:
            n = scope.variables[e.name]
            return n.src, n.type
        if e.name in scope.constants:
            v, t = scope.constants[e.name]
            return literal(v), t
        raise scope.error(f"unknown name '{e.name}'")
    if isinstance(e, PortData):
        n = scope.ports.get((e.port, e.name))
        if n is None:
            raise scope.error(f"unknown port data '{e.port}.{e.name}'")
        return n.src, n.type
    if isinstance(e, Unary):
        s, t = expr(e.operand, scope)
        if e.op == "!":
            return f"(not {s})", "bool"
        if e.op in ("-", "+", "~"):
            return f"({e.op}{s})", "int" if e.op == "~" else t
        raise scope.error(f"unknown unary operator '{e.op}'")
    if isinstance(e, Binary):
        return _binary(e, scope)
    if isinstance(e, Call):
        if e.function not in scope.externs:
            raise scope.error(f"call of '{e.function}', which is not declared 'extern function'")
        scope.called.add(e.function)
        args = ", ".join(expr(a, scope)[0] for a in e.args)
        return f"_x_{e.function}({args})", scope.externs[e.function]
    raise scope.error(f"not an expression: {e!r}")


def _binary(e: Binary, scope: Scope) -> tuple[str, str | None]:
    ls, lt = expr(e.left, scope)
    rs, rt = expr(e.right, scope)
    op = e.op
    if op in ("&&", "||"):
        py = "and" if op == "&&" else "or"
        if lt != "bool":
            ls = f"bool({ls})"
        if rt != "bool":
            rs = f"bool({rs})"
        return f"({ls} {py} {rs})", "bool"
    if op in COMPARISONS:
        return f"({ls} {op} {rs})", "bool"
    if op in BITWISE:
        return f"({ls} {op} {rs})", "int"
    both_int = lt == "int" and rt == "int"
    numeric_t = "int" if both_int else "float" if (lt in NUMERIC and rt in NUMERIC) else None
    if op == "/":
        if both_int:
            return f"_idiv({ls}, {rs})", "int"
        return f"_cdiv({ls}, {rs})", numeric_t
    if op == "%":
        if both_int:
            return f"_imod({ls}, {rs})", "int"
        return f"_cmod({ls}, {rs})", numeric_t
    if op in ("+", "-", "*"):
        t = numeric_t if numeric_t else ("string" if op == "+" and lt == rt == "string" else None)
        return f"({ls} {op} {rs})", t
    raise scope.error(f"unknown operator '{op}'")


def condition(e: Expr | None, scope: Scope) -> str:
    """A guard as a Python expression that is a bool (``True`` when there is no guard)."""
    if e is None:
        return "True"
    s, t = expr(e, scope)
    return s if t == "bool" else f"bool({s})"


def statements(body: list[Stmt] | tuple[Stmt, ...], scope: Scope, indent: str) -> list[str]:
    """Python lines for a block of BIP statements (empty list when the block is empty)."""
    out: list[str] = []
    for st in body:
        if isinstance(st, Assign):
            if isinstance(st.target, Var):
                n = scope.variables.get(st.target.name)
                what = st.target.name
            else:
                n = scope.ports.get((st.target.port, st.target.name))
                what = f"{st.target.port}.{st.target.name}"
            if n is None:
                if isinstance(st.target, Var) and st.target.name in scope.constants:
                    raise scope.error(f"assignment to constant '{what}'")
                raise scope.error(f"assignment to unknown '{what}'")
            if not n.assignable:
                raise scope.error(f"'{what}' cannot be assigned here")
            vs, vt = expr(st.value, scope)
            if n.type == "int" and vt in ("float", "bool"):
                vs = f"int({vs})"
            elif n.type == "bool" and vt not in ("bool",):
                vs = f"bool({vs})"
            out.append(f"{indent}{n.src} = {vs}")
        elif isinstance(st, If):
            out.append(f"{indent}if {condition(st.cond, scope)}:")
            out.extend(statements(st.then, scope, indent + "    ") or [f"{indent}    pass"])
            if st.orelse:
                out.append(f"{indent}else:")
                out.extend(statements(st.orelse, scope, indent + "    "))
        elif isinstance(st, Do):
            out.append(f"{indent}{expr(st.call, scope)[0]}")
        else:
            raise scope.error(f"not a statement: {st!r}")
    return out


def evaluate(e: Expr, constants: dict[str, tuple[Any, str]], where: str) -> Any:
    """Value of a constant expression (instance arguments, parameters, package constants)."""
    scope = Scope(where=where, constants=constants)
    try:
        src, _ = expr(e, scope)
    except EngineError as err:
        raise type(err)(f"{err} (only constants and parameters are allowed here)") from None
    return eval(src, dict(HELPERS))  # noqa: S307 - source built from a constant expression tree
