"""Literal decoding and constant-expression arithmetic for the dotgen front end.

IDL constant expressions follow C: integer division truncates toward zero,
``%`` takes the sign of the dividend, shifts and bitwise operators need
integers.  Problems raise :class:`ConstError`, which the caller turns into a
diagnostic at the offending sub-expression.  Every value is an IDL one: an
integer of 64 bits at most, a finite floating-point number (:func:`checked`).
"""
from __future__ import annotations

import re
from typing import Any

from genom2bip.ir import INTEGER_RANGES
from genom2bip.parser.limits import INT_MAX, literal_too_long, number_problem
from runtime.diagnostics import Span


class ConstError(Exception):
    """A constant expression that cannot be evaluated, with the position to blame."""

    def __init__(self, span: Span, message: str) -> None:
        super().__init__(message)
        self.span = span
        self.message = message


_ESCAPES = {"n": "\n", "t": "\t", "r": "\r", "a": "\a", "b": "\b", "f": "\f", "v": "\v",
            "\\": "\\", '"': '"', "'": "'", "?": "?"}
_ESCAPE_RE = re.compile(r"\\(x[0-9a-fA-F]{1,2}|[0-7]{1,3}|.)", re.S)


def unescape(body: str) -> str:
    """Decode C escape sequences in the body of a string or character literal."""

    def one(m: re.Match) -> str:
        e = m.group(1)
        if e[0] == "x":
            return chr(int(e[1:], 16))
        if e[0] in "01234567":
            return chr(int(e, 8))
        return _ESCAPES.get(e, e)

    return _ESCAPE_RE.sub(one, body)


def int_literal(text: str, span: Span) -> int:
    """Decimal, ``0x`` hexadecimal or leading-zero octal, as C writes them; 64 bits at most."""
    if text[:2] in ("0x", "0X"):
        digits, base = text[2:], 16
    elif len(text) > 1 and text[0] == "0":
        if not all(c in "01234567" for c in text):
            raise ConstError(span, f"invalid octal constant '{text}'")
        digits, base = text, 8
    else:
        digits, base = text, 10
    if literal_too_long(digits, base):
        raise ConstError(span, number_problem(INT_MAX + 1, text) or "")
    return checked(int(digits, base), span, text)


def float_literal(text: str, span: Span) -> float:
    return checked(float(text.rstrip("fFdD")), span, text)


def checked(value: Any, span: Span, shown: str | None = None) -> Any:
    """``value`` when it is an IDL number (or not a number at all); ConstError for a wider integer or an infinity."""
    problem = number_problem(value, shown)
    if problem:
        raise ConstError(span, problem)
    return value


def _kind(v: Any) -> str:
    if isinstance(v, str):
        return "string"
    if isinstance(v, bool):
        return "boolean"
    if isinstance(v, int):
        return "integer"
    return "floating-point"


def binary(op: str, a: Any, b: Any, span: Span) -> Any:
    """Apply a binary operator of the IDL constant-expression grammar."""
    if isinstance(a, str) or isinstance(b, str):
        raise ConstError(span, f"operator '{op}' cannot be applied to a string")
    integral = isinstance(a, int) and isinstance(b, int)
    if op in ("%", "<<", ">>", "&", "|", "^") and not integral:
        bad = a if not isinstance(a, int) else b
        raise ConstError(span, f"operator '{op}' needs integer operands, not {_kind(bad)} {bad!r}")
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if op in ("/", "%"):
        if b == 0:
            raise ConstError(span, "division by zero in constant expression")
        if op == "/":
            if integral:
                q = abs(a) // abs(b)
                return q if (a >= 0) == (b >= 0) else -q
            return a / b
        r = abs(a) % abs(b)
        return r if a >= 0 else -r
    if op in ("<<", ">>"):
        if b < 0:
            raise ConstError(span, f"negative shift count {b} in constant expression")
        if op == "<<" and a and b >= 64:  # computed, a shift by a billion would take gigabytes
            raise ConstError(span, f"shift count {b} is out of range: an integer has 64 bits at most")
        return a << b if op == "<<" else a >> b
    if op == "&":
        return a & b
    if op == "|":
        return a | b
    if op == "^":
        return a ^ b
    raise ConstError(span, f"unknown operator '{op}'")


def unary(op: str, a: Any, span: Span) -> Any:
    if isinstance(a, str):
        raise ConstError(span, f"operator '{op}' cannot be applied to a string")
    if op == "-":
        return -a
    if op == "+":
        return +a
    if not isinstance(a, int) or isinstance(a, bool):
        raise ConstError(span, f"operator '~' needs an integer operand, not {_kind(a)} {a!r}")
    return ~a


_INTEGER_TYPES = {"short", "long", "long long", "unsigned short", "unsigned long", "unsigned long long", "octet"}
_FLOAT_TYPES = {"float", "double"}
FLOAT_MAX = 3.4028234663852886e38


def coerce(type_name: str | None, value: Any, span: Span, what: str) -> Any:
    """Check a constant's value against its declared base type; floats accept integers."""
    if type_name is None or value is None:
        return value
    if type_name in _INTEGER_TYPES:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConstError(span, f"{what} has type {type_name} but its value {value!r} is not an integer")
        lo, hi = INTEGER_RANGES[type_name]
        if not lo <= value <= hi:
            raise ConstError(span, f"{what} has type {type_name}: {value} is out of its range, {lo} to {hi}")
        return value
    if type_name in _FLOAT_TYPES:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConstError(span, f"{what} has type {type_name} but its value {value!r} is not a number")
        if type_name == "float" and abs(value) > FLOAT_MAX:
            raise ConstError(span, f"{what} has type float: {value!r} is out of its range (3.4e38 in magnitude)")
        return float(value)
    if type_name == "boolean":
        if not isinstance(value, bool):
            raise ConstError(span, f"{what} has type boolean but its value {value!r} is not TRUE or FALSE")
        return value
    if type_name in ("char", "wchar"):
        if not (isinstance(value, str) and len(value) == 1):
            raise ConstError(span, f"{what} has type {type_name} but its value {value!r} is not a character")
        return value
    if type_name == "string":
        if not isinstance(value, str):
            raise ConstError(span, f"{what} has type string but its value {value!r} is not a string")
        return value
    return value
