"""The explored LTS as Aldebaran ``.aut`` text (CADP, mCRL2) and as a Graphviz DOT graph.

Both need every state expanded with its successors kept (``StateSpace(...,
keep_edges=True)`` and a complete exploration).  States are numbered as the
explorer numbered them, the initial state first.  An ``.aut`` file has one
initial state: when initial transitions branch on codel outcomes, a fresh
state is added with an ``i`` (internal) transition to each of them.
"""
from __future__ import annotations

from typing import TextIO

from runtime.explore.space import StateSpace


def _quote(label: str) -> str:
    return '"' + label.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _expanded(space: StateSpace) -> None:
    missing = [sid for sid in range(len(space)) if sid not in space.edges]
    if missing:
        raise ValueError(f"{len(missing)} state(s) are not expanded (the exploration stopped at a limit, or "
                         "edges were not kept): the LTS would be wrong")


def write_aut(space: StateSpace, out: TextIO) -> tuple[int, int]:
    """Write ``des (initial, transitions, states)`` and one ``(from, "label", to)`` line per transition."""
    _expanded(space)
    n = len(space)
    extra = len(space.initial_ids) > 1
    transitions = sum(len(t) // 2 for t in space.edges.values()) + (len(space.initial_ids) if extra else 0)
    initial = n if extra else space.initial_ids[0]
    out.write(f"des ({initial}, {transitions}, {n + (1 if extra else 0)})\n")
    if extra:
        for sid in space.initial_ids:
            out.write(f'({n}, "i", {sid})\n')
    labels = [_quote(lab) for lab in space.labels]
    for sid in range(n):
        succ = space.edges[sid]
        for k in range(0, len(succ), 2):
            out.write(f"({sid}, {labels[succ[k]]}, {succ[k + 1]})\n")
    return n + (1 if extra else 0), transitions


def write_dot(space: StateSpace, out: TextIO, describe: bool = True) -> tuple[int, int]:
    """A DOT digraph: initial states bold, deadlocks double circles; tooltips show each state per atom."""
    _expanded(space)
    out.write("digraph lts {\n  rankdir=LR;\n  node [shape=circle, fontsize=10];\n  edge [fontsize=9];\n")
    count = 0
    for sid in range(len(space)):
        attrs = []
        if sid in space.initial_ids:
            attrs.append("style=bold")
        if not space.edges[sid]:
            attrs.append("shape=doublecircle, color=red")
        if describe:
            text = space.engine.format_state(space.engine_state(sid)).replace("\\", "\\\\").replace('"', '\\"')
            attrs.append(f'tooltip="{text.replace(chr(10), "&#10;")}"')
        out.write(f"  {sid}" + (f" [{', '.join(attrs)}]" if attrs else "") + ";\n")
    for sid in range(len(space)):
        succ = space.edges[sid]
        for k in range(0, len(succ), 2):
            out.write(f"  {sid} -> {succ[k + 1]} [label={_quote(space.labels[succ[k]])}];\n")
            count += 1
    out.write("}\n")
    return len(space), count
