"""Every interaction a flat system can ever offer, listed statically (what a translation to another tool needs).

The engine finds enabled interactions state by state; a Promela model needs
them all up front, each with the connector nodes taking part, which
parameter alternative each node uses, the priority rules it can match, and
its label.  Enumeration follows the define trees (``defines.subsets``) through
sub-connectors and merged exports.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from itertools import product

from runtime.engine import defines, support
from runtime.engine.plan import Source, TreeNode, parts


@dataclass
class Static:
    """One interaction: its source and leaf mask (as the engine numbers them), label and parts."""

    source: Source
    mask: int
    label: str
    index: int
    parts: tuple[tuple[int, int], ...]
    low: int = 0  # bit r: matches the low side of compound priority r
    high: int = 0
    supersets: list[int] = field(default_factory=list)  # positions (in the list) of strict supersets, same source


def node_masks(node: TreeNode) -> list[int]:
    """Leaf masks of every interaction a connector node allows (sub-connectors included)."""
    out: set[int] = set()
    n = len(node.params)
    for pm in defines.subsets(node.info.tree, (1 << n) - 1):
        rows = []
        for i in range(n):
            if pm >> i & 1:
                row = []
                for alt in node.params[i]:
                    row.extend([alt.mask] if alt.node is None else node_masks(alt.node))
                rows.append(row)
        for combo in product(*rows):
            m = 0
            for x in combo:
                m |= x
            out.add(m)
    return sorted(out)


def all_interactions(engine) -> list[Static]:
    """The interactions of every source of the engine's plan, in source order then mask order."""
    out: list[Static] = []
    nsrc = len(engine.sources)
    make = engine.step.interaction
    sides = support.RuleSides([(pr.low.entries, pr.high.entries) for pr in engine.flat.priorities])
    for src in engine.sources:
        masks = [1] if src.kind == "port" else node_masks(src.tree)
        first = len(out)
        for mask in masks:
            inter = make(src.index, mask)
            ps = tuple(parts(src.tree, mask)) if src.tree is not None else ()
            st = Static(src, mask, inter.label, mask * nsrc + src.index, ps)
            low, high = sides.of(ps)
            st.low, st.high = sum(1 << r for r in low), sum(1 << r for r in high)
            out.append(st)
        group = out[first:]
        for st in group:
            st.supersets = [first + k for k, other in enumerate(group)
                            if other.mask != st.mask and other.mask & st.mask == st.mask]
    return out


def rule_edges(engine) -> list[list[int]]:
    """``edges[i]``: rules whose low side can match an interaction that the high side of rule i matches.

    The same graph the engine's priority filter walks (support.rule_edges).
    """
    pairs = [(p.low.entries, p.high.entries) for p in engine.flat.priorities]
    return support.rule_edges(pairs, support.top_connectors(engine.sources))
