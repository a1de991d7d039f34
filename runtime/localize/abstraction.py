"""The localization abstraction of a model: a set K of atoms kept exact, every other atom a free environment.

The abstraction is an ordinary BIP package, so the explorers, observers and
traces run on it unchanged.  Every step only adds behaviour (docs/verification/localization.md):

* a dropped atom that offers ports to a connector touching K becomes a *chaos
  atom* with the same ports and data: a port is always ready when no
  interaction it takes part in can hide a smaller one (a rendezvous), else it
  has an on/off toggle of its own (so both the interaction with it and the
  ones without it exist); each boolean it carries that a kept connector reads
  is flipped by a havoc port of its own.  Toggles and havocs are lone atom
  ports, interactions of their own that change nothing in K;
* a dropped atom that carries data other than booleans into K is kept instead
  (:func:`close`);
* connectors among dropped atoms disappear, with their interactions (they
  change no kept atom, and the property must not see them);
* a compound priority stays only when its guard reads kept atoms alone and its
  high side touches dropped atoms only by ports they offer in every state
  without a guard (a poster's ``write``, an observer's ports), which their
  chaos atoms offer no more often (removing a priority only adds behaviour).
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field

from runtime.engine.flatten import FlatConnector, FlatSystem, Leaf, parse_root
from runtime.explore.layout import _port_data  # every p.x read under an expression or statement
from runtime.model import (
    AtomType,
    CompoundType,
    InitialTransition,
    Package,
    PortData,
    PortDecl,
    PortType,
    Transition,
)
from runtime.model.expressions import Assign, Binary, Call, Const, Unary, Var

#: The port type of toggles and havocs (no data).
CHAOS_PORT_TYPE = "ChaosPort"
#: Prefix of the lone ports of chaos atoms: their interactions are the environment's, not the model's.
CHAOS = "chaos_"


@dataclass
class Abstraction:
    """The abstract package and what it dropped, in the concrete model's names."""

    package: Package
    root: str
    kept: frozenset[int]  # flat atom indexes of the concrete model
    chaos: list[str] = field(default_factory=list)  # dropped atoms that became chaos atoms
    removed_connectors: list[str] = field(default_factory=list)
    removed_priorities: list[str] = field(default_factory=list)
    free_labels: frozenset[str] = frozenset()  # concrete labels only removed interactions carry
    toggles: int = 0
    havocs: int = 0


# --------------------------------------------------------------------------- what connectors touch and read


def tree(flat: FlatSystem, fc: FlatConnector) -> list[FlatConnector]:
    """A connector and its sub-connectors, top first."""
    out, todo = [], [fc]
    while todo:
        c = todo.pop()
        out.append(c)
        todo.extend(flat.connectors[a.connector] for alts in c.params for a in alts if not isinstance(a, Leaf))
    return out


def connector_atoms(flat: FlatSystem, fc: FlatConnector) -> frozenset[int]:
    return frozenset(flat.ports[p].atom for p in flat.leaves(fc))


def data_read(flat: FlatSystem, fc: FlatConnector) -> dict[int, set[str]]:
    """Atom port id -> the fields of its data that the connector's tree reads (guards, up, down's values)."""
    out: dict[int, set[str]] = {}
    for c in tree(flat, fc):
        reads: set[tuple[str, str]] = set()
        for spec in c.type.interactions:
            _port_data(spec.guard, reads)
            _port_data(spec.up, reads)
            _port_data([s.value for s in spec.down if isinstance(s, Assign)], reads)
        for param, alts in zip(c.type.params, c.params):
            names = {x for p, x in reads if p == param.name}
            for a in alts:
                if isinstance(a, Leaf) and names:
                    out.setdefault(a.port, set()).update(names)
    return out


def optional_leaves(flat: FlatSystem, fc: FlatConnector) -> set[int]:
    """Atom ports that some interaction of the connector's tree has and a smaller one lacks.

    In a define, an item is mandatory when no item is a trigger (a rendezvous)
    or when it is the only trigger; a leaf is optional when some item above
    it is not mandatory.  Only these ports can hide an interaction by maximal
    progress, so only they need a toggle in a chaos atom.
    """
    out: set[int] = set()

    def items(group, optional: bool, c: FlatConnector) -> None:
        triggers = [i for i in group.items if i.trigger]
        for item in group.items:
            mandatory = not triggers or (len(triggers) == 1 and item.trigger)
            if hasattr(item, "items"):
                items(item, optional or not mandatory, c)
                continue
            k = next(n for n, p in enumerate(c.type.params) if p.name == item.name)
            for a in c.params[k]:
                if isinstance(a, Leaf):
                    if optional or not mandatory:
                        out.add(a.port)
                else:
                    sub = flat.connectors[a.connector]
                    items(sub.type.define, optional or not mandatory, sub)

    items(fc.type.define, False, fc)
    return out


def kept_connectors(flat: FlatSystem, kept: set[int]) -> list[bool]:
    """Per flat connector: it stays (a top one touching K, or a sub-connector of one that stays)."""
    keep = [False] * len(flat.connectors)
    for fc in flat.connectors:
        if fc.top and connector_atoms(flat, fc) & kept:
            for c in tree(flat, fc):
                keep[c.id] = True
    return keep


def close(flat: FlatSystem, kept: set[int]) -> set[int]:
    """K grown until no dropped atom carries data other than booleans into a kept connector."""
    kept = set(kept)
    while True:
        grow = set()
        for fc in flat.connectors:
            if not fc.top or not connector_atoms(flat, fc) & kept:
                continue
            for port, names in data_read(flat, fc).items():
                fp = flat.ports[port]
                if fp.atom in kept:
                    continue
                if any(t != "bool" for n, t in zip(fp.fields, fp.field_types) if n in names):
                    grow.add(fp.atom)
        if not grow:
            return kept
        kept |= grow


# --------------------------------------------------------------------------- the package


def abstract(package: Package, root: str, flat: FlatSystem, kept: set[int]) -> Abstraction:
    """The package with the atoms outside ``kept`` replaced by chaos atoms (``kept`` closed by :func:`close`)."""
    pkg = copy.deepcopy(package)
    name, _ = parse_root(root)
    owned: dict[str, CompoundType] = {"": pkg.compound_type(name)}

    def own(path: str) -> CompoundType:
        """The compound type of instance ``path``, copied so that a change made to it touches this instance only."""
        if path not in owned:
            parent_path, _, inst_name = path.rpartition(".")
            inst = own(parent_path).component(inst_name)
            clone = copy.deepcopy(pkg.compound_type(inst.type))
            clone.name = _fresh(pkg, f"{inst.type}_at_{path.replace('.', '_')}")
            pkg.compound_types.append(clone)
            inst.type = clone.name
            owned[path] = clone
        return owned[path]

    keep = kept_connectors(flat, kept)
    result = Abstraction(pkg, root, frozenset(kept))
    # ports of dropped atoms in kept connectors: whether they need a toggle, which fields are read
    toggled: set[int] = set()
    offered: set[int] = set()
    read: dict[int, set[str]] = {}
    for fc in flat.connectors:
        if not fc.top or not keep[fc.id]:
            continue
        optional = optional_leaves(flat, fc)
        for p in flat.leaves(fc):
            if flat.ports[p].atom not in kept:
                offered.add(p)
                if p in optional:
                    toggled.add(p)
        for p, names in data_read(flat, fc).items():
            read.setdefault(p, set()).update(names)
    if pkg.port_type(CHAOS_PORT_TYPE) is None:
        pkg.port_types.append(PortType(CHAOS_PORT_TYPE))
    for fa in flat.atoms:
        if fa.index in kept:
            continue
        parent_path, _, inst_name = fa.name.rpartition(".")
        chaos = _chaos_type(pkg, fa, {fp: p in toggled for fp, p in fa.ports.items() if p in offered},
                            {v for fp, p in fa.ports.items() if p in offered
                             for n, v in zip(flat.ports[p].fields, flat.ports[p].decl.data) if n in read.get(p, ())},
                            result)
        pkg.atom_types.append(chaos)
        own(parent_path).component(inst_name).type = chaos.name
        if any(p in offered for p in fa.ports.values()):
            result.chaos.append(fa.name)
    for fc in flat.connectors:
        if fc.top and not keep[fc.id]:  # a sub-connector stays: a compound may export its port; alone it never fires
            t = own(fc.scope)
            t.connectors = [c for c in t.connectors if c.name != fc.instance.name]
            result.removed_connectors.append(fc.path)
    for pr in flat.priorities:
        if _keeps(flat, pr, keep, kept):
            continue
        scope, _, rule = pr.name.rpartition(".")
        t = own(scope)
        t.priorities = [p for p in t.priorities if p.name != rule]
        result.removed_priorities.append(pr.name)
    kept_labels = {fc.label for fc in flat.connectors if fc.top and keep[fc.id]}
    kept_labels |= {fp.path for fp in flat.ports if not fp.decl.exported and fp.atom in kept}
    dropped = {fc.label for fc in flat.connectors if fc.top and not keep[fc.id]}
    dropped |= {fp.path for fp in flat.ports if not fp.decl.exported and fp.atom not in kept}
    result.free_labels = frozenset(dropped - kept_labels)
    return result


def always_ready(flat: FlatSystem, port: int) -> bool:
    """Whether atom port ``port`` is offered in every state: from every place a transition on it without a guard,
    and no atom priority over it (a poster's ``write``, an observer's ports)."""
    fp = flat.ports[port]
    t = flat.atoms[fp.atom].type
    if any(pr.low in (fp.name, "*") for pr in t.priorities):
        return False
    free = {tr.sources[0] for tr in t.transitions
            if tr.port == fp.name and tr.guard is None and len(tr.sources) == 1 and tr.resume is None}
    return free >= set(t.places)


def _keeps(flat: FlatSystem, pr, keep: list[bool], kept: set[int]) -> bool:
    """A priority stays when both sides' connectors stay, its guard reads kept atoms only, and its high side's
    connectors touch dropped atoms only by ports always ready whose data they do not read: a chaos atom offers such
    a port at most when the atom would, so the high side is enabled at most when it would be, and blocks no more."""
    for cid, _ in pr.low.entries + pr.high.entries:
        if flat.connectors[cid].top and not keep[cid]:
            return False
    for cid, _ in pr.high.entries:
        fc = flat.connectors[cid]
        read = data_read(flat, fc)
        if any(flat.ports[p].atom not in kept and (p in read or not always_ready(flat, p)) for p in flat.leaves(fc)):
            return False
    if pr.guard is not None:
        reads: set[tuple[str, str]] = set()
        _port_data(pr.guard, reads)
        for ref in reads:
            slot = pr.data.get(ref, (None,))[0]
            if slot is None or _atom_of_slot(flat, slot) not in kept:
                return False
    return True


def _atom_of_slot(flat: FlatSystem, slot: int) -> int:
    return next(a.index for a in flat.atoms if a.offset <= slot < a.offset + a.size)


def _unused(base: str, used) -> str:
    """``base``, else ``base_2``, ``base_3``, ...: the first name ``used(name)`` says is free."""
    name, n = base, 1
    while used(name):
        n += 1
        name = f"{base}_{n}"
    return name


def _fresh(pkg: Package, base: str) -> str:
    """A type name no component type of the package has."""
    return _unused(base, lambda name: pkg.component_type(name) is not None)


def _chaos_type(pkg: Package, fa, ports: dict[str, bool], havoc: set[str], result: Abstraction) -> AtomType:
    """A chaos atom for dropped atom ``fa``: ``ports`` (name -> needs a toggle) always ready or toggled, ``havoc``
    the booleans it flips at will; the other ports never fire."""
    t: AtomType = fa.type
    places = ["chaos_idle"]
    start = ["chaos_idle"]
    transitions: list[Transition] = []
    decls = [copy.deepcopy(p) for p in t.ports]
    taken = {p.name for p in t.ports} | set(t.places) | {d.name for d in t.data}

    def fresh(base: str) -> str:
        name = _unused(base, taken.__contains__)
        taken.add(name)
        return name

    for port, toggle in ports.items():
        if not toggle:
            transitions.append(Transition(port, ["chaos_idle"], ["chaos_idle"]))
            continue
        on, off, switch = fresh(f"{CHAOS}{port}_on"), fresh(f"{CHAOS}{port}_off"), fresh(f"{CHAOS}toggle_{port}")
        places += [off, on]
        start.append(off)
        decls.append(PortDecl(CHAOS_PORT_TYPE, switch))
        transitions += [Transition(port, [on], [on]), Transition(switch, [off], [on]), Transition(switch, [on], [off])]
        result.toggles += 1
    for var in sorted(havoc):
        flip = fresh(f"{CHAOS}havoc_{var}")
        decls.append(PortDecl(CHAOS_PORT_TYPE, flip))
        transitions.append(Transition(flip, ["chaos_idle"], ["chaos_idle"],
                                      action=[Assign(Var(var), Unary("!", Var(var)))]))
        result.havocs += 1
    initial = [s for s in (t.initial.action if t.initial else []) if _plain(s)]
    return AtomType(_fresh(pkg, f"Chaos_{fa.name.replace('.', '_')}"), copy.deepcopy(t.params),
                    copy.deepcopy(t.data), decls, places, InitialTransition(start, initial), transitions)


def _plain(stmt) -> bool:
    """An assignment of a constant expression (no extern call): kept in a chaos atom's initial transition."""
    def calls(e) -> bool:
        if isinstance(e, Call):
            return True
        if isinstance(e, (Unary,)):
            return calls(e.operand)
        if isinstance(e, Binary):
            return calls(e.left) or calls(e.right)
        return not isinstance(e, (Const, Var, PortData))
    return isinstance(stmt, Assign) and isinstance(stmt.target, Var) and not calls(stmt.value)
