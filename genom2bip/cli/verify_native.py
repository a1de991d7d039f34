"""Which explorer ``genom2bip verify`` runs: the compiled one (default) or the Python one, and a note when it falls back.

The compiled search answers deadlocks, model errors, deadlock freedom and
safety properties (through observers); LTS exports and the other properties
need the successor lists the Python explorer keeps, so they run there (a
note says so).  A model the C back end does not take, or a machine
without a C compiler, gets the Python explorer and a one-line note.
"""
from __future__ import annotations

import argparse
import os
import sys

#: Share of the machine's memory the compiled search may use when --max-memory is not given.
MEMORY_SHARE = 0.5


def default_memory() -> int | None:
    """Half of the physical memory, in bytes (None where the system does not say)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") * MEMORY_SHARE)
    except (ValueError, OSError, AttributeError):
        return None


def note(text: str) -> None:
    print(f"note: {text}")


def explore_model(space, args: argparse.Namespace, progress):
    """``(result, view)``: the exploration result, and what gives its traces (the compiled space or ``space``)."""
    from runtime.explore import explore

    if args.engine in ("compiled", "explore"):
        if args.aut or args.dot:
            note("LTS exports need every successor list: exploring with the Python step")
        else:
            found = _compiled(space, args, progress)
            if found is not None:
                return found
    if args.por:
        note("no partial-order reduction in the Python explorer: every interleaving is explored")
    max_bytes = _max_bytes(args)
    _say_unbounded(args, max_bytes)
    result = explore(space, args.max_depth, args.dfs, progress, max_bytes=max_bytes)
    if result.stopped_by == "max-memory":
        note(f"the Python search stopped past {max_bytes / 2**20:,.0f} MB (--max-memory MB sets the bound)")
    return result, space


def check_property(space, item, args: argparse.Namespace, progress):
    """The verdict of one property: by the compiled search when it takes it, else by the Python checker (noted)."""
    from runtime.props import check

    if args.engine in ("compiled", "explore"):
        from genom2bip.cli.verbs import load_externs
        from runtime.native.properties import compiled_check

        verdict = compiled_check(space, item, load_externs(args.externs), progress, args.max_states, _max_bytes(args),
                                 por=args.por)
        if verdict is not None:
            return verdict
        note(f"property {item.name} is checked with the Python step (the compiled search takes deadlock freedom "
             "and [R] false / [R] {P} shapes, on models it compiles)")
    return check(space, item, progress)


def por_note(cs, states: int) -> str:
    """What the partial-order reduction did, in one line."""
    if not cs.por_available:
        return "no partial-order reduction: the request counts of --requests are shared by every service"
    return (f"partial-order reduction: {cs.reduced:,} of {states:,} states expanded with an ample set "
            "(deadlocks and safety verdicts as the full search; traces are shortest in the reduced graph only)")


def _max_bytes(args) -> int | None:
    return args.max_memory * 1024 * 1024 if args.max_memory is not None else default_memory()


def _say_unbounded(args, max_bytes: int | None) -> None:
    """On a terminal, a search given no bound says which one it has and how to stop it."""
    if args.max_states is None and args.max_depth is None and (args.progress or sys.stderr.isatty()) \
            and not args.quiet and max_bytes is not None:
        print(f"searching with no --max-states or --max-depth: until complete or {max_bytes / 2**30:.1f} GB "
              "(--max-memory); Ctrl-C stops and reports what was explored", file=sys.stderr)


def _compiled(space, args, progress):
    from genom2bip.cli.verbs import load_externs
    from runtime.native.compiled import Diverged, compile_space

    cs, why = compile_space(space, load_externs(args.externs))
    if cs is None:
        note(why)
        return None
    max_bytes = _max_bytes(args)
    _say_unbounded(args, max_bytes)
    try:
        result = cs.explore(args.max_states, args.max_depth, args.dfs, progress, max_bytes=max_bytes,
                            por=args.por)
    except Diverged as exc:
        note(f"the compiled step met an integer past 64 bits ({exc}): exploring with the Python step")
        return None
    if args.por:
        note(por_note(cs, result.states))
    if result.stopped_by == "max-memory":
        note(f"the compiled search stopped at {result.memory / 2**20:,.0f} MB (--max-memory MB sets the bound)")
    return result, cs
