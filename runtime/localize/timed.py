"""What a timing observer's verdict hangs on: the atoms localization keeps from its first round.

An observer (an atom type annotated ``@observer(open=..., close=...)``, the
period and latency observers of a ``--timed`` model) reaches ``ERROR`` when
too many ticks pass between its open and close events.  Time passes only when
every atom of the tick rendezvous lets it, so the close event is forced in time
by the atoms that take part in it and by the atoms beside them that can refuse
the tick: a timer whose period is due, a scheduler with a codel to run.  As
free atoms they would let time pass for ever; refinement would then add every
atom of the tick rendezvous (each took part in the counterexample's ticks),
the whole level's timers and schedulers at once, where these few suffice.
The seed only chooses where the rounds start: soundness is the abstraction's.
"""
from __future__ import annotations

from runtime.engine.flatten import FlatSystem
from runtime.explore.timed import TICK
from runtime.localize.abstraction import always_ready


def observer_seed(flat: FlatSystem, atom: int) -> set[int]:
    """The observer ``atom``, the atoms its close event changes, and their neighbours that can refuse the tick;
    empty when the atom is no observer."""
    fa = flat.atoms[atom]
    spec = next((a.arguments for a in fa.type.annotations if a.name == "observer"), None)
    if spec is None or spec.get("close") not in fa.ports:
        return set()
    ticking = {p for fc in flat.connectors if fc.top and fc.label == TICK for p in flat.leaves(fc)}
    refusers = {flat.ports[p].atom for p in ticking if not always_ready(flat, p)}
    close = fa.ports[spec["close"]]
    forcing = {flat.ports[p].atom for fc in _tops(flat, close) for p in flat.leaves(fc)
               if flat.ports[p].atom != atom and not always_ready(flat, p)}
    beside = {flat.ports[p].atom for a in forcing for fp in flat.atoms[a].ports.values() for fc in _tops(flat, fp)
              if fc.label != TICK for p in flat.leaves(fc)}
    return {atom} | forcing | (beside & refusers)


def _tops(flat: FlatSystem, port: int):
    """The top connectors a port takes part in (through sub-connectors too)."""
    return [fc for fc in flat.connectors if fc.top and port in flat.leaves(fc)]
