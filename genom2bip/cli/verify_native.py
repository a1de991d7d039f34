"""The compiled search's options of ``genom2bip verify`` (threads, store, bits), and every search option as the
verification API's :class:`~genom2bip.verify.SearchOptions`.

Which explorer runs, and the notes that say when it falls back, are the
API's (genom2bip/verify/search.py).
"""
from __future__ import annotations

import argparse


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


def search_options(args: argparse.Namespace):
    """The command line's search settings as the verification API takes them."""
    from genom2bip.verify import SearchOptions

    return SearchOptions(engine=args.engine, max_states=args.max_states, max_depth=args.max_depth,
                         max_memory_mb=args.max_memory, dfs=args.dfs, requests=args.requests,
                         reduce=not args.no_reduce, externs=args.externs, por=args.por, workers=args.workers,
                         store=args.store, bits=args.bits, spin_cores=args.spin_cores,
                         spin_bitstate=args.spin_bitstate, spin_hash_bits=args.spin_hash_bits,
                         spin_swarm=args.spin_swarm, spin_dir=args.spin_dir, solver=args.solver,
                         check_states=args.check_states, time_limit=getattr(args, "time_limit_s", None))
