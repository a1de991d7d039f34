"""BIP2 literal text <-> Python values, so that the reader gets back exactly what the writer printed."""
from __future__ import annotations

import math
import re
import unicodedata

_ESCAPES = {"b": "\b", "t": "\t", "n": "\n", "f": "\f", "r": "\r", '"': '"', "'": "'", "\\": "\\"}
_NAMED = {"\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f", "\r": "\\r", '"': '\\"', "\\": "\\\\"}
_OCTAL = re.compile(r"[0-3][0-7]{2}|[0-7]{1,2}")


def decode_string(token: str) -> str:
    """The value of a BIP2 string literal, quotes included in ``token`` (C/Java escapes)."""
    body, out, i = token[1:-1], [], 0
    while i < len(body):
        ch = body[i]
        if ch != "\\":
            out.append(ch)
            i += 1
            continue
        nxt = body[i + 1]
        if nxt in _ESCAPES:
            out.append(_ESCAPES[nxt])
            i += 2
        elif nxt == "u":
            out.append(chr(int(body[i + 2:i + 6], 16)))
            i += 6
        else:
            m = _OCTAL.match(body, i + 1)
            out.append(chr(int(m.group(), 8)))
            i = m.end()
    return "".join(out)


def encode_string(value: str) -> str:
    """A BIP2 string literal for ``value``: printable text as is, control characters and line separators (U+2028,
    U+2029, which break lines where a reader splits them) escaped."""
    out = ['"']
    for ch in value:
        if ch in _NAMED:
            out.append(_NAMED[ch])
        elif unicodedata.category(ch) in ("Cc", "Cs", "Zl", "Zp") and ord(ch) <= 0xFFFF:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def format_literal(value: object) -> str:
    """BIP2 text of a bool, int, float or string; ValueError for what BIP2 cannot write (nan, inf)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"BIP2 has no literal for the float {value!r}")
        return repr(value)  # always has a '.' or an exponent, and reads back to the same float
    if isinstance(value, str):
        return encode_string(value)
    raise ValueError(f"BIP2 has no literal for {type(value).__name__} {value!r}")
