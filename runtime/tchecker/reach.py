"""Reachability of a set of location labels in a TChecker file, by the zone engine on its translation.

The search is runtime/zones/search.py's, on the timed BIP model of
runtime/tchecker/translate.py; it stops at the first symbolic state whose
locations carry every label asked for.  A trace to it is made concrete and
replayed on the tick model (runtime/zones/trace.py), so the delays printed
are those of a run of the model.
"""
from __future__ import annotations

import resource
import time
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

from runtime.diagnostics import DiagnosticError
from runtime.tchecker.syntax import read
from runtime.tchecker.system import System, check
from runtime.tchecker.translate import Translation, translate


@dataclass
class Reach:
    verdict: str  # "reachable", "unreachable", "unknown" (stopped at a limit)
    states: int  # symbolic states stored
    discrete: int  # distinct discrete states among them
    kept: int  # stored states no larger zone came to cover
    transitions: int  # symbolic transitions computed
    seconds: float  # the search (what tck-reach's RUNNING_TIME_SECONDS measures of its own)
    zone_bytes: int  # what the search holds (ZoneExplorer.memory)
    peak_rss: int  # bytes, the whole process
    grid: int  # strict constraints read on a 1/grid time grid (1: no strict constraint)
    exact: bool  # the verdict is dense time's (False: unreachable on the grid only)
    trace: list[tuple[Fraction, str]] = field(default_factory=list)  # (delay before, global edge)
    trace_note: str = ""
    stopped: str = ""  # "max-states" or "time-limit" when the verdict is unknown
    unknown_labels: list[str] = field(default_factory=list)  # carried by no location
    build_seconds: float = 0.0  # the zone model built from the translation, before the search


def load(path: str | Path, grid: int | None = None, keep_integers: bool = False) -> tuple[System, Translation]:
    """Read, check and translate a TChecker file; strict clock constraints need ``grid`` (a located error else)."""
    src, decls = read(path)
    system = check(src, decls)
    if system.strict is not None and grid is None:
        raise src.error(system.strict, "strict clock constraint: the zone engine's bounds are integers",
                        hint="give --grid N to read 'x < c' as 'x <= c - 1/N' (a reachable verdict stays exact; "
                             "an unreachable one then holds on that time grid)")
    if grid is not None and grid < 1:
        raise DiagnosticError([])  # pragma: no cover - the command line checks it first
    return system, translate(system, grid or 1, keep_integers)


def explorer(tr: Translation, invariants: bool = True, **options):
    """The zone explorer of a translated file: each place's LU bounds, no merging (tck-reach's covreach keeps
    zones apart), and invariants part of the state, as a TChecker location's are; ``options`` change
    ZoneExplorer's."""
    from runtime.zones.search import ZoneExplorer

    return ZoneExplorer(tr.package, tr.root, **({"local_ceilings": True, "merge": False} | options),
                        invariants=invariants)


class _Goal:
    """Which places of which atoms carry each label, as the zone explorer's atom indices and place bits."""

    def __init__(self, z, tr: Translation, labels: list[str]) -> None:
        self.need = []
        by_name = {fa.name.rsplit(".", 1)[-1]: fa for fa in z.flat.atoms}
        for lab in labels:
            where = []
            for atom, place in tr.labels.get(lab, ()):
                fa = by_name[atom]
                where.append((fa.offset, fa.place_mask([place])))
            self.need.append(where)


class _OutOfTime(Exception):
    def __init__(self, transitions: int) -> None:
        super().__init__("time limit")
        self.transitions = transitions


def _deadline(seconds: float | None, show):
    """A progress that also stops the search (by raising) once ``seconds`` have passed."""
    from runtime.explore.progress import Progress, null_progress

    shown = show or null_progress()
    if seconds is None:
        return shown
    end = time.monotonic() + seconds

    class Deadline(Progress):
        def tick(self, states, transitions, frontier, memory, depth=None):
            shown.tick(states, transitions, frontier, memory, depth)
            if time.monotonic() > end:
                raise _OutOfTime(transitions)

        def done(self):
            shown.done()

    return Deadline(enabled=False)


def reach(path: str | Path, labels: list[str], grid: int | None = None, max_states: int | None = None,
          progress=None, want_trace: bool = True, time_limit: float | None = None) -> Reach:
    """Is a configuration whose locations carry every label of ``labels`` reachable?  ``unknown`` when the
    search stops at ``max_states`` or after ``time_limit`` seconds."""
    from runtime.zones.node import GOAL

    system, tr = load(path, grid)
    unknown = [lab for lab in labels if lab not in system.labels()]
    goal_set = bool(labels) and not unknown

    start = time.perf_counter()
    z = explorer(tr)
    if goal_set:
        z.goal = _Goal(z, tr, labels).need
    z.prepare()  # the C search set up before it starts, as tck-reach's model is built before its clock starts
    watch = _deadline(time_limit, progress)
    built = time.perf_counter()
    try:
        result = z.explore(max_states=max_states, progress=watch, stop_at_violation=True)
    except _OutOfTime as stop:
        (progress or _deadline(None, None)).done()
        result = z.result
        result.complete, result.stopped = False, "time-limit"
        if z.search is None:  # the Python search counts its discrete states when it ends, which it did not
            result.states, result.discrete = len(z.nodes), len({n.state for n in z.nodes})
            result.transitions = stop.transitions
    seconds = time.perf_counter() - built
    found = result.violations.get(GOAL)
    if found is not None:
        verdict = "reachable"
    elif result.complete:
        verdict = "unreachable"
    else:
        verdict = "unknown"
    kept = int((~z.graph().covered).sum())
    out = Reach(verdict, result.states, result.discrete, kept, result.transitions, seconds, z.memory(),
                resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024, tr.scale,
                verdict == "reachable" or system.strict is None)
    out.unknown_labels = unknown
    out.stopped = result.stopped
    out.build_seconds = built - start
    if found is not None and want_trace:
        out.trace, out.trace_note = _trace(z, tr, found)
    return out


Configuration = tuple[tuple[str, ...], tuple[tuple[str, int], ...]]


def configurations(path: str | Path, grid: int | None = None, **search) -> set[Configuration]:
    """The reachable configurations of a TChecker file without their clocks: each process's location (in file
    order) and the integer variables, every one kept (no dead-variable reduction).  What ``tck-reach -C graph``
    lists, to compare with it.  ``search``: the explorer's options (covreach's by default, see :func:`explorer`)."""

    system, tr = load(path, grid, keep_integers=True)
    z = explorer(tr, **search)
    z.explore()
    atoms = {fa.name.rsplit(".", 1)[-1]: fa for fa in z.flat.atoms}
    where = {(tr.atoms[p], place): loc for (p, loc), place in tr.places.items()}
    g = atoms.get("Globals")
    out = set()
    for n in z.nodes:
        locs = []
        for p in system.processes:
            fa = atoms[tr.atoms[p]]
            locs.append(where[(tr.atoms[p], fa.places[int(n.state[fa.offset]).bit_length() - 1])])
        if g is None:  # no edge reads or writes an integer: each keeps its initial value
            ints = tuple((v, iv.init) for v, iv in system.ints.items())
        else:
            ints = tuple((v, int(n.state[g.slot(tr.variables[v])])) for v in system.ints)
        out.add((tuple(locs), ints))
    return out


def _trace(z, tr: Translation, node: int) -> tuple[list[tuple[Fraction, str]], str]:
    from runtime.explore.space import StateSpace
    from runtime.zones.trace import ConcretizeError, paths_to, replay

    space = StateSpace(tr.package, tr.root, None, None, True, set())
    problem = "no path"
    try:
        for path in paths_to(z, node, []):
            try:
                steps, _ = replay(z, path, [], space)
            except ConcretizeError as exc:
                problem = str(exc)
                continue
            return [(Fraction(s.ticks, tr.scale), s.step.label) for s in steps if s.step.label], ""
    except ConcretizeError as exc:
        problem = str(exc)
    return [], f"no concrete trace: {problem}"
