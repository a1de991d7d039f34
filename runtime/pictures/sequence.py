"""A trace as a sequence diagram: one lifeline per module (or atom), one arrow per interaction.

Laid out by us, not by Graphviz: every node carries its position and the
file is rendered with ``neato -n2``, so lifelines stay straight and steps
stay in order however long the trace.
"""
from __future__ import annotations

from typing import Any, Iterable

from runtime.pictures import style
from runtime.pictures.dot import Dot

X0, DX, Y_HEAD, DY = 90, 190, 60, 42


def participants(engine: Any, step: Any) -> list[str]:
    """The ``atom.port`` names a trace step binds (the initiator first); a bare label stands for its connectors."""
    if not isinstance(step, str):
        return list(engine.interaction(step.index).ports)
    flat = engine.flat
    return [flat.ports[p].path for c in flat.connectors if c.top and c.label == str(step) for p in flat.leaves(c)]


def _lifeline(port_path: str, by: str) -> str:
    """The lifeline of an atom port: its first-level component, its parent component, or its atom."""
    atom = port_path.rsplit(".", 1)[0]
    if by == "module":
        return atom.split(".", 1)[0]
    if by == "component":
        return atom.rsplit(".", 1)[0] if atom.count(".") > 1 else atom
    return atom


def _text_width(text: str, size: float = 9) -> float:
    """About how wide Helvetica draws ``text`` at ``size`` points, in picture units."""
    return len(text) * size * 0.55


def sequence(engine: Any, steps: Iterable[Any], ending: list[str], title: str = "", by: str = "auto") -> str:
    """DOT text (with fixed positions) of ``steps`` from the initial state, ``ending`` written at the bottom.

    ``by`` is ``"module"`` (one lifeline per first-level component),
    ``"component"`` (per parent of an atom: a service, a task), ``"atom"``, or
    ``"auto"``: modules when the trace crosses several, else components.
    """
    steps = list(steps)
    ports = [participants(engine, step) for step in steps]
    if by == "auto":
        modules = {_lifeline(p, "module") for ps in ports for p in ps}
        by = "module" if len(modules) > 1 else "component"
    rows = []
    for step, names in zip(steps, ports):
        rows.append((str(step), list(dict.fromkeys(_lifeline(p, by) for p in names))))
    order: list[str] = list(dict.fromkeys(line for _, lines in rows for line in lines))
    x = {name: X0 + i * DX for i, name in enumerate(order)}
    bottom = Y_HEAD + DY * (len(rows) + 1)
    height = bottom + 40 + 16 * len(ending)

    def pos(px: float, py: float) -> str:
        return f"{px:.0f},{height - py:.0f}!"

    dot = Dot(title or "trace", fontname=style.FONT, label=title, labelloc="t", splines="line")
    style.start(dot)
    for name in order:
        dot.node(f"head:{name}", label=name, pos=pos(x[name], Y_HEAD - 25), shape="box", style="filled",
                 fillcolor="#e8eefc", width=1.6)
        dot.node(f"foot:{name}", label="", pos=pos(x[name], bottom), shape="point", width=0.01)
        dot.edge(f"head:{name}", f"foot:{name}", arrowhead="none", style="dashed", color="#999999")
    for k, (text, lines) in enumerate(rows, 1):
        y = Y_HEAD + DY * k
        tail = lines[0] if lines else None
        if tail is None:
            continue
        dot.node(f"s{k}:{tail}", label="", pos=pos(x[tail], y), shape="point", width=0.06)
        for other in lines[1:]:
            dot.node(f"s{k}:{other}", label="", pos=pos(x[other], y), shape="point", width=0.04)
            dot.edge(f"s{k}:{tail}", f"s{k}:{other}", color="#1f5fbf")
        right = max(x[line] for line in lines)
        left = min(x[line] for line in lines)
        label = f"{k}. {text}"
        anchor = (left + right) / 2 if right > left else x[tail] + 10 + _text_width(label) / 2
        dot.node(f"t{k}", label=label, pos=pos(anchor, y - 11), shape="plaintext", fontsize=9, fontcolor="#222222",
                 width=0.01, height=0.01, margin=0)
    if ending:
        middle = (X0 + X0 + DX * max(len(order) - 1, 0)) / 2
        dot.node("end", label="\n".join(ending), pos=pos(middle, bottom + 20 + 8 * len(ending)), shape="note",
                 style="filled", fillcolor="#fdecea", color="#c0392b", fontsize=10)
    return str(dot)
