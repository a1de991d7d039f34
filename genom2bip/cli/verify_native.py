"""Which explorer ``genom2bip verify`` runs: the compiled one (default) or the Python one.

A note says when it falls back.

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


def add_arguments(search) -> None:
    """The compiled search's options: threads, the visited set's store, the bitstate array's size."""
    from runtime.native.stores import DEFAULT_BITS, STORES

    search.add_argument("--workers", type=int, metavar="N", default=1,
                        help="compiled explorer: breadth-first search on N threads (0: one per core; default 1); "
                             "same states, deadlocks and verdicts, traces still shortest")
    search.add_argument("--store", choices=tuple(STORES), default="exact",
                        help="compiled explorer's visited set: exact states (default), compact (64-bit hash "
                             "compaction, like SPIN's -DHC) or bitstate (like SPIN's -DBITSTATE); the lossy ones "
                             "search breadth-first and state how likely they missed states")
    search.add_argument("--bits", type=int, metavar="N", default=DEFAULT_BITS,
                        help=f"--store bitstate: 2^N bits (default {DEFAULT_BITS}: {2 ** DEFAULT_BITS // 2 ** 23} MB)")


def check_arguments(args: argparse.Namespace) -> str | None:
    """What is wrong with the compiled search's options, or None."""
    if args.workers < 0:
        return "--workers must be >= 0"
    if not 9 <= args.bits <= 40:
        return "--bits must be between 9 and 40"
    special = [f for f, on in (("--workers", args.workers != 1), ("--store", args.store != "exact")) if on]
    if special and args.engine not in ("compiled", "explore"):
        return f"{' and '.join(special)} belong to the compiled explorer (--engine compiled)"
    if special and args.dfs:
        return f"{' and '.join(special)} search breadth-first: drop --dfs"
    return None


def search_options(args: argparse.Namespace) -> dict:
    """The keyword arguments of CompiledSpace.explore that the command line sets."""
    workers = args.workers or os.cpu_count() or 1
    return {"workers": workers, "store": args.store, "bits": args.bits}


def store_note(cs) -> None:
    """What a lossy store may have missed, or that a multi-threaded bitstate search may count a state twice."""
    if cs.lossiness is not None:
        note(cs.lossiness.line() + "; traces are shortest among the states stored")


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
    if args.workers != 1 or args.store != "exact":
        note("the Python explorer runs on one thread over exact states (--workers and --store are the compiled "
             "explorer's)")
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
                                 por=args.por, **search_options(args))
        if verdict is not None:
            if getattr(verdict, "lossiness", None) is not None:
                note(verdict.lossiness.line())
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
                            por=args.por, **search_options(args))
    except Diverged as exc:
        note(f"the compiled step met an integer past 64 bits ({exc}): exploring with the Python step")
        return None
    if args.por:
        note(por_note(cs, result.states))
    store_note(cs)
    if result.stopped_by == "max-memory":
        note(f"the compiled search stopped at {result.memory / 2**20:,.0f} MB (--max-memory MB sets the bound)")
    return result, cs
