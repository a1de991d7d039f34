"""One atom as an automaton (paper Fig. 3 and 6): places, transitions labelled with port, guard and codel."""
from __future__ import annotations

import re

from runtime.bip2.printer import expr
from runtime.codels import codel_specs
from runtime.engine.flatten import FlatSystem
from runtime.model import AtomType
from runtime.model.expressions import calls
from runtime.pictures import style
from runtime.pictures.dot import Dot

_OUTCOME = re.compile(r"^outcome == (\d+)")


def automaton(flat: FlatSystem, atom: str) -> str:
    """The automaton of atom instance ``atom`` (a dotted path, e.g. ``NDD.GoTo.activity``)."""
    found = next((a for a in flat.atoms if a.name == atom), None)
    if found is None:
        raise KeyError(atom)
    t: AtomType = found.type
    specs = codel_specs(flat.package)
    called: dict[str, str] = {}  # place -> the codel extern whose outcome its internal transitions read
    dot = Dot(atom, rankdir="LR", fontname=style.FONT, label=f"{atom} : {t.name}", labelloc="t", nodesep="0.3")
    style.start(dot)
    dot.node("__initial__", label="", shape="point", width=0.12)
    initial = t.initial.targets if t.initial else []
    for place in t.places:
        dot.node(place, label=place, shape="ellipse", style="filled",
                 fillcolor="#fff4d6" if place in initial else "#ffffff",
                 peripheries=2 if place in initial else 1)
    for place in initial:
        dot.edge("__initial__", place)
    for tr in t.transitions:
        for stmt in tr.action:
            for name in calls(stmt):
                if name in specs:
                    for target in tr.targets:
                        called[target] = name
    for tr in t.transitions:
        parts = [tr.port] if tr.port else []
        if tr.guard is not None:
            guard = expr(tr.guard)
            parts.append(f"[{guard}]{_yield_name(guard, specs.get(called.get(tr.sources[0], '')))}")
        codels = [specs[n].codel if n in specs else f"{n}()" for s in tr.action for n in calls(s)]
        if codels:
            parts.append("/ " + ", ".join(codels))
        attrs = {"style": "dashed", "color": "#777777"} if tr.internal else {}
        for src in tr.sources:
            for dst in tr.targets:
                dot.edge(src, dst, label="\n".join(parts), **attrs)
    return str(dot)


def _yield_name(guard: str, spec) -> str:
    """`` (yield plan)`` when the guard tests the codel's outcome against one of its declared yields."""
    m = _OUTCOME.match(guard)
    if spec is None or m is None:
        return ""
    k = int(m.group(1))
    if k < len(spec.yields):
        return f"\n(yield {spec.yields[k]})"
    return f"\n(throw {spec.throws[k - len(spec.yields)]})" if k - len(spec.yields) < len(spec.throws) else ""
