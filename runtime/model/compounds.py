"""Compound types and the package that holds every declaration of a model."""
from __future__ import annotations

from dataclasses import dataclass, field

from runtime.diagnostics import Span
from runtime.model.behaviors import AtomType, PortType
from runtime.model.common import Annotation, DataParam, _span
from runtime.model.expressions import Expr
from runtime.model.interactions import ConnectorType
from runtime.model.priorities import PortRef, Priority


@dataclass
class ComponentInstance:
    """``component T name(args)`` inside a compound."""

    type: str
    name: str
    args: list[Expr] = field(default_factory=list)
    annotations: list[Annotation] = field(default_factory=list)
    span: Span = _span()


@dataclass
class ConnectorInstance:
    """``connector T name(c.p, d.q)`` inside a compound."""

    type: str
    name: str
    ports: list[PortRef] = field(default_factory=list)
    args: list[Expr] = field(default_factory=list)
    annotations: list[Annotation] = field(default_factory=list)  # e.g. @label(name="NDD.GoTo:trigger")
    comment: str | None = field(default=None, compare=False)  # printed as a comment above the declaration
    span: Span = _span()


@dataclass
class ExportPort:
    """``export port T name is c.p`` (or several ``c.p, d.q``) of a compound."""

    type: str
    name: str
    targets: list[PortRef] = field(default_factory=list)
    annotations: list[Annotation] = field(default_factory=list)
    span: Span = _span()


@dataclass
class ExportData:
    """``export data T name is c.x`` of a compound."""

    type: str
    name: str
    target: PortRef
    annotations: list[Annotation] = field(default_factory=list)
    span: Span = _span()


@dataclass
class CompoundType:
    """A compound type: instances of atoms/compounds, connectors between their ports, priorities, exports."""

    name: str
    params: list[DataParam] = field(default_factory=list)
    components: list[ComponentInstance] = field(default_factory=list)
    connectors: list[ConnectorInstance] = field(default_factory=list)
    priorities: list[Priority] = field(default_factory=list)
    ports: list[ExportPort] = field(default_factory=list)
    data: list[ExportData] = field(default_factory=list)
    annotations: list[Annotation] = field(default_factory=list)
    span: Span = _span()

    def component(self, name: str) -> ComponentInstance | None:
        return next((c for c in self.components if c.name == name), None)

    def connector(self, name: str) -> ConnectorInstance | None:
        return next((c for c in self.connectors if c.name == name), None)


@dataclass
class ExternFunction:
    """``extern function [T] f(const T1, T2)``: bound to a Python callable by name when the model runs.

    ``param_const`` says which parameters are ``const`` (one flag per parameter);
    BIP2 lets a guard call only functions whose parameters are all ``const``.
    """

    name: str
    return_type: str | None = None
    param_types: list[str] = field(default_factory=list)
    annotations: list[Annotation] = field(default_factory=list)  # e.g. the outcomes of a codel
    param_const: list[bool] = field(default_factory=list)
    span: Span = _span()

    def __post_init__(self) -> None:
        if not self.param_const:
            self.param_const = [False] * len(self.param_types)


@dataclass
class Constant:
    """``const data T name = e`` at package level."""

    type: str
    name: str
    value: Expr
    annotations: list[Annotation] = field(default_factory=list)
    span: Span = _span()


@dataclass
class Package:
    """One BIP2 package: every type of the model, in declaration order."""

    name: str
    uses: list[str] = field(default_factory=list)
    constants: list[Constant] = field(default_factory=list)
    extern_types: list[str] = field(default_factory=list)
    extern_functions: list[ExternFunction] = field(default_factory=list)
    port_types: list[PortType] = field(default_factory=list)
    atom_types: list[AtomType] = field(default_factory=list)
    connector_types: list[ConnectorType] = field(default_factory=list)
    compound_types: list[CompoundType] = field(default_factory=list)
    annotations: list[Annotation] = field(default_factory=list)
    span: Span = _span()
    #: annotations written before ``extern data type T``, by type name (types are plain names above)
    extern_type_annotations: dict[str, list[Annotation]] = field(default_factory=dict)

    def _find(self, items, name):
        return next((x for x in items if x.name == name), None)

    def port_type(self, name: str) -> PortType | None:
        return self._find(self.port_types, name)

    def atom_type(self, name: str) -> AtomType | None:
        return self._find(self.atom_types, name)

    def connector_type(self, name: str) -> ConnectorType | None:
        return self._find(self.connector_types, name)

    def compound_type(self, name: str) -> CompoundType | None:
        return self._find(self.compound_types, name)

    def component_type(self, name: str) -> AtomType | CompoundType | None:
        return self.atom_type(name) or self.compound_type(name)
