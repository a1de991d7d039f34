"""Split a connector so that it binds each component once: a sub-connector per component it reaches twice.

BIP2 forbids a connector that binds two ports of one component instance
(Verimag's rule ``connectorDoesNotBindTheSameComponentMoreThanOnce``).  When
the ends of a connector meet in one sub-compound, a connector inside that
compound joins them and exports one port, and the outer connector binds that
port once.  The interactions (sets of atom ports) and their guards stay the
same:

- a rendezvous splits into rendezvous;
- a guarded rendezvous carries the port data its guard reads up through the
  sub-connector (``up { v1 = p3.done; }``) and the outer guard reads it there;
- ``p1' .. pn'`` splits into the same shape, one level per compound;
- ``(t1 .. tk)' r1 .. rn`` splits into a sub-connector per component — its
  trigger ends together (and its receivers joining if they can), or its
  receivers alone, each joining if it can — under an outer connector of the
  same shape.
"""
from __future__ import annotations

from dataclasses import dataclass

from runtime.errors import Genom2bipError
from runtime.model import (
    Assign,
    ConnectorExport,
    ConnectorParam,
    ConnectorType,
    DataDecl,
    DataParam,
    DefineGroup,
    DefinePort,
    InteractionSpec,
    PortData,
    PortType,
    Var,
)
from runtime.model.expressions import Binary, Call, Const, Expr, Unary, map_port_data

from genom2bip.build.library import PORT, broadcast_type, param_names, rendezvous_type, triggered_type


@dataclass
class Split:
    """The outer connector type and, per group of parameters, the sub-connector type (None: a lone end)."""

    outer: ConnectorType
    subs: list[ConnectorType | None]
    order: list[int]  # outer parameter k takes group order[k]


class SplitError(Genom2bipError, ValueError):
    """A connector whose shape this module does not know how to split."""


def _triggered_shape(ct: ConnectorType) -> int | None:
    """``k`` when the type is ``(p1 .. pk)' q1 .. qn`` with no interaction block, else None."""
    d = ct.define
    if ct.interactions or (ct.export is not None and ct.export.data) or d is None or d.trigger or not d.items:
        return None
    head, *rest = d.items
    if not (isinstance(head, DefineGroup) and head.trigger and all(isinstance(i, DefinePort) and not i.trigger
                                                                  for i in head.items)):
        return None
    if not all(isinstance(i, DefinePort) and not i.trigger for i in rest):
        return None
    return len(head.items)


def _broadcast_shape(ct: ConnectorType) -> bool:
    """``p1' .. pn'``: any non-empty set of the ports, exporting no data."""
    d = ct.define
    return (not ct.interactions and not (ct.export is not None and ct.export.data) and d is not None
            and not d.trigger and all(isinstance(i, DefinePort) and i.trigger for i in d.items))


def _rendezvous_shape(ct: ConnectorType) -> bool:
    """All ports together, at most one interaction block (with the guard only), exporting no data."""
    d = ct.define
    exported_guard = ct.export is not None and any(s.guard is not None for s in ct.interactions)
    if (ct.export is not None and ct.export.data) or exported_guard or d is None or d.trigger \
            or not all(isinstance(i, DefinePort) and not i.trigger for i in d.items):
        return False
    if len(ct.interactions) > 1:
        return False
    return all(not s.up and all(_constant_down(a) for a in s.down) and len(s.ports) == len(ct.params)
               for s in ct.interactions)


def _constant_down(stmt) -> bool:
    """``p.x = constant``: a down action that any level may run, since it reads nothing."""
    return isinstance(stmt, Assign) and isinstance(stmt.target, PortData) and isinstance(stmt.value, Const)


def split_connector(ct: ConnectorType, groups: list[list[int]], port_types: dict[str, PortType]) -> Split:
    """Split ``ct`` along ``groups`` (parameter indices, each group one component, in order of first end)."""
    k = _triggered_shape(ct)
    if k is not None:
        return _split_triggered(ct, groups, k)
    if _rendezvous_shape(ct):
        return _split_rendezvous(ct, groups, port_types)
    if _broadcast_shape(ct):
        subs = [broadcast_type(len(g), exported=True) if len(g) > 1 else None for g in groups]
        return Split(broadcast_type(len(groups), exported=ct.export is not None), subs, list(range(len(groups))))
    raise SplitError(f"connector type {ct.name} binds a component twice and has a shape that cannot be split")


def _split_triggered(ct: ConnectorType, groups: list[list[int]], k: int) -> Split:
    triggering = [g for g in groups if any(i < k for i in g)]
    receiving = [g for g in groups if all(i >= k for i in g)]
    subs: list[ConnectorType | None] = []
    for g in groups:
        if len(g) == 1:
            subs.append(None)
            continue
        t = sum(1 for i in g if i < k)
        if t == len(g):
            subs.append(rendezvous_type(tuple(PORT for _ in g), exported=True))
        elif t == 0:
            subs.append(broadcast_type(len(g), exported=True))
        else:
            subs.append(triggered_type(t, len(g) - t, exported=True))
    order = [groups.index(g) for g in triggering + receiving]
    outer = triggered_type(len(triggering), len(receiving), exported=ct.export is not None)
    return Split(outer, subs, order)


def _carried_type(n: int, port_types: dict[str, PortType]) -> str:
    """``port type BoolsN(bool v1, .., bool vN)``: what a sub-connector hands up to the outer guard."""
    name = f"Bools{n}"
    port_types.setdefault(name, PortType(name, [DataParam("bool", f"v{i + 1}") for i in range(n)]))
    return name


def _reads(e: Expr | None, acc: list[tuple[str, str]]) -> None:
    if isinstance(e, PortData):
        if (e.port, e.name) not in acc:
            acc.append((e.port, e.name))
    elif isinstance(e, Unary):
        _reads(e.operand, acc)
    elif isinstance(e, Binary):
        _reads(e.left, acc)
        _reads(e.right, acc)
    elif isinstance(e, Call):
        for a in e.args:
            _reads(a, acc)


def _split_rendezvous(ct: ConnectorType, groups: list[list[int]], port_types: dict[str, PortType]) -> Split:
    """Rendezvous of rendezvous; a guard's reads go up, a constant down action goes to the level binding its port."""
    guard = ct.interactions[0].guard if ct.interactions else None
    downs = list(ct.interactions[0].down) if ct.interactions else []
    reads: list[tuple[str, str]] = []
    _reads(guard, reads)
    names = [p.name for p in ct.params]
    outer_names = param_names(len(groups))
    table: dict[tuple[str, str], PortData] = {}
    subs: list[ConnectorType | None] = []
    outer_types: list[str] = []
    membership = [0] * len(ct.params)
    outer_downs: list[Assign] = []
    for gi, g in enumerate(groups):
        for i in g:
            membership[i] = gi
        if len(g) == 1:
            subs.append(None)
            outer_types.append(ct.params[g[0]].port_type)
            for port, field in reads:
                if port == names[g[0]]:
                    table[(port, field)] = PortData(outer_names[gi], field)
            outer_downs += [Assign(PortData(outer_names[gi], a.target.name), a.value) for a in downs
                            if a.target.port == names[g[0]]]
            continue
        local = param_names(len(g))
        types = tuple(ct.params[i].port_type for i in g)
        mine = [(port, field) for port, field in reads if names.index(port) in g]
        sub_downs = [Assign(PortData(local[g.index(names.index(a.target.port))], a.target.name), a.value)
                     for a in downs if names.index(a.target.port) in g]
        if not mine and not sub_downs:
            subs.append(rendezvous_type(types, exported=True))
            outer_types.append(PORT)
            continue
        if not mine:
            subs.append(ConnectorType(name="", params=[ConnectorParam(t, n) for t, n in zip(types, local)],
                                      export=ConnectorExport(PORT, "ep", []),
                                      define=DefineGroup([DefinePort(n) for n in local]),
                                      interactions=[InteractionSpec(list(local), down=sub_downs)]))
            outer_types.append(PORT)
            continue
        carried = _carried_type(len(mine), port_types)
        outer_types.append(carried)
        up = []
        for j, (port, field) in enumerate(mine):
            table[(port, field)] = PortData(outer_names[gi], f"v{j + 1}")
            up.append(Assign(Var(f"v{j + 1}"), PortData(local[g.index(names.index(port))], field)))
        subs.append(ConnectorType(
            name="",  # named below, after the outer type
            params=[ConnectorParam(t, n) for t, n in zip(types, local)],
            data=[DataDecl("bool", f"v{j + 1}") for j in range(len(mine))],
            export=ConnectorExport(carried, "ep", [f"v{j + 1}" for j in range(len(mine))]),
            define=DefineGroup([DefinePort(n) for n in local]),
            interactions=[InteractionSpec(list(local), up=up, down=sub_downs)],
        ))
    order = list(range(len(groups)))
    if guard is None and not downs:
        return Split(rendezvous_type(tuple(outer_types), exported=ct.export is not None), subs, order)
    code = "".join("0123456789abcdefghijklmnopqrstuvwxyz"[m] for m in membership)
    outer = ConnectorType(
        name=f"{ct.name}_{code}",
        params=[ConnectorParam(t, n) for t, n in zip(outer_types, outer_names)],
        define=DefineGroup([DefinePort(n) for n in outer_names]),
        export=ConnectorExport(PORT, "ep", []) if ct.export is not None else None,
        interactions=[
            InteractionSpec(
                list(outer_names),
                guard=map_port_data(guard, lambda d: table[(d.port, d.name)]) if guard is not None else None,
                down=outer_downs,
            )
        ],
    )
    for gi, sub in enumerate(subs):
        if sub is not None and not sub.name:
            sub.name = f"{outer.name}_{gi + 1}"
    return Split(outer, subs, order)
