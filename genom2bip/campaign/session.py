"""Loaded by each worker process of a local cluster (Dask's ``preload``): the worker leaves the session of the
command that started it.

Where the kernel shares the CPU between sessions (Linux's autogroup), every process of one session shares that
session's part of a busy machine: workers left in the command's session would get no more CPU together than one
process, whatever their number (bench/campaign_bench.py measured it).  In a session of its own, each worker gets a
part, as a ``dask worker`` started apart does.  A Ctrl-C at the terminal then reaches the command alone, which
cancels the jobs and closes the cluster; a worker still exits when the command's process is gone (its pipe to the
nanny closes).
"""
from __future__ import annotations

import os


def dask_setup(worker) -> None:
    """Leave the command's session (nothing to do where the process leads one already)."""
    try:
        os.setsid()
    except OSError:
        pass
