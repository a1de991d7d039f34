"""Deadlocks and safety properties by SPIN on the Promela translation, its trails in our labels.

Every trail SPIN reports is replayed on our engine before it is returned
(``runtime.export.spin``), so a trace is a path of the BIP model.  SPIN's
failures are ``runtime.export.spin.SpinError``.
"""
from __future__ import annotations

from genom2bip.loading import InputError
from genom2bip.verify.options import Listener, SearchOptions
from genom2bip.verify.results import Deadlock, DeadlockResult, Figures, PropertyResult, Trace, Verdict


def refuse_for_spin(properties) -> None:
    """Raise :class:`~genom2bip.loading.InputError` naming the properties SPIN does not check."""
    from runtime.export.monitors import spin_shape

    unsupported = [p.name for p in properties if not spin_shape(p)]
    if unsupported:
        raise InputError([f"--engine spin checks deadlock freedom and safety properties [R] false / [R] {{P}} "
                          f"(never, precedes, invariant); use --engine explore for: {', '.join(unsupported)}"])


def spin_summary(report) -> str:
    """One pan run's figures in one line."""
    rate = f", {report.rate:,.0f} states/s" if report.rate else ""
    exact = "" if report.complete else " (not exhaustive)"
    return (f"{report.states:,} states, {report.transitions:,} transitions, state vector {report.vector} bytes, "
            f"{report.memory_mb:.1f} MB, {report.seconds:.2f} s{rate}{exact}")


def _figures(report) -> Figures:
    return Figures(report.states, report.transitions, report.seconds, int(report.memory_mb * 2**20) or None,
                   report.depth or None)


def _limit(report) -> str:
    """What stopped an incomplete pan run: its search depth or its memory."""
    if report.complete:
        return ""
    return "max-memory" if "out of memory" in report.output.lower() else "max-depth"


def _approximate(options: SearchOptions) -> bool:
    return bool(options.spin_bitstate or options.spin_swarm)


def spin_deadlock(space, options: SearchOptions, listener: Listener | None = None) -> DeadlockResult:
    """Deadlock freedom by SPIN (invalid end states): each trail replayed, with the state it ends in."""
    from runtime.export import spin

    listener = listener or Listener()
    if options.spin_swarm:
        result = spin.swarm(space, options.spin_swarm, None, min(options.spin_hash_bits, 30))
    else:
        result = spin.verify_deadlocks(space, options.spin_cores, options.spin_bitstate, options.spin_hash_bits,
                                       workdir=options.spin_dir, progress=listener.progress())
    report = result.report
    deadlocks = [Deadlock(trail.end_state if trail.end_state is not None else -1, Trace(list(trail.steps)),
                          space.engine.format_state(space.concrete(trail.steps)), message=trail.message)
                 for trail in result.trails]
    verdict = (Verdict.VIOLATED if report.errors else Verdict.INCONCLUSIVE if not report.complete
               else Verdict.HOLDS)
    return DeadlockResult("deadlock freedom", verdict, _figures(report), deadlocks[0].trace if deadlocks else None,
                          "SPIN", _limit(report), exhaustive=not _approximate(options),
                          deadlocks=deadlocks, complete=report.complete, shortest=False, summary=spin_summary(report),
                          reported=report.errors)


def spin_property(space, item, options: SearchOptions, listener: Listener | None = None,
                  name: str = "p") -> PropertyResult:
    """A safety property ``[R] false`` / ``[R] {P}`` by SPIN, through its observer (``name``: the monitor's)."""
    from runtime.export import spin
    from runtime.export.interactions import all_interactions
    from runtime.export.monitors import build_monitor
    from runtime.props import describe

    listener = listener or Listener()
    monitor, _ = build_monitor(item, all_interactions(space.engine), name)
    if options.spin_swarm:
        result = spin.swarm(space, options.spin_swarm, [monitor], min(options.spin_hash_bits, 30))
    else:
        result = spin.verify_safety(space, [monitor], options.spin_cores, options.spin_bitstate,
                                    options.spin_hash_bits, workdir=options.spin_dir, progress=listener.progress())
    report = result.report
    approximate = _approximate(options) or not report.complete
    verdict = Verdict.VIOLATED if report.errors else Verdict.INCONCLUSIVE if approximate else Verdict.HOLDS
    trace = Trace(list(result.trails[0].steps)) if report.errors and result.trails else None
    return PropertyResult(describe(item), verdict, _figures(report), trace, "SPIN",
                          _limit(report), exhaustive=not _approximate(options),
                          summary=spin_summary(report), name=item.name,
                          evidence="counterexample" if trace is not None else "")
