"""The interactions a connector's ``define`` expression allows (trigger/synchron semantics of BIP2)."""
from __future__ import annotations

from itertools import combinations

from runtime.model import DefineGroup, DefinePort


def define_ports(group: DefineGroup) -> list[DefinePort]:
    """Every port named in a define expression, left to right, nested groups included."""
    out: list[DefinePort] = []
    for item in group.items:
        out.extend(define_ports(item) if isinstance(item, DefineGroup) else [item])
    return out


def _names(item) -> set[str]:
    return {p.name for p in define_ports(item)} if isinstance(item, DefineGroup) else {item.name}


def allows(group: DefineGroup, ports: set[str]) -> bool:
    """True when the set of port names ``ports`` is an interaction defined by ``group``.

    An interaction of ``e1 ... eN`` is a union of interactions of the ``ei``
    that contains one of a trigger ``ei``, or one of every ``ei`` when none is
    a trigger.  Each port appears once in a define, so the union splits
    uniquely; the check is linear, whatever the number of interactions.
    """
    if not ports or not ports <= _names(group):
        return False
    used = []
    for item in group.items:
        part = ports & _names(item)
        if part:
            if isinstance(item, DefinePort):
                if part != {item.name}:
                    return False
            elif not allows(item, part):
                return False
        used.append(bool(part))
    if any(u and item.trigger for u, item in zip(used, group.items)):
        return True
    return all(used)


def interactions(group: DefineGroup) -> list[frozenset[str]]:
    """Every interaction ``group`` defines, smallest first (exponential: for small connectors and tests)."""
    names = [p.name for p in define_ports(group)]
    out = []
    for size in range(1, len(names) + 1):
        for combo in combinations(names, size):
            if allows(group, set(combo)):
                out.append(frozenset(combo))
    return out
