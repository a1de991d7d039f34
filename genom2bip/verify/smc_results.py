"""What statistical model checking returns: each observer's estimate (a :class:`CheckResult`), the response-time
distributions, the report of one check, and the report as one result (a campaign's job)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

from genom2bip.verify.results import CheckResult, Figures, Verdict
from runtime.smc import Estimate

#: Percentile printed beside the mean and the maximum.
PERCENTILE = 99


@dataclass
class SmcResult(CheckResult):
    """``Pr[<= T](<> phi)`` of one observer: its estimate and interval, or Wald's decision against a threshold."""

    check: ClassVar[str] = "smc"

    observer: str = ""
    runs: int = 0
    hits: int = 0
    epsilon: float = 0.0
    delta: float = 0.0
    threshold: float | None = None
    decision: bool | None = None  # Wald: True Pr >= threshold accepted, False Pr < threshold, None undecided
    seed: int = 0
    horizon_ms: float = 0.0
    first_run: int | None = None  # the first run (index) that reached phi
    first_ms: float | None = None  # when it reached it

    @property
    def estimate(self) -> Estimate:
        return Estimate(self.runs, self.hits, self.epsilon, self.delta)

    def details(self) -> dict[str, Any]:
        e = self.estimate
        return {"observer": self.observer, "runs": self.runs, "hits": self.hits, "estimate": e.value,
                "low": e.low, "high": e.high, "epsilon": self.epsilon, "delta": self.delta,
                "threshold": self.threshold, "decision": self.decision, "seed": self.seed,
                "horizon_ms": self.horizon_ms, "first_run": self.first_run, "first_ms": self.first_ms}


@dataclass
class ResponseDistribution:
    """The response times of one task or service seen over the runs: ticks -> times seen."""

    owner: str
    kind: str  # "task" or "service"
    counts: dict[int, int]
    tick_us: int

    @property
    def samples(self) -> int:
        return sum(self.counts.values())

    def ms(self, ticks: float) -> float:
        return ticks * self.tick_us / 1000

    @property
    def mean_ms(self) -> float | None:
        n = self.samples
        return self.ms(sum(t * c for t, c in self.counts.items()) / n) if n else None

    def percentile_ms(self, q: float = PERCENTILE) -> float | None:
        """The nearest-rank percentile."""
        n = self.samples
        if not n:
            return None
        rank, seen = math.ceil(q / 100 * n), 0
        for t in sorted(self.counts):
            seen += self.counts[t]
            if seen >= rank:
                return self.ms(t)
        return self.ms(max(self.counts))

    @property
    def max_ms(self) -> float | None:
        return self.ms(max(self.counts)) if self.counts else None

    def to_json(self) -> dict[str, Any]:
        return {"owner": self.owner, "kind": self.kind, "samples": self.samples, "mean_ms": self.mean_ms,
                f"p{PERCENTILE}_ms": self.percentile_ms(), "max_ms": self.max_ms,
                "histogram_ms": {f"{self.ms(t):g}": c for t, c in sorted(self.counts.items())}}


@dataclass
class SmcReport:
    """Every estimate of one SMC check, the response-time distributions, and what the runs cost."""

    results: list[SmcResult]
    responses: list[ResponseDistribution]
    runs: int  # runs read (Wald's test may stop earlier for some observers)
    seconds: float
    steps: int
    ticks: int
    ends: dict[str, int]
    method: str  # "Chernoff-Hoeffding" or "Wald SPRT"
    runner: str
    workers: int
    seed: int
    horizon_ms: float
    tick_us: int
    notes: list[str] = field(default_factory=list)
    stopped: str = ""  # "interrupted": Ctrl-C stopped it; the estimates are those of the runs read

    @property
    def runs_per_second(self) -> float:
        return self.runs / self.seconds if self.seconds else 0.0

    def to_json(self) -> dict[str, Any]:
        return {"method": self.method, "runs": self.runs, "seconds": self.seconds, "steps": self.steps,
                "runs_per_second": self.runs_per_second, "ends": self.ends, "runner": self.runner,
                "workers": self.workers, "seed": self.seed, "horizon_ms": self.horizon_ms, "tick_us": self.tick_us,
                "results": [r.to_json() for r in self.results], "responses": [r.to_json() for r in self.responses],
                "notes": self.notes, "stopped": self.stopped or None}


@dataclass
class SmcSummary(CheckResult):
    """A whole SMC report as one check's result (a campaign's job): violated when a run reached an observer's
    ERROR, inconclusive when Wald's test stayed undecided, else holds; ``details`` has every estimate."""

    check: ClassVar[str] = "smc"

    report: dict[str, Any] = field(default_factory=dict)

    @property
    def estimates(self) -> list[dict[str, Any]]:
        return self.report.get("results", [])

    def details(self) -> dict[str, Any]:
        return self.report


def summary(report: SmcReport, subject: str) -> SmcSummary:
    """``report`` as one :class:`~genom2bip.verify.CheckResult`."""
    verdicts = {r.verdict for r in report.results}
    verdict = (Verdict.VIOLATED if Verdict.VIOLATED in verdicts else
               Verdict.INCONCLUSIVE if Verdict.INCONCLUSIVE in verdicts else Verdict.HOLDS)
    return SmcSummary(subject, verdict, Figures(states=0, transitions=report.steps, seconds=report.seconds),
                      method="smc", exhaustive=False, notes=list(report.notes), report=report.to_json())
