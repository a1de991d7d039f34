"""``define`` expressions as bit masks over a connector's port parameters, and the searches on them.

A define tree is ``("p", bit)`` for a port parameter or ``("g", ((node, trigger), ...))``
for a list of sub-expressions.  BIP2 rule (language reference, "Defined
interactions"): a set is an interaction of ``e1 ... eN`` iff it is a union of
at most one interaction of each ``eI`` and it contains an interaction of a
trigger ``eI``, or (no trigger being there) one of every ``eI``.  The family of
interactions is closed under union, so among the interactions inside a set of
enabled ports there is a largest one (:func:`max_allowed`).
"""
from __future__ import annotations

from itertools import product
from typing import Callable

from runtime.model.interactions import DefineGroup, DefinePort

Node = tuple


def compile_define(group: DefineGroup, index: dict[str, int], where: str) -> Node:
    """Define tree of a connector type, port names replaced by bits ``1 << index[name]``."""
    from runtime.engine.errors import FlattenError
    seen: set[str] = set()

    def walk(item) -> Node:
        if isinstance(item, DefinePort):
            if item.name not in index:
                raise FlattenError(f"{where}: define names '{item.name}', which is not a port parameter")
            if item.name in seen:
                raise FlattenError(f"{where}: define names port '{item.name}' twice")
            seen.add(item.name)
            return ("p", 1 << index[item.name])
        if not item.items:
            raise FlattenError(f"{where}: empty group in define")
        return ("g", tuple((walk(i), bool(i.trigger)) for i in item.items))

    tree = walk(group)
    missing = [n for n in index if n not in seen]
    if missing:
        raise FlattenError(f"{where}: port parameter(s) {', '.join(missing)} not named in define")
    return tree


def ports(node: Node) -> int:
    """All bits of a tree."""
    if node[0] == "p":
        return node[1]
    out = 0
    for sub, _ in node[1]:
        out |= ports(sub)
    return out


def required(node: Node) -> int:
    """The bits that take part in every interaction of the tree."""
    if node[0] == "p":
        return node[1]
    triggers = [sub for sub, t in node[1] if t]
    if not triggers:
        return _or(required(sub) for sub, _ in node[1])
    return required(triggers[0]) if len(triggers) == 1 else 0


def has_trigger(node: Node) -> bool:
    return node[0] == "g" and any(t or has_trigger(sub) for sub, t in node[1])


def is_flat(node: Node) -> bool:
    """True when the tree is one list of ports (no nested group)."""
    return node[0] == "p" or all(sub[0] == "p" for sub, _ in node[1])


def triggers(node: Node) -> int:
    """Bits of the trigger ports of a flat tree."""
    if node[0] == "p":
        return 0
    return sum(sub[1] for sub, t in node[1] if t)


def max_allowed(node: Node, enabled: int) -> int:
    """Largest interaction made of ports in ``enabled`` (0 when there is none): in a group with triggers, what each
    member offers if a trigger offers something; in a group without, what each offers if every member does."""
    if node[0] == "p":
        return node[1] & enabled
    out = 0
    missing = triggered = with_triggers = False
    for sub, trig in node[1]:
        m = max_allowed(sub, enabled)
        with_triggers = with_triggers or trig
        if m:
            out |= m
            triggered = triggered or trig
        else:
            missing = True
    if with_triggers:
        return out if triggered else 0
    return 0 if missing else out


def _group_has_trigger(node: Node) -> bool:
    return any(t for _, t in node[1])


def allowed(node: Node, mask: int) -> bool:
    """Is ``mask`` exactly an interaction of the tree?"""
    if mask == 0 or mask & ~ports(node):
        return False
    if node[0] == "p":
        return mask == node[1]
    parts = [(mask & ports(sub), sub, t) for sub, t in node[1]]
    if any(m and not allowed(sub, m) for m, sub, _ in parts):
        return False
    if _group_has_trigger(node):
        return any(m and t for m, _, t in parts)
    return all(m for m, _, _ in parts)


def subsets(node: Node, available: int) -> list[int]:
    """Every interaction made of ports in ``available``, small masks first (exponential: generic path only)."""
    if node[0] == "p":
        return [node[1]] if node[1] & available else []
    options = [subsets(sub, available) for sub, _ in node[1]]
    out: set[int] = set()
    if _group_has_trigger(node):
        choices = [opts + [0] for opts in options]
        trig = [t for _, t in node[1]]
        for combo in product(*choices):
            if any(m and t for m, t in zip(combo, trig)):
                out.add(_or(combo))
    else:
        for combo in product(*options):
            out.add(_or(combo))
    return sorted(out)


def _or(masks) -> int:
    out = 0
    for m in masks:
        out |= m
    return out


def maximal(masks) -> list[int]:
    """The masks of which no other mask in the collection is a strict superset, in increasing order."""
    ms = sorted(set(masks), key=lambda m: -bin(m).count("1"))
    keep: list[int] = []
    for m in ms:
        if not any(k & m == m for k in keep):
            keep.append(m)
    return sorted(keep)


def maximal_enabled(node: Node, enabled: int, blocked: Callable[[int], bool]) -> list[int]:
    """Maximal interactions inside ``enabled`` whose guard holds (``blocked(mask)`` says it does not).

    Starts from the largest interaction and only descends below interactions
    whose guard is false; as only interactions listed with an ``on ... provided``
    clause can have a false guard, this visits few sets even for a broadcast
    with many receivers.
    """
    top = max_allowed(node, enabled)
    if not top:
        return []
    if not blocked(top):
        return [top]
    found: set[int] = set()
    seen = {top}
    stack = [top]
    while stack:
        x = stack.pop()
        rest = x
        while rest:
            low = rest & -rest
            rest ^= low
            y = max_allowed(node, x & ~low)
            if y and y not in seen:
                seen.add(y)
                if blocked(y):
                    stack.append(y)
                else:
                    found.add(y)
    return maximal(found)
