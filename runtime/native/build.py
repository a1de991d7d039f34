"""Compile a model's generated C with the system compiler, cache the library by content hash, load it with ctypes.

The cache is ``$XDG_CACHE_HOME/genom2bip/native`` (``~/.cache/...`` by
default; ``GENOM2BIP_CACHE`` overrides it): the file name is the hash of
the C text and the compiler flags, so a model compiles once per change; the
C text is kept beside its library.
:func:`compiler` finds ``$CC`` or ``gcc``/``cc`` on PATH; without one the
caller explores in Python.
"""
from __future__ import annotations

import atexit
import ctypes
import hashlib
import os
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from pathlib import Path
from typing import Callable

from runtime.cachefiles import cache_dir, write_atomic
from runtime.engine.source import DUMP_ENV, dumped

HERE = Path(__file__).parent
FLAGS = ("-O2", "-march=native", "-fPIC", "-shared", "-fno-strict-aliasing", "-w", "-pipe")
#: GENOM2BIP_OPT's values: gcc's -O levels.
LEVELS = ("0", "1", "2", "3")
#: Added for the multi-threaded search (search.c's PARALLEL: per-thread scratch, atomic shared counters).
PARALLEL_FLAGS = ("-DPARALLEL", "-pthread")
#: Added for a step called one state at a time (the zone search's, a trace's, the agreement tests'): search.c's
#: STEP_ONLY leaves its store and search out, which halves a small model's compile at -O0.
STEP_FLAGS = ("-DSTEP_ONLY",)
#: Added when the C text is dumped (GENOM2BIP_DUMP): line tables for gdb and perf; the code is the same.
DEBUG_FLAGS = ("-g",)


#: Told when a compile starts and when it ends (one line each): the command line prints it on stderr where it shows
#: progress, so that a first run is not a silent minute.  None: nothing is told (a library, a test, a campaign).
notice: Callable[[str], None] | None = None


def tell(fn: Callable[[str], None] | None) -> None:
    """Who hears of compiles (:data:`notice`); None for no one."""
    global notice
    notice = fn


def say(message: str) -> None:
    """Tell :data:`notice` a line about compiles, if anyone hears of them."""
    if notice is not None:
        notice(message)


def forced() -> bool:
    """``GENOM2BIP_OPT`` sets one gcc level for every build: there is no faster build to make beside."""
    return bool(os.environ.get("GENOM2BIP_OPT", "").strip())


class BuildError(Exception):
    """The C compiler failed on generated text (a bug of the generator: the message carries its output)."""


def compiler() -> str | None:
    """The C compiler to use: ``$CC`` if set and found, else gcc or cc on PATH, else None."""
    for name in (os.environ.get("CC"), "gcc", "cc"):
        if name and shutil.which(name):
            return shutil.which(name)
    return None


#: The level of a step only called one state at a time from Python (the zone explorer's, a trace's): its compile
#: is what costs, not its speed (RobNav nc = 4, cold: 2.1 s of gcc at -O0, 5.6 s at -O2, the same 6.5 s of search;
#: docs/verification/explorer.md, *Compiled exploration*).  The C search itself is built at -O2 (DALA's deadlock search
#: runs twice as fast there).
STEP_LEVEL = "0"


def flags(parallel: bool = False, level: str | None = None, step_only: bool = False) -> tuple[str, ...]:
    """gcc's flags: :data:`FLAGS` at ``level`` (None: -O2), ``GENOM2BIP_OPT``'s level if set (whatever the use),
    the threaded build's if ``parallel``, the step's alone (:data:`STEP_FLAGS`) if ``step_only``."""
    level = os.environ.get("GENOM2BIP_OPT", "").strip() or level  # forced()
    if level and level not in LEVELS:
        raise BuildError(f"GENOM2BIP_OPT={level!r}: expected one of {', '.join(LEVELS)} (gcc's -O level)")
    base = tuple(f"-O{level}" if f == "-O2" and level else f for f in FLAGS)
    base += STEP_FLAGS if step_only else ()
    return base + PARALLEL_FLAGS if parallel else base


def _headers() -> str:
    return "".join((HERE / n).read_text() for n in ("prelude.h", "odometer.h", "search.c"))


def _key(source: str, cc: str, opts: tuple[str, ...], dump: Path | None) -> str:
    parts = (source, _headers(), " ".join(opts), cc) + ((str(dump),) if dump is not None else ())
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()


def cached(source: str, cc: str, parallel: bool = False, level: str | None = None,
           step_only: bool = False) -> Path | None:
    """The library :func:`build` would return for these arguments if it is in the cache already, else None."""
    if os.environ.get(DUMP_ENV):  # a dumped step is built from the dump, with line tables
        return None
    opts = flags(parallel, level, step_only)
    lib = cache_dir() / f"step-{_key(source, cc, opts, None)[:24]}.so"
    return lib if lib.exists() and lib.with_suffix(".c").exists() else None


def build(source: str, cc: str, parallel: bool = False, what: str = "compiled step", level: str | None = None,
          told: bool = True, step_only: bool = False) -> Path:
    """The shared library for ``source``, compiled now or found in the cache; ``parallel``: the threaded build.

    The C text is kept next to the library (``step-<key>.c``) and compiled from there, so a profiler or a
    debugger finds the lines it was built from (``level``: gcc's, see :func:`flags`).  With ``GENOM2BIP_DUMP=DIR``
    it is written to DIR instead
    (named after ``what``) and compiled from that file with ``-g``: gdb and perf then show its lines.
    ``told``: :data:`notice` hears of the compile (not from a compile on another thread); ``step_only``: the step
    without the search (:data:`STEP_FLAGS`).
    """
    opts = flags(parallel, level, step_only)
    dump = dumped(source, what, ".c")
    if dump is not None:
        opts += DEBUG_FLAGS
    key = _key(source, cc, opts, dump)
    out_dir = cache_dir()
    lib = out_dir / f"step-{key[:24]}.so"
    c_file = dump or lib.with_suffix(".c")
    if lib.exists() and c_file.exists():
        return lib
    out_dir.mkdir(parents=True, exist_ok=True)
    if dump is None:
        write_atomic(c_file, source.encode("utf-8"))
    if lib.exists():
        return lib
    level = next((f for f in opts if f.startswith("-O")), "")
    told = told and notice is not None
    if told:
        notice(f"{what}: compiling {len(source) // 1024:,} KB of C ({Path(cc).name} {level}) ...")
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="genom2bip-c-") as tmp:
        so = Path(tmp) / "model.so"
        code, err = _compile([cc, *opts, f"-I{HERE}", "-o", str(so), str(c_file)], tmp)
        if code != 0:
            raise BuildError(f"{cc} failed on the generated step ({c_file}):\n{err[-4000:]}")
        write_atomic(lib, so.read_bytes())
    if told:
        notice(f"{what}: compiled in {time.perf_counter() - start:.1f} s (kept in {out_dir} for the next run)")
    return lib


#: Compilers running now, with the folder they write in: a compile on another thread may still run when the
#: process ends, and is then stopped and its folder removed rather than left behind.
_running: dict[subprocess.Popen, str] = {}
_lock = threading.Lock()


def _compile(argv: list[str], tmp: str) -> tuple[int, str]:
    """Run the compiler, its own temporary files in ``tmp`` and its processes a group of their own (so that
    :func:`_stop_compiles` stops them all); its exit status and error output."""
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ, TMPDIR=tmp), start_new_session=True)
    with _lock:
        _running[proc] = tmp
    try:
        _, err = proc.communicate()
    finally:
        with _lock:
            _running.pop(proc, None)
    return proc.returncode, err


@atexit.register
def _stop_compiles() -> None:
    with _lock:
        left = list(_running.items())
    for proc, tmp in left:
        try:
            os.killpg(proc.pid, signal.SIGTERM)  # the driver, cc1 and as
        except ProcessLookupError:
            pass
        proc.wait()
        shutil.rmtree(tmp, ignore_errors=True)


class Result(ctypes.Structure):
    """Mirror of ``Result`` in search.c."""

    _fields_ = [("states", ctypes.c_int64), ("transitions", ctypes.c_int64), ("depth", ctypes.c_int64),
                ("error_state", ctypes.c_int64), ("deadlocks", ctypes.c_int64), ("memory", ctypes.c_int64),
                ("status", ctypes.c_int32), ("ecode", ctypes.c_int32), ("earg", ctypes.c_int64)]


PROGRESS = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_int64, ctypes.c_int64, ctypes.c_int64, ctypes.c_int64,
                            ctypes.c_int64)


def load(path: Path) -> ctypes.CDLL:
    """Open the library with the argument types of its entry points declared."""
    lib = ctypes.CDLL(str(path), mode=ctypes.RTLD_LOCAL)
    i64, i32, p = ctypes.c_int64, ctypes.c_int, ctypes.POINTER
    sig = {
        "c_width": (i32, [i32]), "c_words": (i32, []),
        "c_state_width": (i32, []), "c_nstates": (i64, []), "c_parent": (i64, [i64]), "c_via": (i64, [i64]),
        "c_deadlock": (i64, [i64]), "c_state": (None, [i64, p(i64)]), "c_free": (None, []),
        "c_successors": (i32, [p(i64), p(i64), p(i64), i32, i64, p(i32), p(i64)]), "c_via_bits": (i32, []),
        "c_set_por": (None, [i32]), "c_por_available": (i32, []), "c_reduced": (i64, []),
        "c_search": (i32, [i32, i64, i64, i64, i32, i64, ctypes.c_double, PROGRESS, p(Result), i32, i32, i32]),
        "c_table_size": (ctypes.c_uint64, []), "c_bits_per_state": (i32, []), "c_parallel": (i32, []),
    }
    for name, (res, args) in sig.items():
        fn = getattr(lib, name, None)
        if fn is None:  # a step built without the search (STEP_FLAGS) has the step's entry points only
            continue
        fn.restype = res
        fn.argtypes = args
    return lib
