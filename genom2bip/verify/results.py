"""What a check returns: a verdict, the figures of the search, the trace; printed by the command line, recorded as
JSON by whoever runs many checks.

Every result is a :class:`CheckResult` (``to_json()`` gives a plain dict with
the same keys for every kind: ``check``, ``subject``, ``verdict``, ``method``,
``limit``, ``message``, ``exhaustive``, ``figures``, ``trace``, ``notes``),
plus the keys of its kind under ``details``.  A new kind of check (a response
time: a value in ms per task, or unbounded with a lasso) is one more subclass
with its own details; traces already carry a loop and the time of each step.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from enum import Enum
from typing import Any, ClassVar


class Verdict(str, Enum):
    """The answer of a check."""

    HOLDS = "holds"
    VIOLATED = "violated"
    INCONCLUSIVE = "inconclusive"  # a limit stopped it first (``limit`` says which), or no run shows the answer
    ERROR = "error"  # the model is wrong before the property (a model error met on the way)


#: The limits that stop a search before an answer (the ``limit`` of an inconclusive result).
LIMITS = ("max-states", "max-depth", "max-memory", "interrupted", "time-limit")


@dataclass
class Figures:
    """What a check cost: states and transitions (None where the method does not count them), time, memory."""

    states: int = 0
    transitions: int | None = None
    seconds: float = 0.0
    memory: int | None = None  # bytes
    depth: int | None = None

    def to_json(self) -> dict[str, Any]:
        return asdict(self)


@dataclass
class Trace:
    """A path from the initial state: runtime steps (``label``, codel outcomes), maybe a loop, maybe times.

    ``loop``: the path then goes back to the state after step ``loop`` (0: the
    initial state) and repeats forever (a lasso).  ``ticks[i]``: the ticks
    elapsed when step ``i`` has fired (a timed trace), one tick being
    ``tick_us`` microseconds when the model says so.
    """

    steps: list = field(default_factory=list)
    loop: int | None = None
    ticks: list[int] | None = None
    tick_us: int | None = None

    def __len__(self) -> int:
        return len(self.steps)

    def to_json(self) -> dict[str, Any]:
        steps = []
        for k, step in enumerate(self.steps):
            item: dict[str, Any] = {"label": step.label, "outcomes": list(getattr(step, "outcome_names", ()))}
            if self.ticks is not None:
                item["tick"] = self.ticks[k]
                item["time_ms"] = self.ticks[k] * self.tick_us / 1000 if self.tick_us else None
            steps.append(item)
        return {"steps": steps, "loop": self.loop, "timed": self.ticks is not None,
                "tick_us": self.tick_us if self.ticks is not None else None}


def timed(steps, tick_us: int | None) -> Trace:
    """A trace whose steps carry their time: the ticks (``tick`` interactions) fired up to each step."""
    from genom2bip.build.timed import TICK

    ticks, now = [], 0
    for step in steps:
        now += step.label == TICK
        ticks.append(now)
    return Trace(list(steps), ticks=ticks, tick_us=tick_us)


@dataclass
class CheckResult:
    """One check's answer: verdict, who decided it, what stopped it, its figures, its trace, the notes on the way."""

    check: ClassVar[str] = "check"

    subject: str
    verdict: Verdict
    figures: Figures = field(default_factory=Figures)
    trace: Trace | None = None
    method: str = ""
    limit: str = ""  # an inconclusive verdict: the limit that stopped the search (LIMITS), or "" when unknown
    message: str = ""  # what the checker said beside the verdict (the model error, why it stopped)
    exhaustive: bool = True  # False: a lossy store or bitstate search may have missed states
    notes: list[str] = field(default_factory=list)
    summary: str = ""  # the search's figures in one line, as the command line prints them (not in JSON)

    def details(self) -> dict[str, Any]:
        """The keys of this kind of check."""
        return {}

    def to_json(self) -> dict[str, Any]:
        """A plain dict (JSON types only), with the same keys for every kind of check."""
        return {"check": self.check, "subject": self.subject, "verdict": self.verdict.value, "method": self.method,
                "limit": self.limit or None, "message": self.message, "exhaustive": self.exhaustive,
                "figures": self.figures.to_json(), "trace": self.trace.to_json() if self.trace is not None else None,
                "notes": list(self.notes), "details": self.details()}


@dataclass
class ModelError:
    """A model error met by a search (non-determinism, 1-safety, a domain left), the state and a trace to it."""

    message: str
    state: int
    trace: Trace

    def to_json(self) -> dict[str, Any]:
        return {"message": self.message, "state": self.state, "trace": self.trace.to_json()}


@dataclass
class Deadlock:
    """A reachable state without any enabled interaction: its number, a trace, the state and the atoms that moved."""

    state: int
    trace: Trace
    text: str = ""  # the state, one line per atom (the engine's format)
    moved: list[str] = field(default_factory=list)  # ``atom: PLACE`` of the atoms not in their initial places
    message: str = ""  # what the search said of it (SPIN's "invalid end state")

    def to_json(self) -> dict[str, Any]:
        return {"state": self.state, "trace": self.trace.to_json(), "text": self.text, "moved": list(self.moved),
                "message": self.message}


@dataclass
class DeadlockResult(CheckResult):
    """Deadlock freedom by a search: every deadlock found, each with a trace (``trace``: the first one's)."""

    check: ClassVar[str] = "deadlock"

    deadlocks: list[Deadlock] = field(default_factory=list)
    model_error: ModelError | None = None
    complete: bool = True
    shortest: bool = True  # each trace is a shortest one
    reported: int | None = None  # deadlocks the search counted, where it keeps fewer traces (SPIN's errors)

    def details(self) -> dict[str, Any]:
        return {"deadlocks": [d.to_json() for d in self.deadlocks], "complete": self.complete,
                "shortest": self.shortest, "reported": self.reported,
                "model_error": self.model_error.to_json() if self.model_error is not None else None}


@dataclass
class PropertyResult(CheckResult):
    """A property (MCL-style, docs/verification/properties.md): ``evidence`` says what ``trace`` is."""

    check: ClassVar[str] = "property"

    name: str = ""
    evidence: str = ""  # "counterexample", "witness" or ""

    @property
    def word(self) -> str:
        """The verdict as the command line prints it (a model error is called so)."""
        return "model error" if self.verdict is Verdict.ERROR else self.verdict.value

    def details(self) -> dict[str, Any]:
        return {"name": self.name, "evidence": self.evidence}


@dataclass
class ObserverResult(CheckResult):
    """A timing observer of a timed model (a task's period, a latency): is its ERROR place reachable?"""

    check: ClassVar[str] = "observer"

    observer: str = ""  # the observer atom's path
    kind: str = ""  # "overrun" or "latency"
    bound_ticks: int = 0
    tick_us: int | None = None

    @property
    def bound_ms(self) -> float | None:
        return self.bound_ticks * self.tick_us / 1000 if self.tick_us else None

    def details(self) -> dict[str, Any]:
        return {"observer": self.observer, "kind": self.kind, "bound_ticks": self.bound_ticks,
                "bound_ms": self.bound_ms}


@dataclass
class Refuted:
    """A potential deadlock of the compositional analysis that invariants or a trap refuted."""

    method: str
    reason: str


@dataclass
class Candidate:
    """A potential deadlock left for the explorer: its verdict (reachable, unreachable, unknown) and why."""

    verdict: str
    method: str
    reason: str
    state: list[str] = field(default_factory=list)  # one line per atom
    waits: list[list[str]] = field(default_factory=list)  # wait-for cycles, atom names
    trace: Trace | None = None

    def to_json(self) -> dict[str, Any]:
        return {"verdict": self.verdict, "method": self.method, "reason": self.reason, "state": list(self.state),
                "waits": [list(c) for c in self.waits],
                "trace": self.trace.to_json() if self.trace is not None else None}


@dataclass
class CompositionalResult(CheckResult):
    """Deadlock freedom by invariants and SAT (D-Finder style): the potential deadlocks and the candidates' fates."""

    check: ClassVar[str] = "deadlock"

    potentials: int = 0
    refuted: list[Refuted] = field(default_factory=list)
    candidates: list[Candidate] = field(default_factory=list)
    reused_traps: int = 0
    listing_complete: bool = True
    explored: bool = False  # an exhaustive exploration decided the candidates past the listing too
    analysis: Any = field(default=None, repr=False, compare=False)  # the analysis itself (not in JSON, not pickled)

    def __getstate__(self) -> dict[str, Any]:
        return {**self.__dict__, "analysis": None}  # a result travels (to a worker's caller); the analysis stays

    def details(self) -> dict[str, Any]:
        return {"potentials": self.potentials, "refuted": [asdict(r) for r in self.refuted],
                "candidates": [c.to_json() for c in self.candidates], "reused_traps": self.reused_traps,
                "listing_complete": self.listing_complete, "explored": self.explored}
