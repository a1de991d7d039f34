"""What fires in a flat system: the sources of interactions, and each connector type's compiled define.

A *source* is a top-level connector (one that exports no port) or a lone atom
port (a port the atom does not export).  Each connector source has a tree of
connector nodes whose leaves are atom ports; leaf ``i`` is bit ``1 << i`` of
the masks that identify the source's interactions.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from runtime.engine import defines
from runtime.engine.cexpr import coerce, default_value, evaluate
from runtime.engine.errors import FlattenError
from runtime.engine.flatten import FlatConnector, FlatPort, FlatSystem, Leaf
from runtime.model import ConnectorParam, ConnectorType, DefineGroup, DefinePort, Expr, InteractionSpec
from runtime.model.expressions import Assign, PortData, Var, map_port_data


@dataclass
class ConnectorInfo:
    """A connector type compiled once: parameter indices, define tree, ``on`` clauses by parameter mask."""

    type: ConnectorType
    index: dict[str, int]
    tree: defines.Node
    clauses: dict[int, InteractionSpec]
    local_defaults: list[Any]
    export_idx: tuple[int, ...]

    @property
    def rendezvous(self) -> bool:
        return not defines.has_trigger(self.tree)

    @property
    def all_params(self) -> int:
        return (1 << len(self.type.params)) - 1


@dataclass
class TreeAlt:
    """One alternative of a parameter in a source's tree: a leaf (atom port) or a sub-connector node."""

    mask: int
    port: int | None = None
    node: "TreeNode | None" = None


@dataclass
class TreeNode:
    """A connector instance as it occurs in one source's tree (a shared sub-connector occurs once per parent)."""

    connector: FlatConnector
    info: ConnectorInfo
    params: list[list[TreeAlt]]
    mask: int
    runtime: Any = None  # clause functions, attached by the engine


@dataclass
class Source:
    """Something that fires: ``kind`` is ``rendezvous``, ``flat``, ``generic`` (connectors) or ``port``."""

    index: int
    kind: str
    connector: FlatConnector | None = None
    port: FlatPort | None = None
    leaves: list[int] = field(default_factory=list)
    tree: TreeNode | None = None
    alternatives: bool = False
    maximal: bool = True  # keep only the maximal enabled interactions (maximal progress)

    @property
    def full(self) -> int:
        return (1 << len(self.leaves)) - 1


def connector_info(ct: ConnectorType, constants) -> ConnectorInfo:
    where = f"connector type {ct.name}"
    index = {p.name: i for i, p in enumerate(ct.params)}
    if len(index) != len(ct.params):
        raise FlattenError(f"{where}: two port parameters with the same name")
    tree = defines.compile_define(ct.define, index, where)
    clauses: dict[int, InteractionSpec] = {}
    for spec in ct.interactions:
        mask = 0
        for name in spec.ports:
            if name not in index:
                raise FlattenError(f"{where}: 'on {' '.join(spec.ports)}' names '{name}', not a port parameter")
            mask |= 1 << index[name]
        if not defines.allowed(tree, mask):
            raise FlattenError(f"{where}: 'on {' '.join(spec.ports)}' is not an interaction allowed by define")
        if mask in clauses:
            raise FlattenError(f"{where}: two 'on' clauses for {' '.join(spec.ports)}")
        clauses[mask] = spec
    defaults = []
    for d in ct.data:
        v = evaluate(d.init, constants, f"{where}, data {d.name}") if d.init is not None else default_value(d.type)
        defaults.append(coerce(v, d.type))
    export_idx: tuple[int, ...] = ()
    if ct.export is not None:
        names = [d.name for d in ct.data]
        for v in ct.export.data:
            if v not in names:
                raise FlattenError(f"{where}: exported port {ct.export.name} binds '{v}', not a data of the connector")
        export_idx = tuple(names.index(v) for v in ct.export.data)
    return ConnectorInfo(ct, index, tree, clauses, defaults, export_idx)


def plan(flat: FlatSystem, maximal_progress: bool = True) -> tuple[dict[str, ConnectorInfo], list[Source]]:
    """Compile the connector types in use and list the sources in a fixed order (connectors, then lone ports).

    Without ``maximal_progress`` every connector that has more than one interaction is enumerated
    exhaustively (the generic path), and all its enabled interactions are offered.
    """
    infos: dict[str, ConnectorInfo] = {}
    for fc in flat.connectors:
        if fc.type.name not in infos:
            infos[fc.type.name] = connector_info(fc.type, flat.constants)
    sources: list[Source] = []
    #: connectors a priority names with a parameter mask, or below the top: their trees stay as they are
    referenced = {cid for p in flat.priorities for side in (p.low, p.high) for cid, mask in side.entries
                  if mask or not flat.connectors[cid].top}
    for fc in flat.connectors:
        if not fc.top:
            continue
        counter = [0]
        leaves: list[int] = []
        alts_seen = [False]

        def build(c: FlatConnector) -> TreeNode:
            params = []
            mask = 0
            for alts in c.params:
                if len(alts) > 1:
                    alts_seen[0] = True
                row = []
                for a in alts:
                    if isinstance(a, Leaf):
                        bit = 1 << counter[0]
                        counter[0] += 1
                        leaves.append(a.port)
                        row.append(TreeAlt(bit, port=a.port))
                    else:
                        node = build(flat.connectors[a.connector])
                        row.append(TreeAlt(node.mask, node=node))
                    mask |= row[-1].mask
                params.append(row)
            return TreeNode(c, infos[c.type.name], params, mask)

        tree = build(fc)
        flat_params = all(len(alts) == 1 and isinstance(alts[0], Leaf) for alts in fc.params)
        if flat_params:
            kind = "rendezvous" if infos[fc.type.name].rendezvous else "flat"
        elif _plain_rendezvous(tree):
            kind = "rendezvous"
        elif not alts_seen[0] and _collapsible(tree, top=True) and not (referenced & _ids(tree)):
            fc = _collapsed(fc, tree, [flat.ports[q] for q in leaves], infos, flat)
            counter[0] = 0
            leaves.clear()
            tree = build(fc)
            kind = "rendezvous" if infos[fc.type.name].rendezvous else "flat"
        else:
            kind = "generic"
        if not maximal_progress and kind == "flat":
            kind = "generic"
        sources.append(Source(len(sources), kind, fc, None, leaves, tree, alts_seen[0], maximal_progress))
    for fp in flat.ports:
        if not fp.decl.exported:
            sources.append(Source(len(sources), "port", None, fp, [fp.id]))
    return infos, sources


def _collapsible(node: TreeNode, top: bool) -> bool:
    """A tree whose interactions are one connector's: no data anywhere, or rendezvous that only carry a guard up.

    The second shape is a guarded rendezvous split so that it binds each
    component once: the sub-connectors copy port data up (``up { v1 = p3.done; }``)
    for the top connector's guard, and do nothing else.
    """
    info = node.info
    if info.clauses:
        if not info.rendezvous or len(info.clauses) != 1 or info.all_params not in info.clauses:
            return False
        spec = info.clauses[info.all_params]
        if spec.down:
            return False
        if top and spec.up:  # the top connector may guard, not transfer
            return False
        if not top and (spec.guard is not None or not all(_copy(a) for a in spec.up)):
            return False  # a sub-connector may only copy port data up
    elif info.type.data:
        return False
    return all(a.node is None or _collapsible(a.node, top=False) for alts in node.params for a in alts)


def _copy(stmt) -> bool:
    """``v = p.x``: a sub-connector variable copied from a port's data."""
    return isinstance(stmt, Assign) and isinstance(stmt.target, Var) and isinstance(stmt.value, PortData)


def _ids(node: TreeNode) -> set[int]:
    return {node.connector.id} | {i for alts in node.params for a in alts if a.node is not None for i in _ids(a.node)}


def _collapsed(fc: FlatConnector, tree: TreeNode, leaves: list[FlatPort],
               infos: dict[str, ConnectorInfo], flat: FlatSystem) -> FlatConnector:
    """One connector over the tree's leaves whose define nests the sub-connectors' defines where their ports were.

    A connector tree without data has the interactions and the maximal
    progress of that single connector (BIP2: a define expression nests like
    connectors do), so it runs on the flat paths of the step, the compiled C
    step included; connectors that only gather the ports of one component
    (so that a connector binds each component once) then cost nothing.
    """
    names = [f"p{i + 1}" for i in range(len(leaves))]

    def substitute(node: TreeNode, d: defines.Node) -> defines.Node:
        if d[0] == "p":
            alt = node.params[d[1].bit_length() - 1][0]
            return ("p", alt.mask) if alt.node is None else substitute(alt.node, alt.node.info.tree)
        return ("g", tuple((substitute(node, sub), trig) for sub, trig in d[1]))

    def item(d: defines.Node, trigger: bool):
        if d[0] == "p":
            return DefinePort(names[d[1].bit_length() - 1], trigger)
        return DefineGroup([item(sub, t) for sub, t in d[1]], trigger)

    def data(node: TreeNode, port: str, name: str) -> Expr:
        """What ``port.name`` reads in ``node``: a leaf's data, or what a sub-connector copied up into its export."""
        alt = node.params[node.info.index[port]][0]
        if alt.node is None:
            return PortData(names[alt.mask.bit_length() - 1], name)
        sub = alt.node.info
        fields = [d.name for d in flat.package.port_type(sub.type.export.port_type).params]
        var = sub.type.export.data[fields.index(name)]
        copied = next(a.value for a in sub.clauses[sub.all_params].up if a.target.name == var)
        return data(alt.node, copied.port, copied.name)

    top = substitute(tree, tree.info.tree)
    define = item(top, False)
    spec = tree.info.clauses.get(tree.info.all_params)
    ct = ConnectorType(
        name=f"{fc.type.name}~{fc.id}",
        params=[ConnectorParam(port.decl.type, n) for port, n in zip(leaves, names)],
        define=define if isinstance(define, DefineGroup) else DefineGroup([define]),
        interactions=[
            InteractionSpec(list(names), guard=map_port_data(spec.guard, lambda d: data(tree, d.port, d.name)))
        ]
        if spec is not None and spec.guard is not None
        else [],
    )
    infos[ct.name] = connector_info(ct, flat.constants)
    return FlatConnector(fc.id, fc.path, fc.scope, fc.label, fc.instance, ct, [[Leaf(p.id)] for p in leaves],
                         list(fc.parents), fc.named)


def _plain_rendezvous(node: TreeNode) -> bool:
    """A tree of rendezvous with no alternative, guard or action: one rendezvous of its leaves.

    Sub-connectors that only gather the ports of one component (so that a
    connector binds each component once) then cost nothing at run time.
    """
    if not node.info.rendezvous or node.info.clauses:
        return False
    return all(len(alts) == 1 and (alts[0].node is None or _plain_rendezvous(alts[0].node)) for alts in node.params)


def parts(node: TreeNode, mask: int) -> list[tuple[int, int]]:
    """``(connector id, parameter mask)`` of every connector node taking part in the interaction ``mask``."""
    pm = 0
    out: list[tuple[int, int]] = []
    for i, alts in enumerate(node.params):
        for a in alts:
            if a.mask & mask:
                pm |= 1 << i
                if a.node is not None:
                    out.extend(parts(a.node, mask))
    return [(node.connector.id, pm)] + out if pm else out
