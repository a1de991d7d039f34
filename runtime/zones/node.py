"""A stored symbolic state of a zone search: its discrete state, its zone and how it was reached (for traces)."""
from __future__ import annotations

import numpy as np

#: The key of ``ZoneResult.violations`` under which the first node at an explorer's goal is kept.
GOAL = -1


class Node:
    """A stored symbolic state: its discrete state, zone, and how it was reached (for traces).

    Zones are kept in single precision (their bounds are integers far below 2**24, and ``inf``), half the
    memory of a long search; ``zone`` and ``own`` give them back as the double matrices dbm.py works on.
    """

    __slots__ = ("state", "_zone", "parent", "via", "guard", "grown", "covered", "by", "_own", "members",
                 "expanded", "dead", "skipped", "covers")

    def __init__(self, state: tuple, zone: np.ndarray | None, parent: int, via: int, guard: list,
                 grown: bool) -> None:
        self.state = state
        self.zone = zone  # None: a step into a zone another node covers (that node's zone stands for it)
        self.parent = parent
        self.via = via  # interaction index of the erased engine, -1 for an initial state
        self.guard = guard  # the bounds the step added to its parent's zone (before resets)
        self.grown = grown  # time may have passed after the step (else the zone is where it cannot)
        self.covered = False  # a larger zone of the same discrete state came later
        self.by = -1  # the node whose zone covers this one
        self.own = None  # the step's own zone when others merged into ``zone`` (their union is one)
        self.members: list[int] = []  # the nodes merged into this one
        self.expanded = False  # its successors were computed
        self.dead = False  # pruned: below a node that a larger zone covered after it was expanded
        self.skipped = False  # taken from the queue while dead (queued again if it lives again)
        self.covers = False  # a newcomer's zone was found inside its own (it is never pruned)

    @property
    def zone(self) -> np.ndarray | None:
        return _double(self._zone)

    @zone.setter
    def zone(self, m: np.ndarray | None) -> None:
        self._zone = _single(m)

    @property
    def reached(self) -> np.ndarray | None:
        """The zone the step itself reached: ``own`` when others were merged into ``zone``."""
        return _double(self._own if self._own is not None else self._zone)

    @property
    def stored(self) -> np.ndarray | None:
        """The zone as kept (single precision): enough to compare two zones."""
        return self._zone

    @property
    def own(self) -> np.ndarray | None:
        return _double(self._own)

    @own.setter
    def own(self, m: np.ndarray | None) -> None:
        self._own = _single(m)


def _single(m: np.ndarray | None) -> np.ndarray | None:
    """A zone as a node keeps it (single precision)."""
    return None if m is None else m.astype(np.float32)


def _double(m: np.ndarray | None) -> np.ndarray | None:
    """A kept zone as dbm.py works on it (double precision)."""
    return None if m is None else m.astype(np.float64)
