"""Interaction layer: connector types (typed trigger/synchron ports, nesting, guards, up/down data transfer)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Union

from runtime.diagnostics import Span
from runtime.model.common import Annotation, DataDecl, _span
from runtime.model.expressions import Expr, Stmt


@dataclass
class ConnectorParam:
    """A port parameter of a connector type: ``Port p`` in ``connector type C(Port p, Port q)``."""

    port_type: str
    name: str
    span: Span = _span()


@dataclass
class DefinePort:
    """One port parameter in a ``define`` expression; ``trigger`` for ``p'``."""

    name: str
    trigger: bool = False


@dataclass
class DefineGroup:
    """A parenthesised group ``(p q)'`` in a ``define`` expression; nests like connectors do."""

    items: list["DefineItem"]
    trigger: bool = False


DefineItem = Union[DefinePort, DefineGroup]


@dataclass
class ConnectorExport:
    """``export port T name(x, y)``: the port a connector offers to an enclosing connector."""

    port_type: str
    name: str
    data: list[str] = field(default_factory=list)
    annotations: list[Annotation] = field(default_factory=list)
    span: Span = _span()


@dataclass
class InteractionSpec:
    """``on p q provided (g) up {...} down {...}``: guard and data transfer for one interaction.

    ``ports`` lists the port parameters that take part; an empty list is not
    allowed by BIP2 (``on`` always names ports).
    """

    ports: list[str]
    guard: Expr | None = None
    up: list[Stmt] = field(default_factory=list)
    down: list[Stmt] = field(default_factory=list)
    annotations: list[Annotation] = field(default_factory=list)
    span: Span = _span()


@dataclass
class ConnectorType:
    """A connector type: which interactions of its ports are allowed and what they compute."""

    name: str
    params: list[ConnectorParam] = field(default_factory=list)
    define: DefineGroup = field(default_factory=lambda: DefineGroup([]))
    data: list[DataDecl] = field(default_factory=list)
    export: ConnectorExport | None = None
    interactions: list[InteractionSpec] = field(default_factory=list)
    annotations: list[Annotation] = field(default_factory=list)
    span: Span = _span()

    def param(self, name: str) -> ConnectorParam | None:
        return next((p for p in self.params if p.name == name), None)
