"""Component-based assembly: atoms in a tree of compounds, connectors placed where their ports meet.

A connector never binds two ports of one component of its compound (a BIP2
rule): ends that meet in a sub-compound are joined there by a sub-connector
whose port the sub-compound exports.

The builders describe *what* synchronises (a :class:`Wire` between atom ports,
a :class:`Rank` between two wires) without caring in which compound the
connector must live.  :meth:`Assembly.compounds` places every connector in the
lowest compound that contains all its ports — lifted to where its priorities
are declared when it takes part in one — and exports the ports it needs
through the compounds in between.  This is what lets a rule between NDD and POM
become one connector of the functional level while a service's own start
connector stays inside the service.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Union

from runtime.model import (
    Annotation,
    ComponentInstance,
    CompoundType,
    ConnectorInstance,
    ConnectorType,
    ExportData,
    ExportPort,
    InteractionPattern,
    PortRef,
    PortType,
    Priority,
    SOURCE,
)
from runtime.model.expressions import Expr, PortData

from genom2bip.build.split import SplitError, split_connector

Path = tuple[str, ...]


@dataclass(frozen=True)
class End:
    """A port of an atom, named by the atom's path from the root compound."""

    atom: Path
    port: str


@dataclass(eq=False)
class Wire:
    """An abstract connector: its type, its ends in order, and where its name and label come from."""

    type: ConnectorType
    ends: list[Union[End, "Wire"]]
    name: str  # local name, unique among the wires of ``owner``
    owner: Path  # the compound the name is relative to (a module, a service...)
    label: str | None = None
    comment: str | None = None
    annotations: list[Annotation] = field(default_factory=list)

    def atom_ends(self) -> list[End]:
        out: list[End] = []
        for e in self.ends:
            out.extend(e.atom_ends() if isinstance(e, Wire) else [e])
        return out


@dataclass(eq=False)
class Rank:
    """A priority: ``low`` may not fire while ``high`` is enabled."""

    name: str  # local name, unique among the ranks of ``owner``
    low: Wire
    high: Wire
    comment: str
    owner: Path = ()
    guard: Expr | None = None


@dataclass
class Group:
    path: Path
    type: str
    args: list[Expr] = field(default_factory=list)
    comment: str | None = None


@dataclass
class AtomInstance:
    path: Path
    type: str
    args: list[Expr] = field(default_factory=list)


def _exported_name(rest: Path, data: str) -> str:
    """The name under which a compound exports ``data`` of the atom at path ``rest`` below it."""
    return "_".join(rest + (data,))


def _common_prefix(paths: list[Path]) -> Path:
    if not paths:
        return ()
    first = paths[0]
    n = len(first)
    for p in paths[1:]:
        n = min(n, len(p))
        for i in range(n):
            if p[i] != first[i]:
                n = i
                break
    return first[:n]


class Assembly:
    """Collects groups, atoms, wires and ranks; turns them into BIP compound types."""

    def __init__(self, port_type: "Callable[[str, str], str]",
                 register: "Callable[[ConnectorType], ConnectorType]" = lambda t: t) -> None:
        self.port_type = port_type  # (atom type name, port name) -> port type name, for exports
        self.register = register  # records a connector type the placement creates; returns the one to use
        self.port_types: dict[str, PortType] = {}  # port types the placement creates (data carried up)
        self.groups: dict[Path, Group] = {}
        self.atoms: dict[Path, AtomInstance] = {}
        self.children: dict[Path, list[Path]] = {}
        self.wires: list[Wire] = []
        self.ranks: list[Rank] = []
        self.exposed: dict[tuple[Path, str], str] = {}  # (atom, exported data) -> its type

    def expose(self, atom: Path, data: str, dtype: str = "int") -> PortData:
        """``data`` of ``atom`` (exported by its type) exported up to the root: what a root priority's guard reads."""
        self.exposed[(atom, data)] = dtype
        return PortData(atom[0], _exported_name(atom[1:], data)) if len(atom) > 1 else PortData(atom[0], data)

    # -- building ---------------------------------------------------------------------------
    def group(self, path: Path, type_name: str, comment: str | None = None) -> Path:
        self.groups[path] = Group(path, type_name, comment=comment)
        self.children.setdefault(path, [])
        if path:
            self.children[path[:-1]].append(path)
        return path

    def atom(self, path: Path, type_name: str, args: list[Expr] | None = None) -> Path:
        self.atoms[path] = AtomInstance(path, type_name, list(args or []))
        self.children[path[:-1]].append(path)
        return path

    def wire(self, wire: Wire) -> Wire:
        self.wires.append(wire)
        return wire

    def rank(self, rank: Rank) -> Rank:
        self.ranks.append(rank)
        return rank

    def remove(self, path: Path) -> None:
        """Drop a compound (everything in it) or an atom, with the wires that touch it and their ranks."""
        gone = {p for p in list(self.atoms) + list(self.groups) if p[:len(path)] == path}
        for p in gone:
            self.atoms.pop(p, None)
            self.groups.pop(p, None)
            self.children.pop(p, None)
        if path[:-1] in self.children:
            self.children[path[:-1]] = [c for c in self.children[path[:-1]] if c != path]
        dropped = {id(w) for w in self.wires if any(e.atom[:len(path)] == path for e in w.atom_ends())}
        self.wires = [w for w in self.wires if id(w) not in dropped]
        self.ranks = [r for r in self.ranks if id(r.low) not in dropped and id(r.high) not in dropped]

    # -- placement ------------------------------------------------------------------------
    def _placement(self) -> dict[int, Path]:
        """Compound of every top-level wire: lowest common one, lifted by the ranks it takes part in."""
        top = [w for w in self.wires if not any(w in (o.ends) for o in self.wires)]
        scope = {id(w): _common_prefix([e.atom[:-1] for e in w.atom_ends()]) for w in top}
        changed = True
        while changed:
            changed = False
            for r in self.ranks:
                common = _common_prefix([scope[id(r.low)], scope[id(r.high)]])
                for w in (r.low, r.high):
                    if scope[id(w)] != common:
                        scope[id(w)] = common
                        changed = True
        return scope

    def compounds(self) -> list[CompoundType]:
        """Materialise the tree as compound types, innermost first (declaration order for BIP2)."""
        scope = self._placement()
        by_scope: dict[Path, list[Wire]] = {}
        for w in self.wires:
            if id(w) in scope:
                by_scope.setdefault(scope[id(w)], []).append(w)
        exports: dict[Path, dict[str, ExportPort]] = {p: {} for p in self.groups}
        names: dict[int, str] = {}

        def ref(end: End, at: Path) -> PortRef:
            """Reference to ``end`` from compound ``at``, exporting it through the compounds between."""
            inner = end.port
            for k in range(len(end.atom) - 1, len(at), -1):
                holder = end.atom[:k]
                exported = "_".join(end.atom[k:]) + "_" + end.port
                ptype = self.port_type(self.atoms[end.atom].type, end.port)
                exports[holder].setdefault(exported, ExportPort(ptype, exported, [PortRef(end.atom[k], inner)]))
                inner = exported
            return PortRef(end.atom[len(at)], inner)

        def local_name(w: Wire | Rank, at: Path) -> str:
            extra = w.owner[len(at):] if w.owner[: len(at)] == at else w.owner
            return "_".join(extra + (w.name,))

        connectors: dict[Path, list[ConnectorInstance]] = {p: [] for p in self.groups}

        def join(w: Wire, ctype: ConnectorType, ends: list[End], at: Path) -> tuple[ConnectorType, list[PortRef]]:
            """The connector type and ports joining ``ends`` from ``at``, binding each component of ``at`` once.

            Ends that meet in one sub-compound are joined there by a
            sub-connector whose port that compound exports (genom2bip.build.split).
            """
            groups: dict[str, list[int]] = {}
            for i, e in enumerate(ends):
                groups.setdefault(e.atom[len(at)], []).append(i)
            if all(len(g) == 1 for g in groups.values()):
                return ctype, [ref(e, at) for e in ends]
            keys = list(groups)
            sp = split_connector(ctype, list(groups.values()), self.port_types)
            refs: list[PortRef] = []
            for key, g, sub in zip(keys, groups.values(), sp.subs):
                if sub is None:
                    refs.append(ref(ends[g[0]], at))
                    continue
                # The sub-connector lives where its ends meet, and its port is exported up to ``at``.
                low = _common_prefix([ends[i].atom[:-1] for i in g])
                if len(low) <= len(at):
                    raise SplitError(f"connector {local_name(w, at)} binds atom {'.'.join(at + (key,))} twice")
                sub = self.register(sub)
                name = sub_name(w, low)
                inner_type, inner = join(w, sub, [ends[i] for i in g], low)
                at_source = [a for a in w.annotations if a.name == SOURCE]  # the description line of the whole
                connectors[low].append(ConnectorInstance(inner_type.name, name, inner, annotations=at_source))
                exported, target = name, PortRef(name, sub.export.name)
                for k in range(len(low), len(at), -1):
                    holder = low[:k]
                    if exported in exports[holder]:
                        raise SplitError(f"compound {'.'.join(holder)} already exports a port named {exported}")
                    exports[holder][exported] = ExportPort(sub.export.port_type, exported, [target])
                    target = PortRef(low[k - 1], exported)
                    exported = f"{low[k - 1]}_{exported}"
                refs.append(target)
            return self.register(sp.outer), [refs[k] for k in sp.order]

        def sub_name(w: Wire, at: Path) -> str:
            """A sub-connector's name: the wire's name relative to the compound both it and ``at`` are in."""
            common = _common_prefix([w.owner, at])
            return "_".join(w.owner[len(common):] + (w.name,))

        def place(w: Wire, at: Path) -> str:
            name = local_name(w, at)
            if any(isinstance(e, Wire) for e in w.ends):
                ctype = w.type
                ports = [PortRef(place(e, at), e.type.export.name) if isinstance(e, Wire) else ref(e, at)
                         for e in w.ends]
            else:
                ctype, ports = join(w, w.type, list(w.ends), at)
            annotations = list(w.annotations)
            if w.label:
                annotations.insert(0, Annotation("label", {"name": w.label}))
            connectors[at].append(
                ConnectorInstance(ctype.name, name, ports, annotations=annotations, comment=w.comment)
            )
            names[id(w)] = name
            return name

        for at in sorted(by_scope, key=len):
            for w in by_scope[at]:
                place(w, at)

        priorities: dict[Path, list[Priority]] = {p: [] for p in self.groups}
        for r in self.ranks:
            at = scope[id(r.low)]
            priorities[at].append(
                Priority(
                    local_name(r, at),
                    InteractionPattern(names[id(r.low)]),
                    InteractionPattern(names[id(r.high)]),
                    guard=r.guard,
                    comment=r.comment,
                )
            )

        data: dict[Path, list[ExportData]] = {p: [] for p in self.groups}
        for (atom, name), dtype in sorted(self.exposed.items()):
            for k in range(len(atom) - 1, 0, -1):  # each compound between the atom and the root exports it
                inner = name if k == len(atom) - 1 else _exported_name(atom[k + 1:], name)
                data[atom[:k]].append(ExportData(dtype, _exported_name(atom[k:], name), PortRef(atom[k], inner)))

        out: list[CompoundType] = []
        for path in sorted(self.groups, key=lambda p: (-len(p), p)):
            g = self.groups[path]
            comps = []
            for child in self.children[path]:
                if child in self.groups:
                    cg = self.groups[child]
                    comps.append(ComponentInstance(cg.type, child[-1], list(cg.args)))
                else:
                    a = self.atoms[child]
                    comps.append(ComponentInstance(a.type, child[-1], list(a.args)))
            out.append(
                CompoundType(
                    name=g.type,
                    components=comps,
                    connectors=connectors[path],
                    priorities=priorities[path],
                    ports=list(exports[path].values()),
                    data=data[path],
                )
            )
        return out
