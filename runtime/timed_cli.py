"""``python -m runtime run`` on a timed model: the timed run loop, simulated or real time (``--real-time``)."""
from __future__ import annotations

from runtime.model import Package


def is_timed(package: Package) -> bool:
    """True when some atom declares a clock or an invariant: the model needs the timed run loop."""
    return any(a.timed for a in package.atom_types)


def run_timed_command(package: Package, args, out, err) -> int:
    """Run a timed model with the options of ``python -m runtime run``; the exit status is the reference's
    (0 deadlock/time-lock/limit, 5 invariant violated, 7 timing constraint violated, 2 other model error)."""
    from runtime.engine import EngineError, make_policy
    from runtime.engine.timed import TimedEngine
    from runtime.engine.timed_run import EXIT, run_timed

    if args.limit is not None and args.limit < 0:
        print("error: --limit must be >= 0", file=err)
        return 1
    try:
        te = TimedEngine(package, args.root, externs=args.externs)
    except EngineError as e:
        print(f"{args.model}: error: {e}", file=err)
        return 1
    policy = make_policy(args.policy, args.seed, te.engine.format_state)
    summary = run_timed(te, policy, args.limit, None if args.quiet else out, real_time=args.real_time)
    print(summary.line(), file=out)
    if summary.outcome in ("error", "invariant", "violation"):
        print(f"{args.model}: {summary.line()}", file=err)
    return EXIT[summary.outcome]
