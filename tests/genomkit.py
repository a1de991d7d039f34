"""Helpers for tests of generated GenoM models on the engine: scripted codels, firing by label."""
from __future__ import annotations

import enginekit
from enginekit import labels  # noqa: F401 - the same helper for generated models
from runtime.codels import any_request, codel_specs
from runtime.engine import Engine


class Codels:
    """Codel externs whose next outcome a test sets by codel name (0, the first yield, by default)."""

    def __init__(self, package):
        self.specs = codel_specs(package)
        self.next: dict[str, int] = {}
        self.calls: list[str] = []

    def externs(self) -> dict:
        out = {name: (lambda spec=spec: self._call(spec)) for name, spec in self.specs.items()}
        out.update(any_request())
        return out

    def _call(self, spec) -> int:
        self.calls.append(spec.codel)
        return self.next.pop(spec.codel, 0)


def engine_for(package, root: str) -> tuple[Engine, Codels]:
    codels = Codels(package)
    return Engine(package, root, codels.externs()), codels


def walk(engine, state, *steps):
    """Fire the interactions with these labels in turn, from ``state``."""
    return enginekit.walk(engine, *steps, state=state)


def places(engine, state, atom) -> list[str]:
    return engine.describe_state(state)[atom]["places"]
