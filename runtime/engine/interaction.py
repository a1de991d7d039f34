"""What a step fires: an :class:`Interaction` (a connector's set of atom ports, or one lone atom port).

Interactions are identified by ``(source, mask)``: ``source`` numbers the
top-level connectors then the lone (non-exported) atom ports of the flat
system, ``mask`` has one bit per atom port under that connector (its leaves,
in parameter order, through sub-connectors).  Both are stable for one model,
so ``index`` is too; equality and hashing use it alone.  The engine creates
each interaction once; its ports, label and parts are worked out on first use
(a broadcast has many interactions, and exploration mostly needs the index).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable


@dataclass(frozen=True, repr=False)
class Interaction:
    """One interaction of the flat system, as listed by ``Engine.enabled`` and fired by ``Engine.fire``.

    ``connector`` is the dotted path of the top connector (None for a lone
    atom port); ``ports`` the ``atom.port`` names taking part; ``label`` what
    traces print; ``parts`` the ``(connector id, parameter mask)`` of every
    connector node taking part, which compound priorities match.
    """

    index: int
    source: int = field(compare=False)
    mask: int = field(compare=False)
    connector: str | None = field(compare=False)
    describe: Callable[["Interaction"], tuple] = field(compare=False)

    @cached_property
    def _info(self) -> tuple[tuple[str, ...], str, tuple[tuple[int, int], ...]]:
        return self.describe(self)

    @property
    def ports(self) -> tuple[str, ...]:
        return self._info[0]

    @property
    def label(self) -> str:
        return self._info[1]

    @property
    def parts(self) -> tuple[tuple[int, int], ...]:
        return self._info[2]

    def __str__(self) -> str:
        return self.label

    def __repr__(self) -> str:
        return f"Interaction({self.index}, {self.label!r})"


def interaction_label(base: str | None, ports: list[str], complete: bool, named: bool = False) -> str:
    """The one rule that names interactions in traces, LTS exports and property files.

    A lone atom port is ``atom.port``.  A connector named by a
    ``@label(name=...)`` annotation gives that name to every interaction it
    has (``NDD.Stop:start`` whether or not a running GoTo is aborted with it):
    the generator names connectors after what they mean; only alternatives
    through merged exports keep the port suffix.  Otherwise an
    interaction is the connector's dotted path when all its ports take part,
    else ``path[a.p,b.q]`` with the ports named relative to the compound that
    declares the connector.
    """
    if base is None:
        return ports[0]
    if complete or named:
        return base
    return f"{base}[{','.join(ports)}]"
