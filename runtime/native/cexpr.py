"""Guards and actions to C source text, with the values the Python step computes.

Values are ``int64_t`` (bools 0/1); a float is stored as the bits of a C
``double`` and computed with IEEE doubles as Python does, comparisons of an
int with a float are exact as in Python, and where Python raises (a float
division or remainder by zero, ``fmod`` of an infinity, an infinite or NaN
float made an int) the C step stops with an error code too; a string is
stored as a number and may only be copied and compared with ``==``/``!=``.  Where Python and C differ the generated
code calls a checked helper: overflow of ``+ - *`` and ``<<``, division by
zero, a negative shift all stop the step with an error code, and the Python
step then words the error (or, if Python computes a value, the compiled
search gives way to it: Python integers do not overflow).  What Python
would type differently (an int stored in a float variable stays an int
there) and externs other than choice points and the request externs are
not translated: :class:`Unsupported` says what and where, and the Python
explorer runs.
"""
from __future__ import annotations

import math
import struct
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
FLIPPED = {"==": "==", "!=": "!=", "<": ">", "<=": ">=", ">": "<", ">=": "<="}
FLOAT_OPS = {"+": "+", "-": "-", "*": "*", "/": "FDIV", "%": "FMOD"}
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
    strings: dict[str, int] = field(default_factory=dict)  # string constants, numbered as the C step stores them


@dataclass
class CScope:
    where: str
    externs: Externs
    variables: dict[str, CName] = field(default_factory=dict)
    ports: dict[tuple[str, str], CName] = field(default_factory=dict)
    constants: dict[str, tuple[Any, str]] = field(default_factory=dict)
    in_guard: bool = False


def literal(value: Any, where: str, strings: dict[str, int] | None = None) -> tuple[str, str]:
    """C source and type of a constant, typed by its Python value as the Python step types it."""
    if isinstance(value, bool):
        return ("1" if value else "0"), "bool"
    if isinstance(value, int):
        if not -(1 << 63) <= value < (1 << 63):
            raise Unsupported(f"{where}: the constant {value} does not fit in 64 bits")
        return (f"INT64_C({value})" if value >= 0 else f"(INT64_C({value + 1}) - 1)"), "int"
    if isinstance(value, float):
        if math.isnan(value):
            return "NAN", "float"
        if math.isinf(value):
            return ("INFINITY" if value > 0 else "(-INFINITY)"), "float"
        return f"({value.hex()})", "float"
    if isinstance(value, str) and strings is not None:
        return str(intern(strings, value)), "string"
    raise Unsupported(f"{where}: {type(value).__name__} values ({value!r}) are explored in Python only")


def intern(strings: dict[str, int], value: str) -> int:
    """The number standing for a string in C (strings are only copied and compared for equality)."""
    if value not in strings:
        strings[value] = len(strings)
    return strings[value]


def stored(value: Any, where: str, strings: dict[str, int]) -> str:
    """A value as the 64-bit word the C state holds (a float's bits, a string's number)."""
    if isinstance(value, float):
        if math.isnan(value):
            raise Unsupported(f"{where}: NaN as an initial value (the Python explorer never finds a NaN state again)")
        return f"INT64_C({struct.unpack('<q', struct.pack('<d', value + 0.0))[0]})"
    return literal(value, where, strings)[0]


def read(n: CName) -> tuple[str, str]:
    """An lvalue read as a typed C rvalue (a float's bits become a double)."""
    return (f"F({n.src})", "float") if n.type == "float" else (n.src, n.type)


def expr(e: Expr, sc: CScope) -> tuple[str, str]:
    """C source for an expression and its type (``int``, ``bool``, ``float`` or ``string``)."""
    if isinstance(e, Const):
        return literal(e.value, sc.where, sc.externs.strings)
    if isinstance(e, Var):
        if e.name in sc.variables:
            return read(sc.variables[e.name])
        if e.name in sc.constants:
            value, _ = sc.constants[e.name]
            return literal(value, sc.where, sc.externs.strings)
        raise Unsupported(f"{sc.where}: unknown name '{e.name}'")
    if isinstance(e, PortData):
        n = sc.ports.get((e.port, e.name))
        if n is None:
            raise Unsupported(f"{sc.where}: unknown port data '{e.port}.{e.name}'")
        return read(n)
    if isinstance(e, Unary):
        s, t = expr(e.operand, sc)
        if t == "string":
            raise Unsupported(f"{sc.where}: operator '{e.op}' on a string")
        if e.op == "!":
            return f"(!{s})", "bool"
        if e.op == "-":
            return (f"(-{s})", "float") if t == "float" else (f"NEG({s})", "int")
        if e.op == "+":
            return s, t
        if e.op == "~":
            if t == "float":
                raise Unsupported(f"{sc.where}: operator '~' on a float (the Python step fails there)")
            return f"(~{s})", "int"
        raise Unsupported(f"{sc.where}: unknown unary operator '{e.op}'")
    if isinstance(e, Binary):
        return binary(e, sc)
    if isinstance(e, Call):
        return call(e, sc)
    raise Unsupported(f"{sc.where}: not an expression: {e!r}")


def binary(e: Binary, sc: CScope) -> tuple[str, str]:
    """C source of a binary operation; floats follow Python (exact int/float comparison, errors where it fails)."""
    ls, lt = expr(e.left, sc)
    rs, rt = expr(e.right, sc)
    op = e.op
    if "string" in (lt, rt):
        if lt == rt == "string" and op in ("==", "!="):
            return f"({ls} {op} {rs})", "bool"
        raise Unsupported(f"{sc.where}: operator '{op}' on {lt} and {rt} (strings are only compared with == and !=)")
    if op in ("&&", "||"):
        return f"(({ls} != 0) {op} ({rs} != 0))", "bool"
    if "float" in (lt, rt):
        if op in COMPARISONS:
            if lt == rt:
                return f"({ls} {op} {rs})", "bool"
            if lt == "float":  # x op i  <=>  i op' x
                ls, rs, op = rs, ls, FLIPPED[op]
            return f"ICMPF({ls}, {rs}, {COMPARISONS.index(op)})", "bool"
        if op not in FLOAT_OPS:
            raise Unsupported(f"{sc.where}: operator '{op}' on a float (the Python step fails there)")
        ls, rs = (f"(double)({x})" if t != "float" else x for x, t in ((ls, lt), (rs, rt)))
        if op in ("/", "%"):
            return f"{FLOAT_OPS[op]}({ls}, {rs})", "float"
        return f"({ls} {op} {rs})", "float"
    if op in COMPARISONS:
        return f"({ls} {op} {rs})", "bool"
    if op in ("&", "|", "^"):
        return f"({ls} {op} {rs})", "bool" if lt == rt == "bool" else "int"
    if op in CHECKED:
        return f"{CHECKED[op]}({ls}, {rs})", "int"
    raise Unsupported(f"{sc.where}: unknown operator '{op}'")


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
    if t == "string":
        raise Unsupported(f"{sc.where}: a string used as a condition")
    return s if t == "bool" else f"({s} != 0)"


def _a(type_name: str) -> str:
    return ("an " if type_name[0] in "aeiou" else "a ") + type_name


def converted(vs: str, vt: str, target: str, where: str) -> str:
    """The value ``vs`` of type ``vt`` as a variable of type ``target`` stores it (C state words)."""
    if target == "float":
        if vt != "float":
            raise Unsupported(f"{where}: {_a(vt)} value assigned to a float variable (the Python step keeps it "
                              f"{_a(vt)}, with {vt} arithmetic; write a float constant such as 1.0)")
        return f"B({vs})"
    if (target == "string") != (vt == "string"):
        raise Unsupported(f"{where}: {_a(vt)} value assigned to {_a(target)} variable")
    if target == "bool" and vt != "bool":
        return f"({vs} != 0)"
    if target == "int" and vt == "float":
        return f"F2I({vs})"
    return vs


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
            out.append(f"{indent}{n.src} = {converted(vs, vt, n.type, sc.where)};")
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
    """``int``, ``bool``, ``float`` or ``string``; anything else (extern types) is explored in Python only."""
    if type_name in ("int", "bool", "float", "string"):
        return type_name
    raise Unsupported(f"{where}: {type_name} data are explored in Python only")


__all__ = ["CName", "CScope", "Externs", "Stmt", "Unsupported", "c_type", "condition", "expr", "literal",
           "statements"]
