"""Running SPIN on the Promela translation: deadlock search, safety observers, counts, and trails read back.

``SpinRun`` writes ``model.pml`` in a work directory, runs ``spin -a``, compiles
``pan.c`` with the options asked for (multi-core ``NCORE``, ``BITSTATE``),
runs ``pan`` and parses its report.  Error trails are replayed with
``pan -r -S``, whose output is only our ``@@i``/``@@o`` markers: each becomes a
step that is then replayed on the engine (:meth:`StateSpace.replay`), so a
trail is checked against our own semantics before it is shown.  Swarm mode
runs several bitstate searches with different hash functions and seeds in
parallel and merges what they find.
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from runtime.explore.choices import ExploreError
from runtime.explore.space import StateSpace, Step
from runtime.export.promela import Monitor, refuse_untranslatable, write_promela

#: pan's search depth bound (its default, 10 000, is too small for our models; the stack costs ~50 bytes a level).
DEPTH = 1_000_000


class SpinError(ExploreError):
    """SPIN is missing, or spin/gcc/pan failed."""


def spin_path() -> str | None:
    return shutil.which("spin")


@dataclass
class PanReport:
    """What one pan run printed: counts, memory, time, errors (kind, trail file)."""

    states: int = 0
    matched: int = 0
    transitions: int = 0
    vector: int = 0
    depth: int = 0
    errors: int = 0
    memory_mb: float = 0.0
    states_memory_mb: float = 0.0
    seconds: float = 0.0
    complete: bool = True
    messages: list[str] = field(default_factory=list)
    trails: list[Path] = field(default_factory=list)
    output: str = ""

    @property
    def rate(self) -> float:
        return self.states / self.seconds if self.seconds > 0 else 0.0


@dataclass
class SpinTrail:
    """A trail translated back: the steps, and what pan said about its end."""

    steps: list[Step]
    message: str
    end_state: int | None = None


@dataclass
class SpinResult:
    report: PanReport
    trails: list[SpinTrail]
    mode: str
    workdir: Path | None = None


def parse_pan(output: str) -> PanReport:
    r = PanReport(output=output)

    def num(pattern: str, cast=float, default=0):
        m = re.search(pattern, output)
        return cast(m.group(1)) if m else default

    r.states = int(num(r"([0-9.e+]+) states, stored", float))
    r.matched = int(num(r"([0-9.e+]+) states, matched", float))
    r.transitions = int(num(r"([0-9.e+]+) transitions \(= stored\+matched\)", float))
    r.vector = int(num(r"State-vector (\d+) byte", int))
    r.depth = int(num(r"depth reached (\d+)", int))
    r.errors = int(num(r"errors: (\d+)", int))
    r.memory_mb = num(r"([0-9.]+)\s+total actual memory usage")
    r.states_memory_mb = num(r"([0-9.]+)\s+actual memory usage for states")
    r.seconds = num(r"pan: elapsed time ([0-9.e+-]+) seconds")
    r.messages = re.findall(r"^(?:cpu\d+: )?pan:\d+: (.*?)(?: \(at depth \d+\))?$", output, flags=re.M)
    r.errors = max(r.errors, len(r.messages))
    if r.states == 0:  # multi-core runs that stop at an error print no summary
        visited = [int(x) for x in re.findall(r"\((\d+) states visited\)", output)]
        r.states = max(visited, default=0)
        if r.errors:
            r.complete = False
    if "max search depth too small" in output or "out of memory" in output.lower():
        r.complete = False
    return r


class SpinRun:
    """One SPIN job on a state space's model (its layout, reduction and environment are the explorer's)."""

    def __init__(self, space: StateSpace, workdir: str | Path | None = None, cores: int = 1,
                 bitstate: bool = False, hash_bits: int = 27, keep: bool = False, opt: str = "-O2") -> None:
        refuse_untranslatable(space)  # installing SPIN would not help: say so first
        if spin_path() is None:
            raise SpinError("spin is not installed (Debian: apt-get install spin); use --engine explore")
        if shutil.which("gcc") is None and shutil.which("cc") is None:
            raise SpinError("SPIN needs a C compiler (gcc) to build its verifier")
        self.space = space
        self.cores = cores
        self.bitstate = bitstate
        self.hash_bits = hash_bits
        self.opt = opt  # -O0 compiles pan four times faster: worth it for small models
        self.keep = keep or workdir is not None
        self.dir = Path(workdir) if workdir is not None else Path(tempfile.mkdtemp(prefix="genom2bip-spin-"))
        self.dir.mkdir(parents=True, exist_ok=True)

    def _run(self, argv: list[str], timeout: float | None = None) -> subprocess.CompletedProcess:
        try:
            return subprocess.run(argv, cwd=self.dir, capture_output=True, text=True, timeout=timeout)
        except FileNotFoundError as err:
            raise SpinError(f"cannot run {argv[0]}: {err}") from None

    def build(self, monitors: list[Monitor] | None = None, extra: tuple[str, ...] = ()) -> Path:
        from runtime.native import build as native  # its notice: the command line says what a long wait is

        start = time.perf_counter()
        if native.notice is not None:
            native.notice("SPIN: translating the model to Promela, generating pan.c and compiling it ...")
        text = write_promela(self.space, monitors, hidden=self.cores <= 1)
        (self.dir / "model.pml").write_text(text, encoding="utf-8")
        gen = self._run(["spin", "-o2", "-a", "model.pml"])  # -o2: keep write-only variables (we reduce ourselves)
        if gen.returncode != 0:
            raise SpinError(f"spin -a failed on the generated model:\n{gen.stdout}{gen.stderr}")
        flags = [self.opt, "-DSAFETY", "-DNOREDUCE", "-DVECTORSZ=65536"]
        if self.cores > 1:
            flags.append(f"-DNCORE={self.cores}")
        if self.bitstate:
            flags += ["-DBITSTATE", "-DPERMUTED", "-DT_RAND"]
        flags += list(extra)
        cc = shutil.which("gcc") or "cc"
        comp = self._run([cc, *flags, "-o", "pan", "pan.c"])
        if comp.returncode != 0:
            raise SpinError(f"compiling pan failed:\n{comp.stderr[-2000:]}")
        if native.notice is not None:
            native.notice(f"SPIN: pan ready in {time.perf_counter() - start:.1f} s; searching ...")
        return self.dir / "pan"

    def pan(self, args: list[str], timeout: float | None = None, progress=None) -> PanReport:
        start = time.perf_counter()
        if progress is None:
            done = self._run(["./pan", f"-m{DEPTH}", *args], timeout)
            output = done.stdout + done.stderr
        else:
            output = self._streamed(["./pan", f"-m{DEPTH}", *args], timeout, progress)
        report = parse_pan(output)
        if report.seconds == 0:
            report.seconds = time.perf_counter() - start
        report.trails = sorted(self.dir.glob("model.pml*.trail"), key=_trail_order)
        return report

    def _streamed(self, argv: list[str], timeout: float | None, progress) -> str:
        """Run pan reading its output as it comes; each of its progress lines goes to ``progress.tick``."""
        proc = subprocess.Popen(argv, cwd=self.dir, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        deadline = None if timeout is None else time.monotonic() + timeout
        lines = []
        try:
            for line in proc.stdout:
                lines.append(line)
                m = _PAN_PROGRESS.match(line)
                if m:
                    depth, states, transitions, memory = (float(m.group(k)) for k in range(1, 5))
                    progress.tick(int(states), int(transitions), 0, lambda: memory * 1024 * 1024, depth=int(depth))
                if deadline is not None and time.monotonic() > deadline:
                    proc.kill()
                    raise subprocess.TimeoutExpired(argv, timeout)
            proc.wait()
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            progress.done()
        return "".join(lines)

    def trail(self, path: Path, message: str) -> SpinTrail:
        """Replay a trail with pan, read our markers, and replay the steps on the engine."""
        done = self._run(["./pan", "-r", path.name, "-S", "-n"])
        steps = self.space.replay_markers(_markers(done.stdout))
        return SpinTrail(steps[0], message, steps[1])

    def cleanup(self) -> None:
        if not self.keep:
            shutil.rmtree(self.dir, ignore_errors=True)


#: pan's periodic line: ``Depth= 31 States= 1e+06 Transitions= 7.2e+06 Memory= 128.000 t= 3.1 R= 3e+05``.
_PAN_PROGRESS = re.compile(r"Depth=\s*(\d+)\s+States=\s*([0-9.e+]+)\s+Transitions=\s*([0-9.e+]+)\s+"
                           r"Memory=\s*([0-9.]+)")


def _trail_order(p: Path) -> int:
    m = re.search(r"model\.pml(\d*)\.trail", p.name)
    return int(m.group(1) or 0) if m else 0


def _markers(output: str) -> list[tuple[str, int]]:
    out = []
    for line in output.splitlines():
        m = re.match(r"\s*@@([io]) (-?\d+)", line)
        if m:
            out.append((m.group(1), int(m.group(2))))
    return out


def verify_deadlocks(space: StateSpace, cores: int = 1, bitstate: bool = False, hash_bits: int = 27,
                     max_trails: int = 20, workdir=None, timeout: float | None = None, opt: str = "-O2",
                     progress=None) -> SpinResult:
    """Every invalid end state (deadlock) SPIN finds, with their trails read back (up to ``max_trails``).

    Trails are pan's depth-first paths, usually much longer than the
    explorer's shortest traces (pan's own shortening, ``-i``, counts
    statements inside atomic steps, not interactions).
    """
    run = SpinRun(space, workdir, cores, bitstate, hash_bits, opt=opt)
    try:
        run.build()
        args = ["-c0", "-e", "-n"]
        if bitstate:
            args.append(f"-w{hash_bits}")
        report = run.pan(args, timeout, progress)
        trails = []
        for path, msg in zip(report.trails[:max_trails], report.messages):
            trails.append(run.trail(path, msg))
        return SpinResult(report, trails, "deadlock", run.dir if run.keep else None)
    finally:
        run.cleanup()


def count_states(space: StateSpace, cores: int = 1, workdir=None, timeout: float | None = None,
                 opt: str = "-O2") -> PanReport:
    """A full search ignoring end states: SPIN's count of reachable states."""
    run = SpinRun(space, workdir, cores, opt=opt)
    try:
        run.build()
        return run.pan(["-E", "-n"], timeout)
    finally:
        run.cleanup()


def verify_safety(space: StateSpace, monitors: list[Monitor], cores: int = 1, bitstate: bool = False,
                  hash_bits: int = 27, workdir=None, timeout: float | None = None, opt: str = "-O2",
                  progress=None) -> SpinResult:
    """Assertion violations of the observers (deadlocks ignored); the first trail is read back."""
    run = SpinRun(space, workdir, cores, bitstate, hash_bits, opt=opt)
    try:
        run.build(monitors)
        args = ["-E", "-c1", "-n"]
        if bitstate:
            args.append(f"-w{hash_bits}")
        report = run.pan(args, timeout, progress)
        trails = [run.trail(p, m) for p, m in zip(report.trails[:1], report.messages)]
        return SpinResult(report, trails, "safety", run.dir if run.keep else None)
    finally:
        run.cleanup()


def swarm(space: StateSpace, runs: int, monitors: list[Monitor] | None = None, hash_bits: int = 24,
          parallel: int | None = None, timeout: float | None = None, opt: str = "-O2") -> SpinResult:
    """Several bitstate searches with different hash functions and transition orders; findings merged.

    Each run covers a different random part of a state space too large for
    one exhaustive search; together they find errors with high probability.
    The merged state count is the largest of the runs (a lower bound).
    """
    base = SpinRun(space, None, 1, True, hash_bits, opt=opt)
    try:
        base.build(monitors)
        args = (["-E"] if monitors else []) + ["-c1", "-n", f"-w{hash_bits}", "-rhash"]
        parallel = parallel or os.cpu_count() or 1
        procs: list[tuple[Path, subprocess.Popen]] = []
        reports: list[tuple[Path, PanReport]] = []
        seeds = list(range(1, runs + 1))
        while seeds or procs:
            while seeds and len(procs) < parallel:
                seed = seeds.pop(0)
                sub = base.dir / f"run{seed}"
                sub.mkdir()
                for name in ("pan", "model.pml"):
                    shutil.copy2(base.dir / name, sub / name)
                p = subprocess.Popen(["./pan", f"-m{DEPTH}", *args, f"-RS{seed}", f"-h{seed % 500}"], cwd=sub,
                                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
                procs.append((sub, p))
            sub, p = procs.pop(0)
            try:
                out, _ = p.communicate(timeout=timeout)
            except subprocess.TimeoutExpired:
                p.kill()
                out, _ = p.communicate()
            rep = parse_pan(out)
            rep.trails = sorted(sub.glob("model.pml*.trail"), key=_trail_order)
            reports.append((sub, rep))
        merged = PanReport()
        trails: list[SpinTrail] = []
        for sub, rep in reports:
            merged.states = max(merged.states, rep.states)
            merged.transitions = max(merged.transitions, rep.transitions)
            merged.errors += rep.errors
            merged.seconds = max(merged.seconds, rep.seconds)
            merged.memory_mb = max(merged.memory_mb, rep.memory_mb)
            merged.vector = rep.vector
            merged.complete = False
            if rep.trails and not trails:
                done = subprocess.run(["./pan", "-r", rep.trails[0].name, "-S", "-n"], cwd=sub, capture_output=True,
                                      text=True)
                steps, end = space.replay_markers(_markers(done.stdout))
                trails.append(SpinTrail(steps, rep.messages[0] if rep.messages else "error", end))
        merged.messages = [f"{len(reports)} bitstate runs"]
        return SpinResult(merged, trails, "swarm")
    finally:
        base.cleanup()
