"""Deadlock freedom by the compositional analysis (component and interaction invariants, DIS, SAT: D-Finder style),
its candidates decided by the explorer.  The analysis lives in ``runtime.compositional``.
"""
from __future__ import annotations

import time

from genom2bip.verify.model import Model
from genom2bip.verify.options import Listener, SearchOptions
from genom2bip.verify.results import Candidate, CompositionalResult, Figures, Refuted, Trace, Verdict

#: The analysis's verdict as a result's.
VERDICTS = {"deadlock-free": Verdict.HOLDS, "deadlock": Verdict.VIOLATED, "unknown": Verdict.INCONCLUSIVE}


def check_deadlock_compositional(model: Model, options: SearchOptions | None = None,
                                 listener: Listener | None = None) -> CompositionalResult:
    """Analyse, decide the candidates (``options.check_states`` each), and say whether a deadlock is reachable."""
    from runtime.compositional import analyse, decide
    from runtime.compositional.solver import DEFAULT_SOLVER

    from genom2bip.verify.search import extern_bindings

    options = options or SearchOptions()
    listener = listener or Listener()
    externs = extern_bindings(options.externs)
    started = time.perf_counter()
    analysis = analyse(model.flat, options.solver or DEFAULT_SOLVER, progress=listener.phase)
    budgets = {} if options.check_states is None else {"bfs_budget": options.check_states,
                                                        "guided_budget": options.check_states}
    decide(analysis, model.package, model.root, externs, progress=listener.phase, **budgets)
    seconds = time.perf_counter() - started
    refuted = [Refuted(p.method, p.reason) for p in analysis.potentials if not p.checked]
    candidates = [Candidate(p.verdict, p.method, p.reason, analysis.describe(p.state), [list(c) for c in p.waits],
                            Trace(list(p.trace)) if p.verdict == "reachable" else None)
                  for p in analysis.candidates]
    trace = next((c.trace for c in candidates if c.trace is not None), None)
    return CompositionalResult("deadlock freedom", VERDICTS[analysis.verdict], Figures(seconds=seconds), trace,
                               "compositional", potentials=len(analysis.potentials), refuted=refuted,
                               candidates=candidates, reused_traps=analysis.reused_traps,
                               listing_complete=analysis.complete, explored=analysis.explored, analysis=analysis)
