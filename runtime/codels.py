"""Codels as the model sees them: extern functions with a declared, finite set of outcomes.

The generator annotates every codel extern with what it may return
(``@codel(codel="nddPlan", yields="pause::plan,arrived", throws="e_no_goal")``).
This module reads those annotations back, so that the runtime can bind real
Python codels, simulate them (a seeded random outcome among the declared ones)
or let the explorer branch on every outcome, from a ``.bip`` file alone.
"""
from __future__ import annotations

import random
from dataclasses import dataclass
from typing import Callable

from runtime.model import Package

#: The outcome a codel extern returns for a failure the description did not declare.
UNDECLARED = -1


@dataclass(frozen=True)
class CodelSpec:
    """One codel extern: its BIP name, the codel's own name, and its outcomes in order."""

    extern: str
    codel: str
    yields: tuple[str, ...]
    throws: tuple[str, ...]

    @property
    def outcomes(self) -> tuple[str, ...]:
        """Names of the outcomes by index: the yields, then ``throw <E>`` for each exception."""
        return self.yields + tuple(f"throw {e}" for e in self.throws)

    def outcome(self, name: str) -> int:
        """Index of a yield (``"pause::plan"``) or exception (``"e_no_goal"``)."""
        if name in self.yields:
            return self.yields.index(name)
        if name in self.throws:
            return len(self.yields) + self.throws.index(name)
        raise KeyError(f"codel {self.codel} declares no outcome {name!r} (declared: {', '.join(self.outcomes)})")


def _split(text: str) -> tuple[str, ...]:
    return tuple(x.strip() for x in text.split(",") if x.strip())


def codel_specs(package: Package) -> dict[str, CodelSpec]:
    """Every extern function of ``package`` annotated as a codel, by extern name."""
    out: dict[str, CodelSpec] = {}
    for f in package.extern_functions:
        for a in f.annotations:
            if a.name == "codel":
                args = a.arguments
                out[f.name] = CodelSpec(f.name, args.get("codel", f.name), _split(args.get("yields", "")),
                                        _split(args.get("throws", "")))
    return out


def simulated_codels(package: Package, seed: int | None = None,
                     failure_rate: float = 0.05) -> dict[str, Callable[[], int]]:
    """Stand-ins for every codel: a seeded random yield, now and then a declared exception.

    For running a generated controller without the robot's code; the
    outcomes are only ever ones the description declares.
    """
    rng = random.Random(seed)

    def stand_in(spec: CodelSpec) -> Callable[[], int]:
        def codel() -> int:
            if spec.throws and rng.random() < failure_rate:
                return len(spec.yields) + rng.randrange(len(spec.throws))
            return rng.randrange(len(spec.yields)) if spec.yields else UNDECLARED

        codel.__name__ = spec.codel
        return codel

    return {name: stand_in(spec) for name, spec in codel_specs(package).items()}


def any_request() -> dict[str, Callable]:
    """The acceptor's externs for an environment that may send any request at any time.

    ``request_pending`` always holds and ``take_request`` forgets nothing: the
    choice policy (or the explorer) decides when a request arrives.
    """
    return {"request_pending": lambda service: True, "take_request": lambda service: None}
