"""Action formulas as predicates on interaction labels (``NDD.GoTo:trigger``).

A double-quoted string matches a label equal to it, or equal to it after one
leading module name (``"GoTo:trigger"`` matches ``NDD.GoTo:trigger``, as the
paper writes labels); inside double quotes ``*`` stands for any characters and
``?`` for one.  A single-quoted string is a Python regular expression that
must match the whole label.  Results are cached per label.
"""
from __future__ import annotations

import re
from functools import lru_cache
from typing import Callable

from runtime.props.formulas import AAnd, AConst, Action, ALabel, ANot, AOr, ARegex


def strip_module(label: str) -> str | None:
    """The label without its leading module name (``NDD.GoTo:trigger`` -> ``GoTo:trigger``), or None."""
    head, dot, rest = label.partition(".")
    if not dot or not rest or ":" in head:
        return None
    return rest


@lru_cache(maxsize=None)
def _glob(pattern: str) -> re.Pattern:
    out = []
    for ch in pattern:
        out.append(".*" if ch == "*" else "." if ch == "?" else re.escape(ch))
    return re.compile("".join(out), re.DOTALL)


def label_matcher(text: str) -> Callable[[str], bool]:
    if "*" in text or "?" in text:
        pat = _glob(text)

        def glob(label: str) -> bool:
            if pat.fullmatch(label):
                return True
            rest = strip_module(label)
            return rest is not None and pat.fullmatch(rest) is not None
        return glob

    def exact(label: str) -> bool:
        return label == text or strip_module(label) == text
    return exact


def matcher(a: Action) -> Callable[[str], bool]:
    """A function ``label -> bool`` for an action formula."""
    if isinstance(a, ALabel):
        return label_matcher(a.text)
    if isinstance(a, ARegex):
        pat = re.compile(a.pattern)
        return lambda label: pat.fullmatch(label) is not None
    if isinstance(a, AConst):
        return (lambda label: True) if a.value else (lambda label: False)
    if isinstance(a, ANot):
        m = matcher(a.operand)
        return lambda label: not m(label)
    if isinstance(a, AAnd):
        left, right = matcher(a.left), matcher(a.right)
        return lambda label: left(label) and right(label)
    if isinstance(a, AOr):
        left, right = matcher(a.left), matcher(a.right)
        return lambda label: left(label) or right(label)
    raise TypeError(f"not an action formula: {a!r}")


def leaves(a: Action) -> list[ALabel | ARegex]:
    """The quoted strings of an action formula (for 'matches no label' warnings)."""
    if isinstance(a, (ALabel, ARegex)):
        return [a]
    if isinstance(a, ANot):
        return leaves(a.operand)
    if isinstance(a, (AAnd, AOr)):
        return leaves(a.left) + leaves(a.right)
    return []


class LabelTable:
    """Caches ``action formula k`` x ``label id`` -> bool for one checking run."""

    def __init__(self, actions: list[Action], labels: list[str]) -> None:
        self.matchers = [matcher(a) for a in actions]
        self.labels = labels
        self.cache: list[dict[int, bool]] = [{} for _ in actions]

    def __call__(self, action: int, label: int) -> bool:
        c = self.cache[action]
        got = c.get(label)
        if got is None:
            got = c[label] = self.matchers[action](self.labels[label])
        return got
