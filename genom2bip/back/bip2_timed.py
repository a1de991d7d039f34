"""The writer's side of timed BIP2: what it refuses in clocks, urgency, resume and invariants, and the resume clause."""
from __future__ import annotations

from runtime.bip2.printer import expr as print_expr
from runtime.model import AtomType
from runtime.model.timing import TIME_UNITS, URGENCIES, Resume


def resume_clause(r: Resume | None) -> list[tuple[str, str | None]]:
    """``resume (g)`` or ``resume`` as a clause for the writer's layout, nothing when there is no resume."""
    if r is None:
        return []
    return [("resume", None if r.guard is None else f"({print_expr(r.guard)})")]


def timed_atom_problems(writer, a: AtomType, where: str) -> None:
    """Add to ``writer`` what BIP2 cannot say about the clocks, urgencies, resumes and invariants of ``a``."""
    for c in a.clocks:
        writer.name(where, "clock", c.name)
        if c.unit is not None and c.unit not in TIME_UNITS:
            writer.add(f"{where}, clock {c.name}", f"unknown time unit '{c.unit}' (BIP2 has {', '.join(TIME_UNITS)})")
    for t in a.transitions:
        w = f"{where}, {'internal transition' if t.port is None else f'transition on {t.port}'}"
        if t.urgency is not None and t.urgency not in URGENCIES:
            writer.add(w, f"unknown urgency '{t.urgency}' (BIP2 has {', '.join(URGENCIES)})")
        if t.port is None and (t.urgency is not None or t.resume is not None):
            writer.add(w, "an internal transition has no urgency and no resume in BIP2")
        if t.resume is not None and t.resume.guard is not None:
            writer.expr(w, t.resume.guard)
    if a.initial is not None and a.initial.resume is not None and a.initial.resume.guard is not None:
        writer.expr(f"{where}, initial", a.initial.resume.guard)
    for inv in a.invariants:
        w = f"{where}, invariant {inv.name}"
        writer.name(w, "invariant", inv.name)
        for pl in inv.places:
            writer.name(w, "place", pl)
        if inv.guard is None:
            writer.add(w, "an invariant needs a condition ('provided (...)')")
        else:
            writer.expr(w, inv.guard)
