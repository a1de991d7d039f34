"""Name checks of guards and actions: which variables, port data and extern functions a place may use."""
from __future__ import annotations

import difflib
from dataclasses import dataclass, field, replace
from typing import Callable

from runtime.bip2.locator import Locator
from runtime.diagnostics import Reporter, Span
from runtime.model import Assign, Binary, Call, Const, Do, ExternFunction, If, PortData, Unary, Var


@dataclass
class Scope:
    """What the expressions of one construct may name.

    ``variables`` maps a visible name to what it is (data, parameter,
    constant); only names in ``assignable`` may be written.  ``port_data``
    checks ``p.x`` and returns an error message, or None when it is fine.
    """

    where: str
    variables: dict[str, str]
    assignable: set[str] = field(default_factory=set)
    port_data: Callable[[PortData], str | None] | None = None
    guard: bool = False  # a guard may call only functions whose parameters are all const


def suggestion(name: str, known) -> str | None:
    """``did you mean 'x'?`` when a known name is close to ``name``."""
    close = difflib.get_close_matches(name, sorted(known), n=1)
    return f"did you mean '{close[0]}'?" if close else None


class ExpressionChecker:
    """Reports unknown variables, unknown extern functions and bad writes in guards and actions."""

    def __init__(self, functions: dict[str, list[ExternFunction]], locator: Locator, reporter: Reporter,
                 lenient_calls: bool = False) -> None:
        self.functions = functions
        self.loc = locator
        self.rep = reporter
        self.lenient_calls = lenient_calls  # functions may come from a used package we do not read

    def guard(self, e, scope: Scope, at: Span) -> None:
        """A guard: an expression in a constant context."""
        self.expr(e, replace(scope, guard=True), at)

    def expr(self, e, scope: Scope, at: Span, value_needed: bool = True) -> None:
        if isinstance(e, Const):
            return
        if isinstance(e, Var):
            if e.name not in scope.variables:
                self.rep.error(self.loc.at(e, default=at), f"unknown variable '{e.name}' in {scope.where}",
                               hint=suggestion(e.name, scope.variables))
        elif isinstance(e, PortData):
            problem = (scope.port_data(e) if scope.port_data
                       else f"'{e.port}.{e.name}': dotted data references are allowed only in connectors and "
                            f"compound priority guards, not in {scope.where}")
            if problem:
                self.rep.error(self.loc.at(e, default=at), problem)
        elif isinstance(e, Unary):
            self.expr(e.operand, scope, at)
        elif isinstance(e, Binary):
            self.expr(e.left, scope, at)
            self.expr(e.right, scope, at)
        elif isinstance(e, Call):
            self.call(e, scope, at, value_needed)

    def call(self, c: Call, scope: Scope, at: Span, value_needed: bool) -> None:
        span = self.loc.at(c, default=at)
        prototypes = self.functions.get(c.function)
        if not prototypes:
            if not (self.lenient_calls or "." in c.function):
                self.rep.error(span, f"unknown extern function '{c.function}' in {scope.where}",
                               hint=suggestion(c.function, self.functions)
                               or f"declare it in the package: extern function {c.function}(...)")
        else:
            matching = [p for p in prototypes if len(p.param_types) == len(c.args)]
            if not matching:
                counts = " or ".join(sorted({str(len(p.param_types)) for p in prototypes}))
                self.rep.error(span, f"extern function '{c.function}' takes {counts} argument(s), {len(c.args)} given")
            elif value_needed and all(p.return_type is None for p in matching):
                self.rep.error(
                    span, f"extern function '{c.function}' returns nothing and cannot be used in an expression"
                )
            elif scope.guard and c.args and not any(all(p.param_const) for p in matching):
                # Verimag's rule noSideEffectInGuards: a guard must not hand data to a parameter that may change it.
                proto = matching[0]
                self.rep.error(span, f"{scope.where}: the guard calls '{c.function}', whose parameters are not all "
                                     f"const (BIP2 forbids side effects in guards)",
                               hint=f"declare it extern function {proto.return_type + ' ' if proto.return_type else ''}"
                                    f"{c.function}({', '.join('const ' + t for t in proto.param_types)})")
        for a in c.args:
            self.expr(a, scope, at)

    def stmts(self, stmts, scope: Scope, at: Span) -> None:
        for s in stmts:
            if isinstance(s, Assign):
                self.target(s.target, scope, at)
                self.expr(s.value, scope, at)
            elif isinstance(s, Do):
                self.call(s.call, scope, at, value_needed=False)
            elif isinstance(s, If):
                self.expr(s.cond, scope, at)
                self.stmts(s.then, scope, at)
                self.stmts(s.orelse, scope, at)

    def target(self, t, scope: Scope, at: Span) -> None:
        self.expr(t, scope, at)
        if isinstance(t, Var) and t.name in scope.variables and t.name not in scope.assignable:
            self.rep.error(self.loc.at(t, default=at),
                           f"cannot assign to {scope.variables[t.name]} '{t.name}' in {scope.where}")
