"""The timing observers of a timed model (a task's period, a latency): each checked as
``invariant not (OBS @ ERROR)``, one result per observer, whose trace carries the time of each step.

By the compiled explorer (the Python one with ``engine="python"``, or where
the C step does not take the model, with a note), or by localization on a
model too large to explore (:func:`genom2bip.verify.localized.check_observer_localized`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from genom2bip.verify.model import Model, tick_us
from genom2bip.verify.options import Listener, SearchOptions
from genom2bip.verify.results import ObserverResult, PropertyResult, timed

#: The kinds of observers: every one, or the period observers alone (schedulability).
KINDS = ("overrun", "latency")


@dataclass
class ObserverAtom:
    """An observer atom of the model: its instance path, its kind, its bound in ticks."""

    path: str
    kind: str  # "overrun" or "latency"
    bound: int  # ticks


def observer_atoms(package, root: str) -> list[ObserverAtom]:
    """Every instance of an ``@observer`` atom type under the root, by path."""
    out: list[ObserverAtom] = []

    def walk(type_name: str, prefix: str) -> None:
        compound = package.compound_type(type_name)
        if compound is None:
            return
        for c in compound.components:
            path = f"{prefix}.{c.name}" if prefix else c.name
            atom = package.atom_type(c.type)
            if atom is None:
                walk(c.type, path)
                continue
            ann = next((a for a in atom.annotations if a.name == "observer"), None)
            if ann is not None:
                bound = c.args[0].value if c.args and hasattr(c.args[0], "value") else 0
                out.append(ObserverAtom(path, ann.arguments.get("kind", "?"), int(bound)))

    walk(root.split("(")[0], "")
    return out


def observers(model: Model, kinds=KINDS) -> list[ObserverAtom]:
    """The observers of ``model`` of the given kinds, in the model's order."""
    return [a for a in observer_atoms(model.package, model.root) if a.kind in kinds]


def subject(atom: ObserverAtom, tick: int | None) -> str:
    """What an observer checks, in words: ``period of NDD.motion (100 ms)``, ``latency X (within 16 ms)``."""
    limit = f"{atom.bound * tick / 1000:g} ms" if tick else f"{atom.bound} ticks"
    return (f"period of {atom.path.rsplit('.', 1)[0]} ({limit})" if atom.kind == "overrun"
            else f"latency {atom.path} (within {limit})")


def error_property(model: Model, atom: ObserverAtom):
    """``invariant not (ATOM @ ERROR)`` as a checkable property of the model."""
    from runtime.props import read_property_text

    return read_property_text(f"invariant not ({atom.path} @ ERROR)", model.flat)


def check_observer(model: Model, atom: ObserverAtom, space=None, options: SearchOptions | None = None,
                   listener: Listener | None = None,
                   decide: Callable[[object], PropertyResult] | None = None) -> ObserverResult:
    """Is ``atom``'s ERROR place reachable?  By ``decide(item)`` when given (localization), else by the explorer
    on ``space`` (built when not given) with ``options``."""
    from genom2bip.verify.search import check_property, state_space

    options = options or SearchOptions()
    item = error_property(model, atom)
    if decide is not None:
        found = decide(item)
    else:
        found = check_property(space if space is not None else state_space(model, options), item, options, listener)
    tick = tick_us(model.package)
    trace = timed(found.trace.steps, tick) if found.trace is not None else None
    return ObserverResult(subject(atom, tick), found.verdict, found.figures, trace, found.method, found.limit,
                          found.message, found.exhaustive, found.notes, observer=atom.path, kind=atom.kind,
                          bound_ticks=atom.bound, tick_us=tick)


def check_observers(model: Model, kinds=KINDS, options: SearchOptions | None = None,
                    listener: Listener | None = None) -> list[ObserverResult]:
    """Every observer of the given kinds, one result each, on one state space."""
    from genom2bip.verify.search import state_space

    options = options or SearchOptions()
    space = state_space(model, options)
    return [check_observer(model, atom, space, options, listener) for atom in observers(model, kinds)]
