"""What the front end reads at most, so that any input ends in a located error, never in exhausted memory or stack.

Real descriptions are far below every limit (DALA's largest file and its
includes: 5 kB, 13 levels of syntax tree); docs/reliability.md gives the
memory each costs.
"""
from __future__ import annotations

import math
from typing import Any

from lark import Token, Tree

#: Bytes of text read for one description file and everything it includes (a 100 kB description is large).
MAX_INPUT_BYTES = 2 * 1024 * 1024
#: Tokens made by macro expansion in one description (a macro using another twice, 40 levels deep, makes 2**40).
MAX_EXPANDED_TOKENS = 1_000_000
#: Characters of a preprocessed description: its text plus what macros add.
MAX_OUTPUT_CHARS = 4 * MAX_INPUT_BYTES
#: Files open at once through ``#include`` (cpp compilers allow about 200; a description needs a handful).
MAX_INCLUDE_DEPTH = 64
#: Levels of a file's syntax tree: a struct in a struct takes two, an operator one.  The readers walk the
#: tree recursively; 200 levels keep them far from Python's recursion limit.
MAX_TREE_DEPTH = 200


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

#: What a too deep syntax tree is told (:func:`too_deep`).
TOO_DEEP = f"nested too deeply: more than {MAX_TREE_DEPTH} levels of declarations and expressions"
TOO_DEEP_HINT = "a struct inside a struct takes two levels, an operator one"


def too_deep(tree: Tree, limit: int = MAX_TREE_DEPTH) -> Token | None:
    """The first token of the first subtree (in source order) lying deeper than ``limit`` levels, else None.

    Walked without recursion, so that any depth is measured; the readers, which recurse, then see only
    trees within the limit.
    """
    stack: list[tuple[Tree | Token, int]] = [(tree, 1)]
    deep = None
    while stack:
        node, depth = stack.pop()
        if isinstance(node, Token):
            if deep is not None:
                return node
            continue
        if depth > limit and deep is None:
            deep, stack = node, []  # from here on, the first token below it
        stack.extend((child, depth + 1) for child in reversed(node.children))
    return None if deep is None else Token("DEEP", "", line=1, column=1)  # tokens lack positions: the start
