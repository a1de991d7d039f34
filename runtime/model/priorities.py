"""Priority layer: compound priorities between interactions of connectors, possibly guarded."""
from __future__ import annotations

from dataclasses import dataclass, field

from runtime.diagnostics import Span
from runtime.model.common import _span
from runtime.model.expressions import Expr


@dataclass
class PortRef:
    """``component.port`` (or a connector's exported port when ``component`` names a connector)."""

    component: str
    port: str

    def __str__(self) -> str:
        return f"{self.component}.{self.port}"


@dataclass
class InteractionPattern:
    """``conn:c.p, d.q`` (exactly those ports of connector ``conn``) or ``conn:*`` (any of its interactions).

    ``connector`` may be ``*`` for any connector, as BIP2 allows.
    """

    connector: str
    ports: list[PortRef] | None = None  # None means ``*``

    def __str__(self) -> str:
        tail = "*" if self.ports is None else ", ".join(map(str, self.ports))
        return f"{self.connector}:{tail}"


@dataclass
class Priority:
    """``priority name low < high provided (g)``: ``low`` may not fire while ``high`` is enabled."""

    name: str
    low: InteractionPattern
    high: InteractionPattern
    guard: Expr | None = None
    comment: str | None = field(default=None, compare=False)  # why the rule exists; printed as a comment
    span: Span = _span()
