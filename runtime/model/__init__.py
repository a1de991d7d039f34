"""The BIP model as plain data, split like the BIP metamodel: behaviors, interactions, priorities.

``Package`` (in :mod:`runtime.model.compounds`) holds every declaration; a
running system is a package plus the root instance (``System()``).
"""
from runtime.model.behaviors import (
    AtomPriority,
    AtomType,
    InitialTransition,
    PortDecl,
    PortType,
    Transition,
    coverable_places,
)
from runtime.model.common import BUILTIN_TYPES, SOURCE, Annotation, DataDecl, DataParam, source_annotation, source_of
from runtime.model.compounds import (
    ComponentInstance,
    CompoundType,
    ConnectorInstance,
    Constant,
    ExportData,
    ExportPort,
    ExternFunction,
    Package,
)
from runtime.model.expressions import Assign, Binary, Call, Const, Do, Expr, If, PortData, Stmt, Unary, Var
from runtime.model.interactions import (
    ConnectorExport,
    ConnectorParam,
    ConnectorType,
    DefineGroup,
    DefineItem,
    DefinePort,
    InteractionSpec,
)
from runtime.model.priorities import InteractionPattern, PortRef, Priority
from runtime.model.timing import ClockDecl, Invariant, Rate, Resume

__all__ = [
    "Annotation",
    "Assign",
    "AtomPriority",
    "AtomType",
    "BUILTIN_TYPES",
    "Binary",
    "Call",
    "ComponentInstance",
    "CompoundType",
    "ConnectorExport",
    "ConnectorInstance",
    "ConnectorParam",
    "ConnectorType",
    "Const",
    "Constant",
    "DataDecl",
    "DataParam",
    "DefineGroup",
    "DefineItem",
    "DefinePort",
    "Do",
    "ExportData",
    "ExportPort",
    "Expr",
    "ExternFunction",
    "If",
    "InitialTransition",
    "InteractionPattern",
    "InteractionSpec",
    "Package",
    "PortData",
    "PortDecl",
    "PortRef",
    "PortType",
    "Priority",
    "SOURCE",
    "Stmt",
    "Transition",
    "Unary",
    "Var",
    "coverable_places",
    "source_annotation",
    "source_of",
    "ClockDecl",
    "Invariant",
    "Rate",
    "Resume",
]
