"""The interactions of a flat system, statically, with what it takes for each to be surely enabled.

Every top-level connector's interactions are enumerated from its define tree
(the same enumeration the Promela export uses), plus every lone atom port.
For each: the atom ports taking part, and the guards along its connector
tree.  ``enabling`` turns the guards into the combinations of port values
under which they surely hold; a guard that reads what the analysis does not
track (a sub-connector's exported data, connector variables, an untracked
atom variable) never surely holds, so DIS stays an over-approximation.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from itertools import product

from runtime.compositional.local import AtomAbstraction
from runtime.compositional.values import TOP, Evaluator, truths
from runtime.engine.flatten import FlatSystem
from runtime.engine.interaction import interaction_label
from runtime.engine.plan import Source, TreeNode, plan
from runtime.export.interactions import node_masks

#: More value combinations than this for one guarded interaction: it is never counted as surely enabled.
MAX_COMBINATIONS = 4096


@dataclass
class StaticInteraction:
    """One interaction: its label and the (atom index, port name, global port id) taking part."""

    label: str
    ports: list[tuple[int, str, int]]
    fields: list[list[str]] = field(default_factory=list)  # per port: the port type's field names
    checks: list[tuple] = field(default_factory=list)  # (guard, param index -> port position, param names)

    @property
    def atoms(self) -> list[int]:
        return [a for a, _, _ in self.ports]


@dataclass
class Enabling:
    """When an interaction is surely enabled: every port in ``plain`` surely enabled, and, for the
    ports read by guards (``read``), one of ``combos`` (tuples of local-state sets, one per read port)."""

    plain: list[tuple[int, str]]
    read: list[tuple[int, str]]
    combos: list[tuple[frozenset[int], ...]] | None  # None: no guard; []: never surely enabled


def static_interactions(flat: FlatSystem) -> list[StaticInteraction]:
    """All interactions, connectors first (in the engine's source order), then lone ports."""
    _, sources = plan(flat)
    out: list[StaticInteraction] = []
    for src in sources:
        if src.kind == "port":
            p = src.port
            out.append(StaticInteraction(p.path, [(p.atom, p.name, p.id)], [list(p.fields)]))
            continue
        for mask in node_masks(src.tree):
            out.append(_interaction(flat, src, mask))
    return out


def _interaction(flat: FlatSystem, src: Source, mask: int) -> StaticInteraction:
    fc = src.connector
    leaves = [(k, flat.ports[p]) for k, p in enumerate(src.leaves) if mask >> k & 1]
    cut = len(fc.scope) + 1 if fc.scope else 0
    label = interaction_label(fc.label, [p.path[cut:] for _, p in leaves], mask == src.full and not src.alternatives,
                              fc.named and not src.alternatives)
    inter = StaticInteraction(label, [(p.atom, p.name, p.id) for _, p in leaves], [list(p.fields) for _, p in leaves])
    position = {k: n for n, (k, _) in enumerate(leaves)}
    _collect(src.tree, mask, inter, position)
    return inter


def _collect(node: TreeNode, mask: int, inter: StaticInteraction, position: dict[int, int]) -> None:
    pm = 0
    params: dict[int, int] = {}
    for i, alts in enumerate(node.params):
        for a in alts:
            if a.mask & mask:
                pm |= 1 << i
                if a.node is not None:
                    _collect(a.node, mask, inter, position)
                else:
                    params[i] = position[a.mask.bit_length() - 1]
    clause = node.info.clauses.get(pm)
    if clause is not None and clause.guard is not None:
        inter.checks.append((clause.guard, params, node.info.index))


def enabling(inter: StaticInteraction, atoms: list[AtomAbstraction], constants: dict) -> Enabling:
    """The conditions under which ``inter`` is surely enabled (see :class:`Enabling`)."""
    plain_ports = [(a, p) for a, p, _ in inter.ports]
    if len({a for a, _ in plain_ports}) != len(plain_ports):
        return Enabling(plain_ports, [], [])  # two ports of one atom: leave it to the engine, never sure
    if not inter.checks:
        return Enabling(plain_ports, [], None)
    read_leaves: set[int] = set()
    for guard, params, index in inter.checks:
        read_leaves |= set(params.values())
    read = sorted(read_leaves)
    groups = []
    for n in read:
        a, p, _ = inter.ports[n]
        by_value: dict[tuple, set[int]] = {}
        for k in atoms[a].certain.get(p, ()):
            by_value.setdefault(atoms[a].port_values(p, k), set()).add(k)
        groups.append(list(by_value.items()))
    size = 1
    for g in groups:
        size *= max(1, len(g))
    plain = [plain_ports[n] for n in range(len(plain_ports)) if n not in read_leaves]
    read_ports = [plain_ports[n] for n in read]
    if size > MAX_COMBINATIONS:
        return Enabling(plain, read_ports, [])
    combos = []
    for combo in product(*groups):
        values = {n: v for n, (v, _) in zip(read, combo)}
        if all(_surely(guard, params, index, values, inter, atoms, constants) for guard, params, index in inter.checks):
            combos.append(tuple(frozenset(states) for _, states in combo))
    return Enabling(plain, read_ports, combos)


def _surely(guard, params: dict[int, int], index: dict[str, int], values: dict[int, tuple],
            inter: StaticInteraction, atoms: list[AtomAbstraction], constants: dict) -> bool:
    def port(name: str, field_: str):
        i = index.get(name)
        if i is None or i not in params:
            return TOP
        n = params[i]
        a, p, _ = inter.ports[n]
        names = inter.fields[n]
        if field_ not in names:
            return TOP
        v = values[n][names.index(field_)]
        return TOP if v is TOP else frozenset((v,))

    def lookup(name: str):
        return frozenset((constants[name][0],)) if name in constants else TOP

    return truths(Evaluator(lookup, {}, port).value(guard)) == {True}

