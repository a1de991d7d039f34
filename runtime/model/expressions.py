"""Guards and actions as small expression/statement trees (C operators, extern calls, if/then/else).

These are data, not Python strings: the BIP2 writer prints them, the reader
builds them, and the engine compiles them to Python once per model.
Nodes are frozen so that models can be compared and hashed.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Union

#: Binary C operators, loosest first; the writer uses this order to decide parentheses.
BINARY_PRECEDENCE: dict[str, int] = {
    "||": 1, "&&": 2, "|": 3, "^": 4, "&": 5,
    "==": 6, "!=": 6,
    "<": 7, "<=": 7, ">": 7, ">=": 7,
    "<<": 8, ">>": 8,
    "+": 9, "-": 9,
    "*": 10, "/": 10, "%": 10,
}
UNARY_OPERATORS = ("-", "+", "!", "~")


@dataclass(frozen=True)
class Const:
    """A literal: bool, int, float or string."""

    value: bool | int | float | str


@dataclass(frozen=True)
class Var:
    """A data variable of the enclosing atom or connector (or a constant of the package)."""

    name: str


@dataclass(frozen=True)
class PortData:
    """``p.x``: in a connector, variable ``x`` carried by its port parameter ``p``;
    in a compound priority guard, exported data ``x`` of component ``p``."""

    port: str
    name: str


@dataclass(frozen=True)
class Unary:
    op: str
    operand: "Expr"


@dataclass(frozen=True)
class Binary:
    op: str
    left: "Expr"
    right: "Expr"


@dataclass(frozen=True)
class Call:
    """A call of an extern function (bound to a Python callable when the model runs)."""

    function: str
    args: tuple["Expr", ...] = ()


Expr = Union[Const, Var, PortData, Unary, Binary, Call]


@dataclass(frozen=True)
class Assign:
    target: Var | PortData
    value: Expr


@dataclass(frozen=True)
class If:
    cond: Expr
    then: tuple["Stmt", ...] = ()
    orelse: tuple["Stmt", ...] = ()


@dataclass(frozen=True)
class Do:
    """An expression used as a statement, usually a call of an extern function."""

    call: Call


Stmt = Union[Assign, If, Do]


def variables(node: Expr | Stmt) -> set[str]:
    """Names of the plain variables read or written by a node (not port data)."""
    if isinstance(node, Var):
        return {node.name}
    if isinstance(node, Unary):
        return variables(node.operand)
    if isinstance(node, Binary):
        return variables(node.left) | variables(node.right)
    if isinstance(node, Call):
        return set().union(*(variables(a) for a in node.args)) if node.args else set()
    if isinstance(node, Assign):
        return variables(node.target) | variables(node.value)
    if isinstance(node, If):
        out = variables(node.cond)
        for s in node.then + node.orelse:
            out |= variables(s)
        return out
    if isinstance(node, Do):
        return variables(node.call)
    return set()


def assigned(stmts) -> set[str]:
    """Names of the plain variables some path of ``stmts`` assigns."""
    out: set[str] = set()
    for s in stmts:
        if isinstance(s, Assign) and isinstance(s.target, Var):
            out.add(s.target.name)
        elif isinstance(s, If):
            out |= assigned(s.then) | assigned(s.orelse)
    return out


def map_port_data(e: Expr, fn: Callable[[PortData], Expr]) -> Expr:
    """``e`` with every port data read ``p.x`` replaced by ``fn(p.x)`` (moving a guard between connectors)."""
    if isinstance(e, PortData):
        return fn(e)
    if isinstance(e, Unary):
        return Unary(e.op, map_port_data(e.operand, fn))
    if isinstance(e, Binary):
        return Binary(e.op, map_port_data(e.left, fn), map_port_data(e.right, fn))
    if isinstance(e, Call):
        return Call(e.function, tuple(map_port_data(a, fn) for a in e.args))
    return e


def calls(node: Expr | Stmt) -> set[str]:
    """Names of the extern functions a node calls."""
    if isinstance(node, Call):
        out = {node.function}
        for a in node.args:
            out |= calls(a)
        return out
    if isinstance(node, Unary):
        return calls(node.operand)
    if isinstance(node, Binary):
        return calls(node.left) | calls(node.right)
    if isinstance(node, Assign):
        return calls(node.value)
    if isinstance(node, If):
        out = calls(node.cond)
        for s in node.then + node.orelse:
            out |= calls(s)
        return out
    if isinstance(node, Do):
        return calls(node.call)
    return set()
