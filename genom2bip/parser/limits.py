"""What the front end reads at most, so that any input ends in a located error, never in exhausted memory or stack.

Real descriptions are far below every limit (DALA's largest file and its
includes: 5 kB, 13 levels of syntax tree, against runtime.nesting's 200);
docs/reliability.md gives the memory each costs.
"""
from __future__ import annotations

import math
from typing import Any

from lark import Token, Tree

from runtime.nesting import MAX_DEPTH, too_deep

#: Bytes of text read for one description file and everything it includes (a 100 kB description is large).
MAX_INPUT_BYTES = 2 * 1024 * 1024
#: Tokens made by macro expansion in one description (a macro using another twice, 40 levels deep, makes 2**40).
MAX_EXPANDED_TOKENS = 1_000_000
#: Characters of a preprocessed description: its text plus what macros add.
MAX_OUTPUT_CHARS = 4 * MAX_INPUT_BYTES
#: Files open at once through ``#include`` (cpp compilers allow about 200; a description needs a handful).
MAX_INCLUDE_DEPTH = 64
def megabytes(size: int) -> str:
    return f"{size / 1024 / 1024:.1f} MB"


#: The widest integers a description may write: IDL's long long and unsigned long long, C's int64_t and uint64_t.
INT_MIN, INT_MAX = -(2 ** 63), 2 ** 64 - 1
#: Digits of the largest integer literal in each base, leading zeros aside: more is out of range before int() runs.
INT_DIGITS = {16: 16, 10: 20, 8: 22}


def number_problem(value: Any, shown: str | None = None) -> str | None:
    """Why ``value`` (``shown`` as written) is not a number a description may hold: a wider integer, an infinity."""
    if isinstance(value, int) and not isinstance(value, bool) and not INT_MIN <= value <= INT_MAX:
        shown = shown if shown is None or len(shown) <= 24 else shown[:20] + "..."
        return (f"{shown or f'a value of {value.bit_length()} bits'} is out of range: an integer has 64 bits at "
                "most (from -2**63 to 2**64 - 1)")
    if isinstance(value, float) and not math.isfinite(value):
        return f"{shown or 'the value'} is out of range: a floating-point number is at most 1.8e308 in magnitude"
    return None


def literal_too_long(digits: str, base: int) -> bool:
    """An integer literal too long to be in range: thousands of digits are refused before ``int()`` reads them."""
    return len(digits.lstrip("0")) > INT_DIGITS[base]


#: Durations (periods, delays, WCETs, observer bounds) in seconds: whole microseconds, a day at most.
MIN_DURATION, MAX_DURATION = 1e-6, 86_400.0

#: What a syntax tree deeper than runtime.nesting.MAX_DEPTH is told (the readers recurse on it).
TOO_DEEP = f"nested too deeply: more than {MAX_DEPTH} levels of declarations and expressions"
TOO_DEEP_HINT = "a struct inside a struct takes two levels, an operator one"


def deep_place(tree: Tree) -> tuple[int, int] | None:
    """Line and column (1-based) where ``tree`` nests deeper than MAX_DEPTH levels, else None."""
    node = too_deep(tree)
    if node is None:
        return None
    if not getattr(node.meta, "empty", True):
        return node.meta.line, node.meta.column
    token = next(node.scan_values(lambda v: isinstance(v, Token) and v.line is not None), None)
    return (token.line, token.column) if token is not None else (1, 1)
