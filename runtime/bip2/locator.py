"""Where each part of a model was read from, so that checks can point at the offending name.

The model keeps one span per declaration; references (a port named in a
transition, ``c.p`` in a connector, a variable in a guard) have none, so the
reader notes them here, keyed by the object that holds them.
"""
from __future__ import annotations

from runtime.diagnostics import NOWHERE, Span
from runtime.model.common import source_span


class Locator:
    """Spans of model objects and of their fields, filled by the reader."""

    def __init__(self) -> None:
        self._spans: dict[tuple[int, object], Span] = {}
        self._keep: list[object] = []  # keeps noted objects alive so that their ids stay unique

    def note(self, obj: object, span: Span, key: object = None) -> None:
        self._spans[(id(obj), key)] = span
        self._keep.append(obj)

    def at(self, obj: object, key: object = None, default: Span | None = None) -> Span:
        """The span noted for ``obj`` (and ``key``), else the object's own span, else the description line
        its ``@source`` names (a generated model), else ``default``."""
        span = self._spans.get((id(obj), key))
        if span is None and key is not None:
            span = self._spans.get((id(obj), None))
        if span is None:
            own = getattr(obj, "span", None)
            if isinstance(own, Span) and own is not NOWHERE and own.line > 0:
                span = own
        if span is None and isinstance(getattr(obj, "annotations", None), list):
            span = source_span(obj.annotations)
        return span or default or NOWHERE
