"""Deadlocks and properties by our explorer: the compiled one (default) or the Python one, with a note when it
falls back.

The compiled search answers deadlocks, model errors, deadlock freedom and
safety properties (through observers); LTS exports and the other properties
need the successor lists the Python explorer keeps, so they run there (a
note says so).  A model the C back end does not take, or a machine without a
C compiler, gets the Python explorer and a one-line note.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from genom2bip.verify.model import Model
from genom2bip.verify.options import Listener, Notes, SearchOptions
from genom2bip.verify.results import (
    LIMITS, Deadlock, DeadlockResult, Figures, ModelError, PropertyResult, Trace, Verdict,
)


def extern_bindings(spec: str | None) -> dict[str, Any]:
    """The public names of the Python module ``spec``, binding extern functions that are not codels."""
    if not spec:
        return {}
    from runtime.engine.externs import load_module

    module = load_module(spec)
    return {k: getattr(module, k) for k in dir(module) if not k.startswith("_")}


def state_space(model: Model, options: SearchOptions, properties=(), keep_edges: bool = False):
    """The explorer's state space of ``model`` (``runtime.explore.StateSpace``), keeping what ``properties`` read."""
    from runtime.explore import StateSpace

    observed = set().union(*(p.observed for p in properties)) if properties else set()
    return StateSpace(model.package, model.root, extern_bindings(options.externs), options.requests, options.reduce,
                      observed, keep_edges=keep_edges, max_states=options.max_states)


@dataclass
class Exploration:
    """One exhaustive search: the runtime's result, what gives its traces (the compiled space or the state space)."""

    result: Any  # runtime.explore.ExploreResult
    view: Any
    notes: list[str] = field(default_factory=list)

    @property
    def figures(self) -> Figures:
        r = self.result
        return Figures(r.states, r.transitions, r.seconds, r.memory or None, r.depth)

    @property
    def limit(self) -> str:
        return self.result.stopped_by if not self.result.complete and self.result.stopped_by in LIMITS else ""

    @property
    def model_error(self) -> ModelError | None:
        e = self.result.error
        return None if e is None else ModelError(e.message, e.state, Trace(list(e.trace)))


def explore(space, options: SearchOptions, listener: Listener | None = None, lts: bool = False) -> Exploration:
    """Number every reachable state up to the limits (``lts``: keep every successor list, for an export)."""
    from runtime.explore import explore as python_explore

    listener = listener or Listener()
    notes = Notes(listener)
    if options.compiled:
        if lts:
            notes("LTS exports need every successor list: exploring with the Python step")
        else:
            found = _compiled(space, options, listener, notes)
            if found is not None:
                return Exploration(*found, notes.lines)
    if options.por:
        notes("no partial-order reduction in the Python explorer: every interleaving is explored")
    if options.workers != 1 or options.store != "exact":
        notes("the Python explorer runs on one thread over exact states (--workers and --store are the compiled "
              "explorer's)")
    max_bytes = options.max_bytes
    _say_unbounded(options, listener, max_bytes)
    result = python_explore(space, options.max_depth, options.dfs, listener.progress(), max_bytes=max_bytes)
    if result.stopped_by == "max-memory":
        notes(f"the Python search stopped past {max_bytes / 2**20:,.0f} MB (--max-memory MB sets the bound)")
    return Exploration(result, space, notes.lines)


def check_deadlock(space, options: SearchOptions, listener: Listener | None = None, lts: bool = False,
                   exploration: Exploration | None = None) -> DeadlockResult:
    """Every reachable deadlock, each with a trace (shortest unless depth-first or reduced), by one exploration."""
    found = exploration or explore(space, options, listener, lts)
    result, view = found.result, found.view
    initial = view.engine.describe_state(view.concrete([])) if result.deadlocks else {}
    deadlocks = []
    for sid in result.deadlocks:
        steps = view.trace_to(sid)
        state = view.concrete(steps)
        deadlocks.append(Deadlock(sid, Trace(steps), view.engine.format_state(state),
                                  moved_atoms(view.engine, initial, state)))
    error = found.model_error
    verdict = (Verdict.ERROR if error is not None else Verdict.VIOLATED if deadlocks
               else Verdict.HOLDS if result.complete else Verdict.INCONCLUSIVE)
    trace = error.trace if error is not None else deadlocks[0].trace if deadlocks else None
    method = "compiled search" if view is not space else "Python search"
    return DeadlockResult("deadlock freedom", verdict, found.figures, trace, method, found.limit,
                          error.message if error is not None else "", _exhaustive(view), list(found.notes),
                          deadlocks=deadlocks, model_error=error, complete=result.complete,
                          shortest=not (options.dfs or options.por), summary=result.summary())


def moved_atoms(engine, initial: dict, state, most: int = 10) -> list[str]:
    """``atom: PLACE`` for the atoms that are not in their initial places (what a deadlock picture shows)."""
    now = engine.describe_state(state)
    moved = [f"{a}: {','.join(v['places']) or '-'}" for a, v in now.items() if v["places"] != initial[a]["places"]]
    return moved[:most] + ([f"… and {len(moved) - most} more atoms"] if len(moved) > most else [])


def check_property(space, item, options: SearchOptions, listener: Listener | None = None) -> PropertyResult:
    """One property (a ``runtime.props`` checkable): by the compiled search when it takes it, else the Python one."""
    from runtime.props import check

    listener = listener or Listener()
    notes = Notes(listener)
    verdict = None
    if options.compiled:
        from runtime.native.properties import compiled_check

        verdict = compiled_check(space, item, extern_bindings(options.externs), listener.progress(),
                                 options.max_states, options.max_bytes, por=options.por, **options.search())
        if verdict is not None:
            if getattr(verdict, "lossiness", None) is not None:
                notes(verdict.lossiness.line())
        else:
            notes(f"property {item.name} is checked with the Python step (the compiled search takes deadlock "
                  "freedom and [R] false / [R] {P} shapes, on models it compiles)")
    if verdict is None:
        verdict = check(space, item, listener.progress())
    return property_result(item, verdict, notes.lines)


def property_result(item, verdict, notes: list[str] = ()) -> PropertyResult:
    """A runtime verdict (``runtime.props.Verdict``) as a result."""
    from runtime.props import describe

    word = (Verdict.ERROR if verdict.error else Verdict.HOLDS if verdict.holds
            else Verdict.VIOLATED if verdict.holds is False else Verdict.INCONCLUSIVE)
    search = getattr(verdict, "result", None)  # the compiled search's own figures
    figures = Figures(verdict.states, search.transitions if search else None, verdict.seconds,
                      (search.memory or None) if search else None, search.depth if search else None)
    trace = Trace(list(verdict.trace), verdict.loop if verdict.loop >= 0 else None) if verdict.evidence else None
    return PropertyResult(describe(item), word, figures, trace, verdict.method, limit_of(verdict),
                          verdict.note, getattr(verdict, "lossiness", None) is None, list(notes),
                          name=item.name, evidence=verdict.evidence)


def limit_of(verdict) -> str:
    """The limit that stopped an inconclusive runtime verdict, from its search or its note ("" when none did)."""
    if verdict.holds is not None or verdict.error:
        return ""
    search = getattr(verdict, "result", None)
    if search is not None and search.stopped_by in LIMITS:
        return search.stopped_by
    note = verdict.note or ""
    if "state budget" in note:
        return "max-states"
    return next((limit for limit in LIMITS if limit in note), "")


def por_note(cs, states: int) -> str:
    """What the partial-order reduction did, in one line."""
    if not cs.por_available:
        return "no partial-order reduction: the request counts of --requests are shared by every service"
    return (f"partial-order reduction: {cs.reduced:,} of {states:,} states expanded with an ample set "
            "(deadlocks and safety verdicts as the full search; traces are shortest in the reduced graph only)")


def _exhaustive(view) -> bool:
    return getattr(view, "lossiness", None) is None


def _say_unbounded(options: SearchOptions, listener: Listener, max_bytes: int | None) -> None:
    if options.max_states is None and options.max_depth is None and max_bytes is not None:
        listener.unbounded(max_bytes)


def _compiled(space, options: SearchOptions, listener: Listener, notes: Notes):
    """``(result, compiled space)`` of the compiled search, or None (noted) where it cannot run."""
    from runtime.native.compiled import Diverged, compile_space

    cs, why = compile_space(space, extern_bindings(options.externs), search=True)
    if cs is None:
        notes(why)
        return None
    max_bytes = options.max_bytes
    _say_unbounded(options, listener, max_bytes)
    try:
        result = cs.explore(options.max_states, options.max_depth, options.dfs, listener.progress(),
                            max_bytes=max_bytes, por=options.por, **options.search())
    except Diverged as exc:
        notes(f"the compiled step met an integer past 64 bits ({exc}): exploring with the Python step")
        return None
    if options.por:
        notes(por_note(cs, result.states))
    if cs.lossiness is not None:
        notes(cs.lossiness.line() + "; traces are shortest among the states stored")
    if result.stopped_by == "max-memory":
        notes(f"the compiled search stopped at {result.memory / 2**20:,.0f} MB (--max-memory MB sets the bound)")
    return result, cs
