"""Errors of the engine: bad root or structure (before running), missing externs, and model errors at a step.

All derive from :class:`EngineError` so that a command line can turn any of
them into a one-paragraph message and a non-zero exit status.
"""
from __future__ import annotations

from runtime.errors import Genom2bipError


class EngineError(Genom2bipError):
    """Base class: anything the engine refuses, with a message meant for a user."""


class FlattenError(EngineError):
    """The package cannot be instantiated from the root spec (unknown type, arity, dangling port...)."""


class ExternError(EngineError):
    """Extern functions the model calls have no Python binding, or a binding is not callable."""

    def __init__(self, message: str, missing: tuple[str, ...] = ()) -> None:
        super().__init__(message)
        self.missing = missing


class ModelError(EngineError):
    """The model misbehaves at a step: non-determinism, a 1-safety violation, a priority cycle...

    Carries the names a user needs to find the fault: atom instance, port,
    places and transitions (as text), besides the message.
    """

    def __init__(self, message: str, *, atom: str | None = None, port: str | None = None,
                 places: tuple[str, ...] = (), transitions: tuple[str, ...] = ()) -> None:
        self.message = message
        self.atom = atom
        self.port = port
        self.places = tuple(places)
        self.transitions = tuple(transitions)
        super().__init__(self.render())

    def render(self) -> str:
        parts = [self.message]
        if self.atom is not None:
            parts.append(f"atom {self.atom}")
        if self.port is not None:
            parts.append(f"port {self.port}")
        if self.places:
            parts.append("places " + ", ".join(self.places))
        if self.transitions:
            parts.append("transitions: " + "; ".join(self.transitions))
        return " | ".join(parts)
