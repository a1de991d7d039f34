"""Pieces shared by the three BIP layers: typed parameters, data declarations, annotations."""
from __future__ import annotations

from dataclasses import dataclass, field

from runtime.diagnostics import NOWHERE, Span
from runtime.model.expressions import Expr

#: The BIP2 built-in data types; any other type name must be declared ``extern data type``.
BUILTIN_TYPES = ("bool", "int", "float", "string")


def _span():
    return field(default=NOWHERE, compare=False, repr=False, kw_only=True)


@dataclass
class Annotation:
    """``@cpp(include="x.hpp")`` and the like: kept verbatim, ignored by the engine."""

    name: str
    arguments: dict[str, str] = field(default_factory=dict)
    span: Span = _span()


@dataclass
class DataParam:
    """A typed formal parameter of a port type or an atom/compound type; ``const`` as in ``(const int v)``."""

    type: str
    name: str
    const: bool = False
    span: Span = _span()


@dataclass
class DataDecl:
    """``[export] [const] data T x [= e]`` in an atom or connector."""

    type: str
    name: str
    init: Expr | None = None
    const: bool = False
    exported: bool = False
    annotations: list[Annotation] = field(default_factory=list)
    span: Span = _span()


#: The annotation that names the description line an element of a generated model comes from.
SOURCE = "source"


def source_annotation(span: Span) -> list[Annotation]:
    """``@source(file="ndd.gen", line="42", column="3")`` for an element built from ``span``; none if unknown."""
    if span.line <= 0:
        return []
    return [Annotation(SOURCE, {"file": span.file, "line": str(span.line), "column": str(span.column)})]


def source_span(annotations: list[Annotation]) -> Span | None:
    """The :class:`Span` a ``@source`` annotation among ``annotations`` names, if there is a well-formed one."""
    for a in annotations:
        if a.name == SOURCE and "file" in a.arguments:
            line, column = a.arguments.get("line", ""), a.arguments.get("column", "1")
            if line.isdigit() and column.isdigit():
                return Span(a.arguments["file"], int(line), int(column))
    return None


def source_of(annotations: list[Annotation]) -> str | None:
    """``file:line:column`` from a ``@source`` annotation among ``annotations``, if there is one."""
    for a in annotations:
        if a.name == SOURCE and "file" in a.arguments:
            where = [a.arguments["file"], a.arguments.get("line"), a.arguments.get("column")]
            return ":".join(x for x in where if x)
    return None
