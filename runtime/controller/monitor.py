"""Online monitoring: the model's observer atoms, run on the controller's clock instead of ticks.

A model generated with observers (``genom2bip ... --monitor``, or
``--timed``) has an atom per observer, annotated
``@observer(kind=..., open=..., close=..., bound=...)``: the ports that start
and end what it measures, and the parameter holding its bound, in units of
the package's ``@monitored(tick_us=...)`` (or ``@timed``).  Its ports join
the interactions it watches.  While the controller runs, the monitor
measures on the controller's clock the time from an interaction that opens
an observer to the one that closes it; more than the bound is a violation,
reported once, as soon as the controller sees it (at the end of the step
that exceeds it), as an ``observer`` event: the observer, the bound, the time
measured and the interactions fired since it opened (the last ``KEEP``), with
their times since the run started.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Any, Callable

#: How many events of an open observation are kept for its report.
KEEP = 32


def _annotation(atom_type, name: str) -> dict[str, str] | None:
    return next((a.arguments for a in atom_type.annotations if a.name == name), None)


@dataclass
class Watch:
    """One observer atom: which port paths open and close it, its bound (s), the observation under way."""

    name: str  # the observer's instance path, e.g. "NDD.motion.overrun"
    kind: str
    bound: float
    opening: str
    closing: str
    opened: float | None = None
    reported: bool = False
    events: deque = field(default_factory=lambda: deque(maxlen=KEEP))
    violations: int = 0


class Monitor:
    """The observers of a flat system; ``step()`` after every fired interaction returns the violation events."""

    def __init__(self, watches: list[Watch]) -> None:
        self.watches = watches
        self.by_port: dict[str, list[tuple[Watch, bool]]] = {}
        for w in watches:
            self.by_port.setdefault(w.opening, []).append((w, True))
            self.by_port.setdefault(w.closing, []).append((w, False))
        self.start_time = 0.0
        #: observer name -> what to do on a violation (e.g. request a recovery service); set by the run options
        self.actions: dict[str, Callable[[dict[str, Any]], None]] = {}

    @classmethod
    def of(cls, flat, package) -> "Monitor | None":
        """The monitor of a model with observers, or None when it has none."""
        unit = next((a.arguments for a in package.annotations if a.name in ("monitored", "timed")), None)
        if unit is None:
            return None
        tick = int(unit.get("tick_us", "1")) / 1e6
        watches = []
        for atom in flat.atoms:
            spec = _annotation(atom.type, "observer")
            if spec is None:
                continue
            bound = atom.constants[spec["bound"]][0] * tick
            watches.append(Watch(atom.name, spec["kind"], bound, f"{atom.name}.{spec['open']}",
                                 f"{atom.name}.{spec['close']}"))
        return cls(watches) if watches else None

    def start(self, now: float) -> None:
        self.start_time = now
        for w in self.watches:
            w.opened, w.reported = None, False
            w.events.clear()

    def step(self, ports, label: str, began: float, now: float) -> list[dict[str, Any]]:
        """The interaction with atom ``ports`` fired at ``began`` (``now`` is after it): violations to report."""
        out = []
        touched = set()
        for p in ports:
            for w, opens in self.by_port.get(p, ()):
                touched.add(w.name)
                if opens:
                    if w.opened is None:
                        w.opened, w.reported = began, False
                        w.events.clear()
                    w.events.append((label, began))
                elif w.opened is not None:
                    w.events.append((label, began))
                    took = began - w.opened
                    if took > w.bound and not w.reported:
                        out.append(self._violation(w, took))
                    w.opened = None
        for w in self.watches:
            if w.opened is None:
                continue
            if w.name not in touched:  # what happened while it was open: the events that lead to a violation
                w.events.append((label, began))
            if not w.reported and now - w.opened > w.bound:
                out.append(self._violation(w, now - w.opened))
        return out

    def _violation(self, w: Watch, took: float) -> dict[str, Any]:
        w.reported = True
        w.violations += 1
        what = "period overran" if w.kind == "overrun" else "answer came late"
        event = {
            "observer": w.name, "kind": w.kind, "bound_ms": round(w.bound * 1e3, 3), "took_ms": round(took * 1e3, 3),
            "violations": w.violations,
            "events": [{"label": label, "at_ms": round((t - self.start_time) * 1e3, 3)} for label, t in w.events],
            "message": f"observer {w.name} violated: {what} after {took * 1e3:.1f} ms (bound {w.bound * 1e3:g} ms)",
        }
        action = self.actions.get(w.name)
        if action is not None:
            event["action"] = action(event)
        return {"event": "observer", **event}
