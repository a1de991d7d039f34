"""Codel durations drawn in their ``[best, worst]`` interval: uniform by default, triangular or truncated normal.

A duration is drawn as a real number of microseconds, then rounded *up* to the model's ticks: a codel drawn to
take 6.3 ms ends at the first tick at or after it, so ``P(duration > k ticks)`` is the continuous distribution's
exactly at every tick boundary (a codel in ``[0, 10]`` ms is over 6 ms with probability 0.4 at any resolution
that divides 6 ms).
"""
from __future__ import annotations

import math
import random
from dataclasses import dataclass

#: The distributions a platform file may name for a codel.
DISTRIBUTIONS = ("uniform", "triangular", "normal")
#: A truncated normal draw is retried this many times before it is clamped to the interval.
NORMAL_TRIES = 32


@dataclass(frozen=True)
class Distribution:
    """How a codel's duration is drawn in its interval: ``uniform``; ``triangular`` with its ``mode_us``;
    ``normal`` with ``mean_us`` and ``sd_us``, truncated to the interval."""

    kind: str = "uniform"
    mode_us: float | None = None
    mean_us: float | None = None
    sd_us: float | None = None

    def draw_us(self, rng: random.Random, lo_us: float, hi_us: float) -> float:
        """A duration in ``[lo_us, hi_us]``."""
        if hi_us <= lo_us:
            return lo_us
        if self.kind == "triangular":
            mode = min(max(self.mode_us if self.mode_us is not None else (lo_us + hi_us) / 2, lo_us), hi_us)
            return rng.triangular(lo_us, hi_us, mode)
        if self.kind == "normal":
            mean = self.mean_us if self.mean_us is not None else (lo_us + hi_us) / 2
            sd = self.sd_us if self.sd_us else (hi_us - lo_us) / 6
            for _ in range(NORMAL_TRIES):
                value = rng.gauss(mean, sd)
                if lo_us <= value <= hi_us:
                    return value
            return min(max(mean, lo_us), hi_us)
        return rng.uniform(lo_us, hi_us)

    def draw_ticks(self, rng: random.Random, lo: int, hi: int, tick_us: float) -> int:
        """A duration in ticks within ``[lo, hi]``: drawn in µs over ``[lo, hi]`` ticks, rounded up."""
        value = self.draw_us(rng, lo * tick_us, hi * tick_us)
        return min(max(math.ceil(value / tick_us - 1e-9), lo), hi)

    def describe(self) -> str:
        if self.kind == "triangular":
            return f"triangular (mode {self.mode_us / 1000:g} ms)" if self.mode_us is not None else "triangular"
        if self.kind == "normal":
            return f"normal (mean {(self.mean_us or 0) / 1000:g} ms, sd {(self.sd_us or 0) / 1000:g} ms)"
        return "uniform"


UNIFORM = Distribution()
