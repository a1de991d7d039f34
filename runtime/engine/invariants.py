"""Atom invariants of an untimed model: checked after the initial transitions and after every step.

``invariant n [at P | from P, Q] provided (g)`` must hold whenever it is in
force (see :class:`runtime.model.timing.Invariant`).  A violation is a model
error, worded and numbered (exit status 5) as the Verimag reference engine
does; the run, the explorer and the trace replay meet it through
``Engine.initial_state``/``Engine.fire``, so they agree on it.  Timed models
check their invariants in runtime/engine/timed.py instead.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

from runtime.engine.cexpr import Name, Scope, expr as compile_expr
from runtime.engine.errors import ModelError
from runtime.model.timing import Invariant


class InvariantViolation(ModelError):
    """An atom invariant is false in the state a step (or the initial transitions) reached."""

    def __init__(self, invariant: str, atom: str, after: str | None = None) -> None:
        self.invariant = invariant
        self.after = after
        super().__init__(f"the invariant {invariant} of component {atom} has been violated!", atom=None)
        self.atom = atom

    def render(self) -> str:
        return self.message + (f" (after {self.after})" if self.after else "")


def compile_state_expr(flat, namespace: dict[str, Any], fa, e) -> Callable[[tuple], Any]:
    """``e``, an expression over the variables of flat atom ``fa``, as a function of the engine's state."""
    scope = Scope(where=f"atom {fa.name} ({fa.type.name})", constants=fa.constants,
                  externs={f.name: f.return_type for f in flat.package.extern_functions})
    for d in fa.variables:
        scope.variables[d.name] = Name(f"s[{fa.slot(d.name)}]", d.type)
    src, _ = compile_expr(e, scope)
    return eval(f"lambda s: {src}", namespace)  # noqa: S307 - our own compiled guard


@dataclass(frozen=True)
class _Check:
    atom: str
    offset: int
    mask: int
    invariant: Invariant
    holds: Callable[[tuple], Any]


class Invariants:
    """Every invariant of the model's atoms, in atom then declaration order (the first false one is reported)."""

    def __init__(self, flat, namespace: dict[str, Any]) -> None:
        self.checks = [
            _Check(fa.name, fa.offset, fa.place_mask(inv.places) if inv.places else 0, inv,
                   compile_state_expr(flat, namespace, fa, inv.guard))
            for fa in flat.atoms for inv in fa.type.invariants
        ]

    def __bool__(self) -> bool:
        return bool(self.checks)

    def check(self, state: tuple, after: str | None = None) -> tuple:
        """``state`` itself, or :class:`InvariantViolation` for the first invariant in force that is false."""
        for c in self.checks:
            if c.invariant.in_force(state[c.offset], c.mask) and not c.holds(state):
                raise InvariantViolation(c.invariant.name, c.atom, after)
        return state

    def guard_fire(self, fire: Callable[..., tuple], label: Callable[[int], str]) -> Callable[..., tuple]:
        """``fire(state, mask, record)`` of one source, followed by the check (``label(mask)`` names the step)."""
        check = self.check

        def fire_checked(state, mask, record):
            return check(fire(state, mask, record), label(mask))

        return fire_checked
