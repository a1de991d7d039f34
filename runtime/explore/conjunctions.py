"""Flags read only together: one is dead once another flag of every conjunction that reads it is false for good.

A service's ``done`` flag is read by the requests that come ``after`` it, and always in one conjunction with the
flags of the other services they come after (GenoM3's ``after A, B, C``: a request starts when all have succeeded,
and is refused while one has not).  Once one of those flags is false and its atom can no longer set it (its service
cannot run again: the mission will not send it any more), every such conjunction is false for ever, whatever the
others hold: the others are dead there, and states that differ only in them have the same future
(docs/verification/explorer.md, *Flags read only together*).  This module finds, for each variable that connectors
alone read, those other flags and the condition under which each can still be set.
"""
from __future__ import annotations

from dataclasses import fields, is_dataclass

from runtime.engine.flatten import FlatAtom, FlatSystem, Leaf, Sub
from runtime.explore.firing import connector_alive, places_to
from runtime.model.expressions import Assign, Binary, PortData, Var, assigned

#: A way a flag can still be set: every ``(marking slot, mask)`` of one alternative meets its mask.
Settable = tuple[tuple[tuple[int, int], ...], ...]


def dead_with(flat: FlatSystem) -> dict[int, tuple[tuple[int, int, Settable], ...]]:
    """Per slot of a variable that connectors read only inside conjunctions: ``(flag slot, flag's marking slot,
    settable)`` for each other bool flag present in every one of those conjunctions and set by its own atom only.
    The variable is dead where one of these flags is false and no alternative of its ``settable`` holds."""
    aliases, others = _aliases(flat)
    groups: dict[int, list[set[int]]] = {}
    for fc in flat.connectors:
        for spec in fc.type.interactions:
            _reads(flat, fc, aliases, spec.guard, others, groups)
            for st in spec.down:  # what goes down is read whole, and what it writes is set by a connector
                _reads(flat, fc, aliases, st, others)
                if isinstance(st, Assign) and isinstance(st.target, PortData):
                    others.update(_resolve(flat, fc, aliases, st.target))
    bools = {fa.slot(d.name): fa for fa in flat.atoms for d in fa.variables if d.type == "bool"}
    settable: dict[int, Settable] = {}
    out: dict[int, tuple[tuple[int, int, Settable], ...]] = {}
    for slot, found in groups.items():
        if slot in others:
            continue
        entries = []
        for g in sorted(set.intersection(*found) - {slot} - others):
            if g in bools:
                if g not in settable:
                    settable[g] = _settable(flat, bools[g], g)
                entries.append((g, bools[g].offset, settable[g]))
        if entries:
            out[slot] = tuple(entries)
    return out


def _aliases(flat: FlatSystem) -> tuple[dict[tuple[int, str], int], set[int]]:
    """The connectors' exported variables that copy one atom variable (``up { v = p.x; }``), and the slots read any
    other way in an ``up`` (a copy read again in a parent's ``up`` goes further than this analysis follows)."""
    copies: dict[tuple[int, str], set[int]] = {}
    others: set[int] = set()
    for fc in flat.connectors:
        for spec in fc.type.interactions:
            for st in spec.up:
                got = _resolve(flat, fc, {}, st.value) if isinstance(st, Assign) and isinstance(st.value, PortData) \
                    else None
                if got is not None and len(got) == 1 and isinstance(st.target, Var):
                    copies.setdefault((fc.id, st.target.name), set()).add(got[0])
                else:
                    _reads(flat, fc, {}, st, others)
    aliases = {key: next(iter(got)) for key, got in copies.items() if len(got) == 1}
    others.update(s for key, got in copies.items() if len(got) > 1 for s in got)
    for fc in flat.connectors:
        for spec in fc.type.interactions:
            for st in spec.up:
                _reads(flat, fc, aliases, st, others, subs_only=True)
    return aliases, others


def _resolve(flat: FlatSystem, fc, aliases: dict, data: PortData, subs_only: bool = False) -> list[int]:
    """The atom variables (slots) ``data`` may read in connector ``fc`` (``subs_only``: through copies only)."""
    index = {p.name: i for i, p in enumerate(fc.type.params)}
    if data.port not in index:
        return []
    out = []
    for alt in fc.params[index[data.port]]:
        if isinstance(alt, Leaf) and not subs_only:
            fp = flat.ports[alt.port]
            fa = flat.atoms[fp.atom]
            out += [fa.slot(var) for name, var in zip(fp.fields, fp.decl.data) if name == data.name]
        elif isinstance(alt, Sub) and (alt.connector, data.name) in aliases:
            out.append(aliases[(alt.connector, data.name)])
    return out


def _reads(flat, fc, aliases, node, others: set[int], groups: dict | None = None, subs_only: bool = False) -> None:
    """The slots ``node`` reads go to ``others``, except, with ``groups``, those read as a whole conjunct of a
    conjunction: each conjunction is a group of them."""
    if node is None:
        return
    if groups is not None and isinstance(node, Binary) and node.op == "&&":
        group: set[int] = set()
        for leaf in _conjuncts(node):
            got = _resolve(flat, fc, aliases, leaf) if isinstance(leaf, PortData) else None
            if got is not None and len(got) == 1:
                group.add(got[0])
            else:
                _reads(flat, fc, aliases, leaf, others, groups)
        for s in group:
            groups.setdefault(s, []).append(group)
    elif isinstance(node, PortData):
        others.update(_resolve(flat, fc, aliases, node, subs_only))
    elif isinstance(node, (list, tuple)):
        for x in node:
            _reads(flat, fc, aliases, x, others, groups, subs_only)
    elif is_dataclass(node) and not isinstance(node, type):
        for f in fields(node):
            _reads(flat, fc, aliases, getattr(node, f.name), others, groups, subs_only)


def _conjuncts(node) -> list:
    if isinstance(node, Binary) and node.op == "&&":
        return _conjuncts(node.left) + _conjuncts(node.right)
    return [node]


def _settable(flat: FlatSystem, fa: FlatAtom, slot: int) -> Settable:
    """When ``fa`` may still set variable ``slot``: from the places where a transition that writes it is reached
    through ports that never stop being offered, or, while one of the ports that may stop (their connectors need
    an atom that can leave the places from which it offers them) still can, from any place that reaches it."""
    var = next(d.name for d in fa.variables if fa.slot(d.name) == slot)
    dying: dict[str, tuple[tuple[int, int], ...]] = {}
    for fp in flat.ports:
        if fp.atom != fa.index or not fp.connectors:
            continue
        conditions = [connector_alive(flat, flat.connectors[c], fa.index) for c in fp.connectors]
        if None not in conditions:
            dying[fp.name] = tuple(sorted({pair for c in conditions for pair in c}))
    writers = [t for t in fa.type.transitions if var in assigned(t.action)]
    steady = [t for t in fa.type.transitions if t.port not in dying]
    still = places_to(fa, [t for t in writers if t.port not in dying], steady)
    every = places_to(fa, writers)
    out = [((fa.offset, still),)] if still else []
    if every:
        # a transition that neither moves the atom nor writes the flag (a port offering data where it is) leads
        # nowhere: its port stopping changes nothing
        ports = {t.port for t in fa.type.transitions if t.port in dying
                 and (set(t.sources) != set(t.targets) or t in writers)}
        out += [((s, mask), (fa.offset, every)) for s, mask in sorted({p for q in ports for p in dying[q]})]
    return tuple(out)
