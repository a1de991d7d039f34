"""What the front end reads at most, so that any input ends in a located error, never in exhausted memory or stack.

Real descriptions are far below every limit (DALA's largest file and its
includes: 5 kB, 13 levels of syntax tree); docs/reliability.md gives the
memory each costs.
"""
from __future__ import annotations

from lark import Tree

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


def too_deep(tree: Tree, limit: int = MAX_TREE_DEPTH) -> Tree | None:
    """The first subtree (in source order) lying deeper than ``limit`` levels, else None; walked without recursion."""
    stack = [(tree, 1)]
    while stack:
        node, depth = stack.pop()
        if depth > limit:
            return node
        stack.extend((child, depth + 1) for child in reversed(node.children) if isinstance(child, Tree))
    return None
