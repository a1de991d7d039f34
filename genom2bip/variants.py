"""Variants of a description for a sweep: every codel's WCET scaled, a task's period replaced.

A campaign asks "how much WCET margin is left?" or "which period breaks it?"
by building the same description with other timing figures; the model is then
built as usual (``genom2bip.verify.build_model(..., variant=...)``), so the
tick, the observers' bounds and the .bip text all follow the new figures.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass

from genom2bip.ir import Description, Duration
from genom2bip.loading import InputError


#: The largest WCET factor: past it a WCET is no longer one of a robot's codels, and the search follows every
#: period of the other tasks through it.
MAX_WCET_SCALE = 1000


@dataclass(frozen=True)
class Variant:
    """What changes: every WCET (declared, and the default of those that declare none) times ``wcet_scale``,
    and the period of each task named ``Module.task`` (µs)."""

    wcet_scale: float = 1.0
    periods: tuple[tuple[str, int], ...] = ()

    @property
    def identity(self) -> bool:
        return self.wcet_scale == 1.0 and not self.periods


def scaled(us: int | None, scale: float) -> int | None:
    """A duration in µs times ``scale``, rounded to the µs (None stays None)."""
    return None if us is None else round(us * scale)


def apply_variant(description: Description, variant: Variant) -> Description:
    """A copy of ``description`` with the variant's figures; :class:`InputError` names a task it cannot change."""
    if variant.identity:
        return description
    if not 0 <= variant.wcet_scale <= MAX_WCET_SCALE:  # NaN too
        raise InputError([f"wcet scale {variant.wcet_scale:g}: a factor from 0 to {MAX_WCET_SCALE} expected"])
    out = copy.deepcopy(description)
    tasks = {f"{c.name}.{t.name}": t for c in out.components for t in c.tasks}
    wrong = []
    for name, us in variant.periods:
        task = tasks.get(name)
        if task is None:
            wrong.append(f"period of {name}: no task {name} (tasks: {', '.join(sorted(tasks)) or 'none'})")
        elif task.period is None:
            wrong.append(f"period of {name}: the task is not periodic")
        elif us <= 0:
            wrong.append(f"period of {name}: a positive duration expected")
        else:
            task.period = Duration(us / 1e6, f"{us / 1000:g} ms")
    if wrong:
        raise InputError(wrong)
    if variant.wcet_scale != 1.0:
        seen: set[int] = set()  # a codel shared by two lists is scaled once
        for component in out.components:
            codels = [c for t in component.tasks for c in t.codels]
            codels += [c for s in component.services for c in (*s.codels, *([s.validate] if s.validate else []))]
            for codel in codels:
                if codel.wcet is not None and id(codel) not in seen:
                    seen.add(id(codel))
                    seconds = codel.wcet.seconds * variant.wcet_scale
                    codel.wcet = Duration(seconds, f"{seconds * 1000:g} ms")
    return out
