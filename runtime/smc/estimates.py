"""What runs tell about ``Pr[<= T](<> phi)``: a Chernoff–Hoeffding interval, or Wald's sequential test.

Chernoff–Hoeffding: with ``n >= ln(2/delta) / (2 epsilon^2)`` independent runs, the share of runs that reach phi
is within ``epsilon`` of the probability with confidence ``1 - delta`` (UPPAAL-SMC's and PRISM's "APMC" bound).
Wald's SPRT tests ``p >= theta`` against ``p < theta`` with an indifference region ``[theta - epsilon,
theta + epsilon]`` and both error probabilities ``delta``; it reads runs in the order of their index, so the
decision (and the run count) is the same whatever order they were computed in.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

#: Probabilities of the SPRT's hypotheses are kept this far from 0 and 1 (log of 0).
EDGE = 1e-9


def chernoff_runs(epsilon: float, delta: float) -> int:
    """Runs for ``|estimate - p| <= epsilon`` with confidence ``1 - delta``."""
    return math.ceil(math.log(2 / delta) / (2 * epsilon * epsilon))


def hoeffding_epsilon(runs: int, delta: float) -> float:
    """The half-width that ``runs`` runs give with confidence ``1 - delta``."""
    return math.sqrt(math.log(2 / delta) / (2 * runs)) if runs else 1.0


@dataclass
class Estimate:
    """``hits`` of ``runs`` runs reached phi: the estimate and its interval ``[low, high]`` (clamped to [0, 1])."""

    runs: int
    hits: int
    epsilon: float
    delta: float

    @property
    def value(self) -> float:
        return self.hits / self.runs if self.runs else 0.0

    @property
    def low(self) -> float:
        return max(0.0, self.value - self.epsilon)

    @property
    def high(self) -> float:
        return min(1.0, self.value + self.epsilon)

    def contains(self, p: float) -> bool:
        return self.low <= p <= self.high


class Sprt:
    """Wald's test of ``p >= theta`` (H0) against ``p < theta`` (H1), fed one run at a time in index order."""

    def __init__(self, theta: float, epsilon: float, delta: float) -> None:
        self.theta, self.epsilon, self.delta = theta, epsilon, delta
        self.p0 = min(theta + epsilon, 1 - EDGE)
        self.p1 = max(theta - epsilon, EDGE)
        self.hit = math.log(self.p1 / self.p0)
        self.miss = math.log((1 - self.p1) / (1 - self.p0))
        self.accept_h1 = math.log((1 - delta) / delta)
        self.accept_h0 = math.log(delta / (1 - delta))
        self.ratio = 0.0
        self.runs = self.hits = 0
        self.decision: bool | None = None  # True: p >= theta accepted; False: p < theta accepted

    def add(self, reached: bool) -> bool | None:
        """One more run; the decision once taken (later runs change nothing)."""
        if self.decision is not None:
            return self.decision
        self.runs += 1
        self.hits += reached
        self.ratio += self.hit if reached else self.miss
        if self.ratio >= self.accept_h1:
            self.decision = False
        elif self.ratio <= self.accept_h0:
            self.decision = True
        return self.decision
