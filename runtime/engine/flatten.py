"""Instantiate a package from a root spec (``System()``, ``Sys(3)``) into a flat system.

The flat system is what code generation works from: atom instances with
dotted names and bound parameters, the slots of their state in the global
state tuple, every connector instance with its port parameters resolved down
to atom ports (through compound exports, possibly merged, and sub-connectors'
exported ports), and compound priorities resolved to concrete connectors.
"""
from __future__ import annotations

import ast
from dataclasses import dataclass, field
from typing import Any, Union

from runtime.diagnostics import Span
from runtime.engine.cexpr import coerce, evaluate
from runtime.engine.errors import FlattenError
from runtime.model import (
    AtomType,
    CompoundType,
    ConnectorInstance,
    ConnectorType,
    DataDecl,
    Expr,
    InteractionPattern,
    Package,
    PortDecl,
    PortRef,
)
from runtime.model.expressions import Const, Unary, Var

Constants = dict[str, tuple[Any, str]]  # name -> (value, type)


@dataclass
class FlatAtom:
    """An atom instance: its type, bound constants, and where its state sits in the state tuple.

    The slot ``offset`` holds the marking (bit i = ``places[i]`` marked), the
    following slots hold ``variables`` in declaration order.
    """

    index: int
    name: str
    type: AtomType
    constants: Constants
    variables: list[DataDecl]
    offset: int
    places: list[str]
    ports: dict[str, int] = field(default_factory=dict)

    def slot(self, var: str) -> int:
        return self.offset + 1 + next(i for i, d in enumerate(self.variables) if d.name == var)

    def place_mask(self, names: list[str]) -> int:
        return sum(1 << self.places.index(n) for n in set(names))

    @property
    def size(self) -> int:
        return 1 + len(self.variables)


@dataclass
class FlatPort:
    """A port of an atom instance; ``slots`` are the state slots of the data it carries."""

    id: int
    atom: int
    name: str
    path: str
    decl: PortDecl
    fields: list[str]
    field_types: list[str]
    slots: tuple[int, ...]
    connectors: list[int] = field(default_factory=list)


@dataclass(frozen=True)
class Leaf:
    """A connector parameter alternative that is an atom port."""

    port: int


@dataclass(frozen=True)
class Sub:
    """A connector parameter alternative that is the exported port of another connector."""

    connector: int


Alternative = Union[Leaf, Sub]


@dataclass
class FlatConnector:
    """A connector instance; each port parameter has one or more alternatives (several through merged exports)."""

    id: int
    path: str
    scope: str
    label: str
    instance: ConnectorInstance
    type: ConnectorType
    params: list[list[Alternative]]
    parents: list[int] = field(default_factory=list)
    named: bool = False  # the label comes from an @label annotation

    @property
    def top(self) -> bool:
        """Only connectors that export no port fire on their own (BIP2 execution sequences)."""
        return self.type.export is None


@dataclass
class FlatPattern:
    """One side of a compound priority: ``(connector id, parameter mask)`` entries, mask 0 meaning ``C:*``."""

    text: str
    entries: tuple[tuple[int, int], ...]


@dataclass
class FlatPriority:
    """A compound priority of some compound instance, with what its guard may read."""

    name: str
    low: FlatPattern
    high: FlatPattern
    guard: Expr | None
    constants: Constants
    data: dict[tuple[str, str], tuple[int, str]]  # (component, exported data) -> (slot, type)
    span: Span | None = None

    @property
    def text(self) -> str:
        return f"{self.name}: {self.low.text} < {self.high.text}"


@dataclass
class FlatSystem:
    """The whole instantiated model."""

    package: Package
    root: str
    atoms: list[FlatAtom]
    ports: list[FlatPort]
    connectors: list[FlatConnector]
    priorities: list[FlatPriority]
    state_size: int
    constants: Constants = field(default_factory=dict)  # package constants, evaluated

    def atom_of(self, port: int) -> FlatAtom:
        return self.atoms[self.ports[port].atom]

    def leaves(self, connector: FlatConnector) -> list[int]:
        """Every atom port a connector may bind, through its sub-connectors, in parameter order."""
        out: list[int] = []
        for alternatives in connector.params:
            for alt in alternatives:
                out += [alt.port] if isinstance(alt, Leaf) else self.leaves(self.connectors[alt.connector])
        return list(dict.fromkeys(out))


def _at(span: Span | None) -> str:
    return f"{span}: " if span is not None and span.line > 0 else ""


def _join(prefix: str, name: str) -> str:
    return f"{prefix}.{name}" if prefix else name


def parse_root(spec: str) -> tuple[str, list[Expr]]:
    """``Name(arg, ...)`` with literal arguments (ints, floats, strings, true/false, constant names)."""
    text = spec.strip()
    if "(" not in text:
        text += "()"
    try:
        node = ast.parse(text, mode="eval").body
    except SyntaxError:
        raise FlattenError(f"root '{spec}': expected a type name and arguments, e.g. System() or Sys(3)") from None
    if not isinstance(node, ast.Call) or not isinstance(node.func, ast.Name) or node.keywords:
        raise FlattenError(f"root '{spec}': expected a type name and arguments, e.g. System() or Sys(3)")

    def arg(a: ast.expr) -> Expr:
        if isinstance(a, ast.Constant) and isinstance(a.value, (int, float, str)) and not isinstance(a.value, bool):
            return Const(a.value)
        if isinstance(a, ast.UnaryOp) and isinstance(a.op, (ast.USub, ast.UAdd)):
            return Unary("-" if isinstance(a.op, ast.USub) else "+", arg(a.operand))
        if isinstance(a, ast.Name):
            return Const(a.id == "true") if a.id in ("true", "false") else Var(a.id)
        raise FlattenError(f"root '{spec}': arguments must be constants")

    return node.func.id, [arg(a) for a in node.args]


class _Interface:
    """What a component instance offers to its enclosing compound: exported ports and data."""

    def __init__(self) -> None:
        self.ports: dict[str, tuple[str, list[Alternative]]] = {}
        self.data: dict[str, tuple[int, str]] = {}


class _Builder:
    def __init__(self, package: Package) -> None:
        self.package = package
        self.atoms: list[FlatAtom] = []
        self.ports: list[FlatPort] = []
        self.connectors: list[FlatConnector] = []
        self.priorities: list[FlatPriority] = []
        self.offset = 0
        self.constants: Constants = {}
        for c in package.constants:
            value = evaluate(c.value, self.constants, f"{_at(c.span)}constant {c.name}")
            self.constants[c.name] = (coerce(value, c.type), c.type)

    # -- arguments ---------------------------------------------------------------------
    def bind(self, what: str, params, args: list[Expr], env: Constants, span) -> Constants:
        if len(args) != len(params):
            names = ", ".join(f"{p.type} {p.name}" for p in params)
            raise FlattenError(f"{_at(span)}{what} takes {len(params)} argument(s) ({names}), {len(args)} given")
        bound = dict(self.constants)
        for p, a in zip(params, args):
            value = evaluate(a, env, f"{_at(span)}{what}, argument {p.name}")
            bound[p.name] = (coerce(value, p.type), p.type)
        return bound

    # -- components ----------------------------------------------------------------------
    def component(self, name: str, type_name: str, args: list[Expr], env: Constants, span) -> _Interface:
        atom = self.package.atom_type(type_name)
        if atom is not None:
            return self.atom(name, atom, self.bind(f"atom type {type_name}", atom.params, args, env, span))
        compound = self.package.compound_type(type_name)
        if compound is not None:
            bound = self.bind(f"compound type {type_name}", compound.params, args, env, span)
            return self.compound(name, compound, bound)
        known = ", ".join(t.name for t in self.package.atom_types + self.package.compound_types) or "none"
        raise FlattenError(f"{_at(span)}unknown component type '{type_name}' for '{name}' (known: {known})")

    def atom(self, name: str, t: AtomType, constants: Constants) -> _Interface:
        constants = dict(constants)
        variables = []
        for d in t.data:
            if d.const:
                if d.init is None:
                    raise FlattenError(f"{_at(d.span)}{t.name}: const data '{d.name}' has no value")
                constants[d.name] = (coerce(evaluate(d.init, constants, f"{t.name}.{d.name}"), d.type), d.type)
            else:
                variables.append(d)
        if not t.places:
            raise FlattenError(f"{_at(t.span)}atom type {t.name} has no place")
        if t.initial is None:
            raise FlattenError(f"{_at(t.span)}atom type {t.name} has no initial transition")
        fa = FlatAtom(len(self.atoms), name, t, constants, variables, self.offset, list(t.places))
        self.atoms.append(fa)
        self.offset += fa.size
        iface = _Interface()
        for d in t.data:
            if d.exported and not d.const:
                iface.data[d.name] = (fa.slot(d.name), d.type)
        for decl in t.ports:
            ptype = self.package.port_type(decl.type)
            if ptype is None:
                raise FlattenError(f"{_at(decl.span)}{t.name}: unknown port type '{decl.type}' of port {decl.name}")
            if len(decl.data) != len(ptype.params):
                raise FlattenError(f"{_at(decl.span)}{t.name}: port {decl.name} binds {len(decl.data)} variable(s), "
                                   f"port type {ptype.name} has {len(ptype.params)}")
            slots = []
            for v in decl.data:
                if not any(d.name == v for d in variables):
                    raise FlattenError(
                        f"{_at(decl.span)}{t.name}: port {decl.name} binds '{v}', not a variable of the atom"
                    )
                slots.append(fa.slot(v))
            fp = FlatPort(len(self.ports), fa.index, decl.name, _join(name, decl.name), decl,
                          [p.name for p in ptype.params], [p.type for p in ptype.params], tuple(slots))
            self.ports.append(fp)
            fa.ports[decl.name] = fp.id
            if decl.exported:
                iface.ports.setdefault(decl.interface_name, (decl.type, []))[1].append(Leaf(fp.id))
        return iface

    def compound(self, path: str, t: CompoundType, env: Constants) -> _Interface:
        children: dict[str, _Interface] = {}
        for c in t.components:
            if c.name in children:
                raise FlattenError(f"{_at(c.span)}{t.name}: two components named '{c.name}'")
            children[c.name] = self.component(_join(path, c.name), c.type, c.args, env, c.span)
        # Number the connectors first, so that a connector may use one declared after it.
        local: dict[str, FlatConnector] = {}
        for ci in t.connectors:
            ct = self.package.connector_type(ci.type)
            if ct is None:
                raise FlattenError(f"{_at(ci.span)}{t.name}: unknown connector type '{ci.type}' for '{ci.name}'")
            if ci.name in local or ci.name in children:
                raise FlattenError(f"{_at(ci.span)}{t.name}: name '{ci.name}' declared twice")
            if ci.args:
                raise FlattenError(f"{_at(ci.span)}{t.name}: connector {ci.name} takes no data arguments")
            label, named = _join(path, ci.name), False
            for a in ci.annotations:
                if a.name == "label" and "name" in a.arguments:
                    label, named = a.arguments["name"], True
            fc = FlatConnector(len(self.connectors), _join(path, ci.name), path, label, ci, ct, [], named=named)
            self.connectors.append(fc)
            local[ci.name] = fc
        for ci in t.connectors:
            fc = local[ci.name]
            ct = fc.type
            if len(ci.ports) != len(ct.params):
                raise FlattenError(f"{_at(ci.span)}connector {fc.path} of type {ct.name}: {len(ct.params)} port(s) "
                                   f"expected, {len(ci.ports)} given")
            for p, ref in zip(ct.params, ci.ports):
                ptype, alts = self.resolve(t, path, children, local, ref, ci.span)
                if ptype != p.port_type:
                    raise FlattenError(f"{_at(ci.span)}connector {fc.path}: port {ref} has type {ptype}, "
                                       f"parameter {p.name} of {ct.name} expects {p.port_type}")
                fc.params.append(alts)
                for a in alts:
                    if isinstance(a, Sub):
                        self.connectors[a.connector].parents.append(fc.id)
                    else:
                        self.ports[a.port].connectors.append(fc.id)
            self.check_disjoint(fc, ci.span)
        iface = _Interface()
        for ex in t.ports:
            alts: list[Alternative] = []
            for ref in ex.targets:
                ptype, more = self.resolve(t, path, children, local, ref, ex.span)
                if ptype != ex.type:
                    raise FlattenError(f"{_at(ex.span)}{t.name}: export port {ex.name} of type {ex.type} "
                                       f"refers to {ref} of type {ptype}")
                alts.extend(more)
            iface.ports[ex.name] = (ex.type, alts)
        for ed in t.data:
            iface.data[ed.name] = self.resolve_data(t, children, ed.target, ed.span)
        data_refs = {}
        for cname, ch in children.items():
            for dname, ref in ch.data.items():
                data_refs[(cname, dname)] = ref
        for pr in t.priorities:
            low = self.pattern(t, path, local, pr.low, pr.high, pr.span)
            high = self.pattern(t, path, local, pr.high, pr.low, pr.span)
            self.priorities.append(FlatPriority(_join(path, pr.name), low, high, pr.guard, env, data_refs, pr.span))
        return iface

    def resolve(self, t: CompoundType, path: str, children: dict[str, _Interface],
                local: dict[str, FlatConnector], ref: PortRef, span) -> tuple[str, list[Alternative]]:
        """Port type and alternatives of ``c.p`` inside compound ``t``."""
        if ref.component in local:
            fc = local[ref.component]
            if fc.type.export is None or fc.type.export.name != ref.port:
                raise FlattenError(f"{_at(span)}{t.name}: connector {ref.component} exports no port '{ref.port}'")
            return fc.type.export.port_type, [Sub(fc.id)]
        ch = children.get(ref.component)
        if ch is None:
            raise FlattenError(f"{_at(span)}{t.name}: no component or connector named '{ref.component}' (in {ref})")
        if ref.port not in ch.ports:
            atom = next((a for a in self.atoms if a.name == _join(path, ref.component)), None)
            if atom is not None and ref.port in atom.ports:
                raise FlattenError(f"{_at(span)}{t.name}: port {ref} is not exported by atom type {atom.type.name}")
            raise FlattenError(f"{_at(span)}{t.name}: component {ref.component} has no exported port '{ref.port}'")
        return ch.ports[ref.port]

    def resolve_data(self, t: CompoundType, children, ref: PortRef, span) -> tuple[int, str]:
        ch = children.get(ref.component)
        if ch is None or ref.port not in ch.data:
            raise FlattenError(f"{_at(span)}{t.name}: no exported data {ref}")
        return ch.data[ref.port]

    def leaves(self, alt: Alternative, seen: tuple[int, ...] = ()) -> list[int]:
        """Atom ports under an alternative; a connector nested in itself is an error."""
        if isinstance(alt, Leaf):
            return [alt.port]
        if alt.connector in seen:
            raise FlattenError(f"connector {self.connectors[alt.connector].path} is nested in itself")
        out = []
        for alts in self.connectors[alt.connector].params:
            for a in alts:
                out.extend(self.leaves(a, seen + (alt.connector,)))
        return out

    def check_disjoint(self, fc: FlatConnector, span) -> None:
        owner: dict[int, str] = {}
        for p, alts in zip(fc.type.params, fc.params):
            atoms = set()
            for a in alts:
                atoms.update(self.ports[x].atom for x in self.leaves(a, (fc.id,)))
            for x in atoms:
                if x in owner:
                    raise FlattenError(f"{_at(span)}connector {fc.path}: atom {self.atoms[x].name} is reached through "
                                       f"both parameters {owner[x]} and {p.name} (a component may take part once)")
                owner[x] = p.name

    def pattern(self, t: CompoundType, path: str, local: dict[str, FlatConnector],
                pat: InteractionPattern, other: InteractionPattern, span) -> FlatPattern:
        if pat.connector == "*":
            if other.connector == "*":
                raise FlattenError(f"{_at(span)}{t.name}: '*:*' on both sides of a priority")
            # any other connector that fires on its own: a sub-connector is part of its parent's interactions
            entries = tuple((fc.id, 0) for name, fc in local.items() if name != other.connector and fc.top)
            return FlatPattern(str(pat), entries)
        fc = local.get(pat.connector)
        if fc is None:
            raise FlattenError(f"{_at(span)}{t.name}: priority names unknown connector '{pat.connector}'")
        if pat.ports is None:
            return FlatPattern(_join(path, str(pat)), ((fc.id, 0),))
        mask = 0
        for ref in pat.ports:
            idx = next(
                (i for i, r in enumerate(fc.instance.ports) if (r.component, r.port) == (ref.component, ref.port)), None
            )
            if idx is None:
                raise FlattenError(
                    f"{_at(span)}{t.name}: priority names {ref}, not a port of connector {pat.connector}"
                )
            mask |= 1 << idx
        return FlatPattern(_join(path, str(pat)), ((fc.id, mask),))


def flatten(package: Package, root: str = "System()") -> FlatSystem:
    """Instantiate ``root`` (a compound or atom type of ``package`` with constant arguments)."""
    name, args = parse_root(root)
    b = _Builder(package)
    t = package.component_type(name)
    if t is None:
        known = ", ".join(c.name for c in package.compound_types + package.atom_types) or "none"
        raise FlattenError(f"root '{root}': no compound or atom type named '{name}' in package {package.name} "
                           f"(types: {known})")
    if len(args) != len(t.params):
        names = ", ".join(f"{p.type} {p.name}" for p in t.params)
        raise FlattenError(f"root '{root}': {name} takes {len(t.params)} argument(s) ({names}), {len(args)} given")
    b.component(name if isinstance(t, AtomType) else "", name, args, b.constants, None)
    for fc in b.connectors:
        b.leaves(Sub(fc.id))
    return FlatSystem(package, root, b.atoms, b.ports, b.connectors, b.priorities, b.offset, b.constants)


__all__ = ["FlatAtom", "FlatConnector", "FlatPattern", "FlatPort", "FlatPriority", "FlatSystem", "Leaf", "Sub",
           "flatten", "parse_root"]
