"""Which enabled interaction the controller fires next, and when it may sleep instead.

A due period goes first (earliest deadline), then an untimed interaction
(the least recently fired, or a random one with a seed), then a period of
an untimed task only when one of its codels would run in it; a period not
yet due tells how long the engine thread may sleep.
"""
from __future__ import annotations

import random

from runtime.controller.meaning import Meanings, StepInfo
from runtime.engine import Engine, Interaction

#: (what to fire, its meaning, when the next period is due, services whose queued request can be answered now)
Chosen = tuple[Interaction | None, StepInfo | None, float | None, set[str]]


class Choice:
    """The choice among ready interactions; it remembers when each fired, so that no module starves the others."""

    def __init__(self, engine: Engine, meanings: Meanings, seed: int | None = None) -> None:
        self.engine = engine
        self.meanings = meanings
        self.rng = random.Random(seed) if seed is not None else None
        self.last: dict[int, int] = {}  # interaction index -> step when it last fired (fair choice)
        self.work: dict[tuple, bool] = {}  # (untimed period, state) -> a codel would run in it
        self.atoms: dict[int, frozenset[str]] = {}  # interaction index -> the atoms taking part

    def choose(self, state: tuple, now: float, step: int, frozen: set[str] | frozenset = frozenset()) -> Chosen:
        """A due period first (earliest deadline), else an untimed interaction, else a period with work to do.

        Interactions of ``frozen`` atoms (waiting for a detached codel) are left out.
        """
        due: tuple[float, Interaction, StepInfo] | None = None
        ready: list[tuple[Interaction, StepInfo]] = []
        lazy: list[tuple[Interaction, StepInfo]] = []
        wake_at = None
        answerable: set[str] = set()  # services whose queued request can be accepted or refused now
        cache, meaning = self.meanings.cache, self.meanings.info
        for inter in self.engine.enabled(state):
            if frozen and self._frozen(inter, frozen):
                continue
            info = cache.get(inter.index) or meaning(inter)
            if info.service is not None and info.kind in ("trigger", "refuse"):
                answerable.add(info.service.label)
            if info.opens is not None:
                d = info.opens.deadline
                if d <= now:
                    if due is None or d < due[0]:
                        due = (d, inter, info)
                elif wake_at is None or d < wake_at:
                    wake_at = d
            elif info.lazy_exec is not None:
                lazy.append((inter, info))
            else:
                ready.append((inter, info))
        if due is not None:
            return due[1], due[2], wake_at, answerable
        if ready:
            if self.rng is not None:
                inter, info = ready[self.rng.randrange(len(ready))]
            else:  # the least recently fired: a module stuck in a loop of codels cannot starve the others
                last = self.last
                inter, info = min(ready, key=lambda r: last.get(r[0].index, -1))
            self.last[inter.index] = step
            return inter, info, wake_at, answerable
        for inter, info in lazy:
            if self.has_work(state, inter, info):
                return inter, info, wake_at, answerable
        return None, None, wake_at, answerable

    def _frozen(self, inter: Interaction, frozen: set[str] | frozenset) -> bool:
        atoms = self.atoms.get(inter.index)
        if atoms is None:
            atoms = self.atoms[inter.index] = frozenset(p.rsplit(".", 1)[0] for p in inter.ports)
        return not atoms.isdisjoint(frozen)

    def has_work(self, state: tuple, inter: Interaction, info: StepInfo) -> bool:
        """Would opening this untimed period let one of its task's codels run?  (Memoised by state.)"""
        key = (inter.index, state)
        got = self.work.get(key)
        if got is None:
            after = self.engine.fire(state, inter)
            got = self.work[key] = any(info.lazy_exec in j.ports for j in self.engine.enabled(after))
            if len(self.work) > 50_000:
                self.work.clear()
        return got
