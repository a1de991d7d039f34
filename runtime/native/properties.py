"""Properties the compiled search checks: deadlock freedom, and safety properties through their observers.

``compiled_check`` returns a :class:`~runtime.props.check.Verdict` like the
Python checker's, or None when the property is not of a shape the compiled
search takes (the caller then checks it in Python and says so).
"""
from __future__ import annotations

import time

from runtime.export.promela import PromelaError
from runtime.props.check import Verdict

METHOD = "compiled observer search"


def compiled_check(space, item, externs=None, progress=None, max_states=None, max_bytes=None,
                   por: bool = False, **search) -> Verdict | None:
    """The verdict of ``item`` by the compiled search, or None if it cannot take the property or the model.

    ``por``: with partial-order reduction (the observer's interactions are visible; same verdict).
    ``search``: ``workers``, ``store``, ``bits`` of :meth:`CompiledSpace.explore`; a lossy store's
    omission figures are the verdict's ``lossiness`` (None for the exact store).
    """
    from runtime.export.interactions import all_interactions
    from runtime.export.monitors import build_monitor, spin_shape
    from runtime.native.compiled import Diverged, compile_space
    from runtime.native.observers import minimal

    shape = spin_shape(item)
    if not shape:
        return None
    monitors = []
    if shape == "observer":
        statics = all_interactions(space.engine)
        try:
            monitor, _ = build_monitor(item, statics, "p")
        except PromelaError:
            return None
        monitors.append((minimal(monitor), statics))
    cs, _ = compile_space(space, externs, monitors, search=True)
    if cs is None:
        return None
    start = time.perf_counter()
    try:
        result = cs.explore(max_states, progress=progress, stop_at_deadlock=shape == "deadlock", max_bytes=max_bytes,
                            por=por, **search)
    except Diverged:
        return None
    prop = item.property
    if result.error is not None:
        verdict = Verdict(prop, None, note=result.error.message, error=result.error.message)
    elif shape == "deadlock" and result.deadlocks:
        verdict = Verdict(prop, False, cs.trace_to(result.deadlocks[0]), "counterexample", method=METHOD)
    elif result.stopped_by == "violated":
        verdict = Verdict(prop, False, cs.trace_to(cs.violation), "counterexample", method=METHOD)
    elif result.complete:
        verdict = Verdict(prop, True, method=METHOD)
    else:
        verdict = Verdict(prop, None, note=f"the search stopped at {result.stopped_by} before an answer", method="")
    verdict.states = result.states
    verdict.lossiness = cs.lossiness
    verdict.result = result  # the search's figures: depth, memory, how it stopped
    verdict.seconds = time.perf_counter() - start
    return verdict
