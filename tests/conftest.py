"""What every test shares, whoever wrote it and whichever worker runs it (docs/architecture.md, *Tests*).

* The compiled explorer's gcc level, ``GENOM2BIP_OPT`` (runtime/native/build.py): the tests check
  states, verdicts and traces, never speed, and most of them compile far more than they explore, so the
  suite builds at :data:`TEST_LEVEL` unless the run sets the variable itself
  (``GENOM2BIP_OPT=2 python -m pytest`` tests the level users get throughout).  Set in ``os.environ``, it
  reaches the commands the tests start.  :func:`shipped_c_level` gives a test the level users get.
* ``verify``'s traces, ``GENOM2BIP_TRACES`` (genom2bip/cli/verify_report.py): by default ``verify`` prints a
  summary and writes its details and traces under ``out/traces/``.  The suite's verify tests read the details
  and traces as they are printed, so the suite runs with ``terminal`` (and writes nothing into the working
  directory); tests/test_verify_output.py tests the default, the directory and the JSON document.
* The compiled-C cache (``$XDG_CACHE_HOME/genom2bip/native``) is shared by the workers of ``-n``: a
  library is written under a name of its own and renamed into place, so two workers building the same
  model at once both load a whole library (tests/test_native.py checks it).
* Bytecode, where the environment says not to write it (``PYTHONDONTWRITEBYTECODE``, as on the machine
  these tests were written on): the suite starts hundreds of ``python -m genom2bip`` processes, each of
  which would compile every module it imports from source again (a quarter of a small ``verify``'s time).
  The run writes their bytecode instead into a directory of its own (``PYTHONPYCACHEPREFIX``), outside the
  tree, shared by its workers and removed at its end by the process that made it.
"""
from __future__ import annotations

import atexit
import os
import shutil
import sys
import tempfile

import pytest

#: gcc's level for the suite's builds.
TEST_LEVEL = "0"
os.environ.setdefault("GENOM2BIP_OPT", TEST_LEVEL)
os.environ.setdefault("GENOM2BIP_TRACES", "terminal")


def _bytecode_apart() -> None:
    """``PYTHONDONTWRITEBYTECODE`` replaced, for this run and the processes it starts, by a bytecode directory
    of the run's own (the first process to load this file makes it; its workers inherit it)."""
    if not os.environ.get("PYTHONDONTWRITEBYTECODE") or os.environ.get("PYTHONPYCACHEPREFIX"):
        return
    where = tempfile.mkdtemp(prefix="genom2bip-tests-bytecode-")
    os.environ["PYTHONPYCACHEPREFIX"] = where
    del os.environ["PYTHONDONTWRITEBYTECODE"]
    sys.pycache_prefix, sys.dont_write_bytecode = where, False
    atexit.register(shutil.rmtree, where, ignore_errors=True)


_bytecode_apart()


@pytest.fixture
def shipped_c_level(monkeypatch):
    """Build at the level users get (-O2): a test of what the shipped build computes, or whose exploration costs
    more than its builds (measure first: the localization tests build about 150 libraries, and take about a
    quarter of the CPU time at -O0)."""
    monkeypatch.setenv("GENOM2BIP_OPT", "2")
