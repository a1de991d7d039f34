"""Component-based assembly: atoms in a tree of compounds, connectors placed where their ports meet.

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
    ExportPort,
    InteractionPattern,
    PortRef,
    Priority,
)
from runtime.model.expressions import Expr

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

    def __init__(self, port_type: "Callable[[str, str], str]") -> None:
        self.port_type = port_type  # (atom type name, port name) -> port type name, for exports
        self.groups: dict[Path, Group] = {}
        self.atoms: dict[Path, AtomInstance] = {}
        self.children: dict[Path, list[Path]] = {}
        self.wires: list[Wire] = []
        self.ranks: list[Rank] = []

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

        def place(w: Wire, at: Path) -> str:
            ports = []
            for e in w.ends:
                if isinstance(e, Wire):
                    ports.append(PortRef(place(e, at), e.type.export.name))
                else:
                    ports.append(ref(e, at))
            name = local_name(w, at)
            annotations = list(w.annotations)
            if w.label:
                annotations.insert(0, Annotation("label", {"name": w.label}))
            connectors[at].append(ConnectorInstance(w.type.name, name, ports, annotations=annotations, comment=w.comment))
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
                )
            )
        return out
