"""What a step fires: an :class:`Interaction` (a connector's set of atom ports, or one lone atom port).

Interactions are identified by ``(source, mask)``: ``source`` numbers the
top-level connectors then the lone (non-exported) atom ports of the flat
system, ``mask`` has one bit per atom port under that connector (its leaves,
in parameter order, through sub-connectors).  Both are stable for one model,
so ``index`` is too; equality and hashing use it alone.
"""
from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Interaction:
    """One interaction of the flat system, as listed by ``Engine.enabled`` and fired by ``Engine.fire``."""

    index: int
    source: int = field(compare=False)
    mask: int = field(compare=False)
    connector: str | None = field(compare=False)      # dotted path; None for a lone atom port
    ports: tuple[str, ...] = field(compare=False)     # "atom.port" of every atom port taking part
    label: str = field(compare=False)
    # (connector id, parameter mask) of every connector node taking part: what priority patterns match
    parts: tuple[tuple[int, int], ...] = field(default=(), compare=False, repr=False)

    def __str__(self) -> str:
        return self.label


def interaction_label(base: str | None, ports: list[str], complete: bool) -> str:
    """The one rule that names interactions in traces, LTS exports and property files.

    A lone atom port is ``atom.port``; an interaction of a connector is the
    connector's label (its ``@label(name=...)`` annotation, else its dotted path)
    when all of the connector's ports take part, else ``label[a.p,b.q]`` with
    the ports named relative to the compound that declares the connector.
    """
    if base is None:
        return ports[0]
    if complete:
        return base
    return f"{base}[{','.join(ports)}]"
