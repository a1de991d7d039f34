"""A bound on how deeply a parsed input may nest, checked before anything recurses on it.

Parse trees of property files and ``.bip`` files are transformed, typed and
compiled by recursive functions; an input nested thousands of levels deep
(``1+1+...+1``, ``((((...))))``) would end in a RecursionError.  The readers
refuse it first, at the place where it gets too deep.
"""
from __future__ import annotations

from lark import Tree

#: How many levels of operators an input may nest; real models and properties stay far below it.
MAX_DEPTH = 200


def too_deep(tree: Tree, limit: int = MAX_DEPTH) -> Tree | None:
    """The first node (in source order) nested deeper than ``limit``, found without recursion, or None."""
    stack = [(tree, 0)]
    while stack:
        node, depth = stack.pop()
        if depth > limit:
            return node
        stack.extend((child, depth + 1) for child in reversed(node.children) if isinstance(child, Tree))
    return None

