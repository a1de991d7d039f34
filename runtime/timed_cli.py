"""``python -m runtime run`` on a timed model: the timed run loop, simulated or real time (``--real-time``)."""
from __future__ import annotations

import json
import random

from runtime.exits import EXIT_INCONCLUSIVE, EXIT_OK, EXIT_VIOLATED
from runtime.model import Package


def is_timed(package: Package) -> bool:
    """True when some atom declares a clock: the model needs the timed run loop.  Invariants on data alone are
    checked by the untimed engine (runtime/engine/invariants.py)."""
    return any(a.clocks for a in package.atom_types)


def run_timed_command(package: Package, args, out, err) -> int:
    """Run a timed model with the options of ``python -m runtime run``; the exit status is runtime/exits.py's
    (0 deadlock/time-lock/limit, 4 an invariant or a timing constraint violated or another model error)."""
    from runtime.engine import EngineError, make_policy
    from runtime.engine.timed import TimedEngine
    from runtime.engine.timed_run import EXIT, Planner, run_timed

    if args.limit is not None and args.limit < 0:
        print("error: --limit must be >= 0", file=err)
        return 1
    try:
        te = TimedEngine(package, args.root, externs=args.externs)
    except EngineError as e:
        print(f"{args.model}: error: {e}", file=err)
        return 1
    policy = make_policy(args.policy, args.seed, te.engine.format_state)
    try:
        trace = open(args.trace, "w", encoding="utf-8") if args.trace else None
    except OSError as e:
        print(f"error: cannot write trace: {e}", file=err)
        return 1
    record = (lambda step: print(json.dumps(step), file=trace, flush=True)) if trace else None
    try:
        planner = Planner(random.Random(args.seed)) if args.random_time else None
        summary = run_timed(te, policy, args.limit, None if args.quiet else out, real_time=args.real_time,
                            record=record, planner=planner)
    finally:
        if trace:
            trace.close()
    print(summary.line(), file=out)
    if summary.outcome in ("error", "invariant", "violation"):
        print(f"{args.model}: {summary.line()}", file=err)
    return EXIT[summary.outcome]


_UNITS = {"ns": 1, "us": 10**3, "ms": 10**6, "s": 10**9}


def parse_tick(text: str) -> int:
    """``1ms``, ``250us``, ``2s`` or a number of nanoseconds, as nanoseconds (> 0)."""
    import re
    m = re.fullmatch(r"\s*(\d+)\s*(ns|us|ms|s)?\s*", text)
    if not m or int(m.group(1)) == 0:
        raise ValueError(f"a tick is a positive duration such as 1ms, 250us or 2s, not '{text}'")
    return int(m.group(1)) * _UNITS[m.group(2) or "ns"]


def explore_command(args, out, err) -> int:
    """``python -m runtime explore MODEL --tick 1ms``: the discrete-time exploration of a timed model.
    Exit 0 when complete with no deadlock and no time-lock, 4 when one is reachable or a model error is met,
    5 when a limit stopped it first (runtime/exits.py)."""
    from runtime.bip2 import parse_file
    from runtime.diagnostics import DiagnosticError
    from runtime.engine import EngineError
    from runtime.engine.timed import TimedEngine
    from runtime.explore.timed import explore_timed

    try:
        tick = parse_tick(args.tick)
        te = TimedEngine(parse_file(args.model), args.root, externs=args.externs)
    except (ValueError, DiagnosticError, EngineError) as e:
        message = e.render() if isinstance(e, DiagnosticError) else \
            f"{'error' if isinstance(e, ValueError) else args.model + ': error'}: {e}"
        print(message, file=err)
        return 1
    result = explore_timed(te, tick, args.max_states)
    print(result.summary(), file=out)
    for name in result.uncapped:
        print(f"warning: clock {name} is compared with a non-constant: it is not capped, the space may be infinite",
              file=err)
    for kind, sids in (("deadlock", result.deadlocks), ("time-lock", result.time_locks)):
        for sid in sids[:3]:
            print(f"{kind} at state {sid}: {' '.join(result.traces[sid]) or '(initial state)'}", file=out)
    if result.error:
        print(f"{args.model}: model error: {result.error}", file=err)
        return EXIT_VIOLATED
    if result.deadlocks or result.time_locks:
        return EXIT_VIOLATED
    return EXIT_OK if result.complete else EXIT_INCONCLUSIVE
