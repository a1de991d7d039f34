"""How a check searches (limits, engine, store, SPIN's and the compositional analysis's settings), and the listener
that hears it on the way (progress lines, notes, phases, rounds).
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

from runtime.native.stores import DEFAULT_BITS

#: Share of the machine's memory a search may use when ``max_memory_mb`` is not given.
MEMORY_SHARE = 0.5
#: Engines: our explorer compiled to C (Python where it cannot be compiled), the Python one, SPIN.
ENGINES = ("compiled", "python", "spin")


def default_memory() -> int | None:
    """Half of the physical memory, in bytes (None where the system does not say)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") * MEMORY_SHARE)
    except (ValueError, OSError, AttributeError):
        return None


@dataclass
class SearchOptions:
    """Plain settings of every check (the options of ``genom2bip verify``); the defaults are the command's."""

    engine: str = "compiled"  # ENGINES ("explore" is read as "compiled")
    max_states: int | None = None
    max_depth: int | None = None
    max_memory_mb: int | None = None  # None: half the machine's memory
    time_limit: float | None = None  # seconds a zone search may take; past them it stops and says what it found
    dfs: bool = False
    requests: int | None = None  # each service receives at most N requests (None: any number, one at a time)
    reduce: bool = True  # reset dead variables
    externs: str | None = None  # a Python module binding extern functions that are not codels
    # the compiled search
    por: bool = False
    workers: int = 1  # 0: one per core
    store: str = "exact"  # "exact", "compact" or "bitstate"
    bits: int = DEFAULT_BITS  # the bitstate store's 2^bits bits
    # SPIN
    spin_cores: int = 1
    spin_bitstate: bool = False
    spin_hash_bits: int = 27
    spin_swarm: int | None = None
    spin_dir: str | None = None
    # the compositional analysis and localization
    solver: str | None = None  # a python-sat solver; None: the analysis's default
    check_states: int | None = None  # states the explorer may visit to decide each candidate

    @property
    def compiled(self) -> bool:
        return self.engine in ("compiled", "explore")

    @property
    def max_bytes(self) -> int | None:
        return self.max_memory_mb * 1024 * 1024 if self.max_memory_mb is not None else default_memory()

    def search(self) -> dict[str, Any]:
        """The keyword arguments of the compiled search's ``explore``: threads, store, bits."""
        return {"workers": self.workers or os.cpu_count() or 1, "store": self.store, "bits": self.bits}


class Listener:
    """What a check says while it runs; this one hears nothing (a job of a campaign), the command line prints.

    Notes are also kept in the results (``notes``); this is for a terminal that shows them as they come.
    """

    def progress(self):
        """A progress display for one search (:class:`runtime.explore.Progress`)."""
        from runtime.explore.progress import null_progress
        return null_progress()

    def note(self, text: str) -> None:
        """A remark on how the check runs (a fallback, a reduction, a lossy store)."""

    def found(self, result) -> None:
        """A verdict known while the search goes on (a timing observer violated, with its trace)."""

    def so_far(self, text: str) -> None:
        """What a running search has found so far (the largest response times reached: lower bounds)."""

    def unbounded(self, max_bytes: int, bounds: str = "--max-states or --max-depth") -> None:
        """A search starts with none of ``bounds`` (its options): it runs until complete or ``max_bytes``."""

    def phase(self, line: str) -> None:
        """A phase of the compositional analysis ended."""

    def round(self, number: int, round_) -> None:
        """A localization round ended (:class:`runtime.localize.refine.Round`)."""


class Notes:
    """The notes of one check: kept for its result and told to the listener as they come."""

    def __init__(self, listener: Listener) -> None:
        self.listener, self.lines = listener, []

    def __call__(self, text: str) -> None:
        self.lines.append(text)
        self.listener.note(text)
