"""The functional level (paper Fig. 1) and one module as a compound (Fig. 7), as DOT text."""
from __future__ import annotations

from collections import defaultdict

from runtime.pictures import style
from runtime.pictures.dot import Dot, Html, escape, quote
from runtime.pictures.structure import Link, Structure


def _short(label: str) -> str:
    """``NDD.GoTo:exec_plan`` -> ``exec_plan``."""
    return label.rsplit(":", 1)[-1]


def _wrap(names: list[str], width: int = 24) -> str:
    """``names`` joined by commas, a new line before a name that would make a line longer than ``width``."""
    lines: list[str] = []
    for name in names:
        if lines and len(lines[-1]) + len(name) + 2 <= width:
            lines[-1] += f", {name}"
        else:
            lines[-1:] = [lines[-1] + ","] if lines else []
            lines.append(name)
    return "\n".join(lines)


def _module_table(module: str, rows: list[tuple[str, str, str]]) -> Html:
    """A module as one table: its name, then one row per (port id, text, role): tasks, services, posters."""
    shade = {"task": "#f3e8fc", "service": "#e8eefc", "poster": "#e6f1fb"}
    cells = "".join(f'<tr><td port="{port}" bgcolor="{shade[role]}" align="left">'
                    + (f"<i>{escape(text)}</i>" if role != "service" else escape(text)) + "</td></tr>"
                    for port, text, role in rows)
    return Html(f'<table border="0" cellborder="1" cellspacing="0" cellpadding="4" color="#7a8ca8">'
                f'<tr><td bgcolor="#d5deee"><b>{escape(module)}</b></td></tr>{cells}</table>')


def _grid(modules: list[str]) -> list[list[str]]:
    """Columns of two modules each, in the description's order, when there are more than four; else none (the
    data flow alone places them, left to right)."""
    if len(modules) <= 4:
        return []
    return [modules[k:k + 2] for k in range(0, len(modules), 2)]


def _labeller(grid: list[list[str]]):
    """How an edge between two modules is labelled: ``label``, or ``xlabel`` between two modules of one column.

    Two modules of one column are of one rank: dot lays the labels of every edge between them at one spot, over one
    another (three of them between NDD and POM).  An ``xlabel`` is placed once the layout is done, beside its edge
    and clear of the nodes and of the other labels.
    """
    column = {m: k for k, modules in enumerate(grid) for m in modules}

    def label(a: str, b: str, text: str | None) -> dict[str, str | None]:
        same = a in column and column.get(a) == column.get(b)
        return {"xlabel" if same else "label": text}

    return label


def functional_level(s: Structure) -> str:
    """Modules with their tasks, services and posters, the data flow between them, and the links that cross modules.

    Each module is one table (a row per task, service and poster): edges leave and reach the rows they are about,
    so that a rule needs only its id as label and the picture stays a few modules wide.
    """
    dot = Dot(s.system, rankdir="LR", fontname=style.FONT, labelloc="t", nodesep="0.3", ranksep="0.4")
    style.start(dot)
    kinds: list[str] = []
    rows: dict[str, list[tuple[str, str, str]]] = defaultdict(list)
    ports: dict[str, str] = {}  # "Module.Service" (or task, poster) -> its row's port
    for owner in dict.fromkeys(s.owners.values()):
        module, name = owner.split(".", 1)
        period = s.periods.get(owner)
        ports[owner] = f"s_{name}"
        rows[module].append((f"s_{name}", f"{name}: {period}" if period else name, "task" if period else "service"))
    for a, role in s.roles.items():
        if role == "poster":
            module, name = a.split(".", 1)[0], a.rsplit(".", 1)[-1]
            ports[f"{module}.{name}"] = f"p_{name}"
            rows[module].append((f"p_{name}", f"poster {name}", "poster"))
    for module in s.modules:
        dot.node(module, label=_module_table(module, rows.get(module, [])), shape="plain")
    grid = _grid(list(s.modules))
    for left, right in zip(grid, grid[1:]):  # more than four modules: two rows, so that it stays a screen wide
        for a, b in zip(left, right):
            dot.edge(a, b, style="invis", weight="10")
    label = _labeller(grid)
    for f in s.flows:
        where = {"constraint": "false", "tailport": ports[f'{f.module}.{f.poster}']} if grid else \
            {"tailport": f"{ports[f'{f.module}.{f.poster}']}:e"}
        dot.edge(f.module, f.reader, **label(f.module, f.reader, _wrap(f.codels)), **where, **style.EDGES["read"][0])
        kinds.append("read")
    crossing: dict[tuple[str, str, str], list[str]] = defaultdict(list)
    for link in s.links:
        a, b = s.module_of(link.tail), s.module_of(link.head)
        if a == b or link.kind not in ("constraint", "rule", "interrupts"):
            continue
        what = "" if link.kind == "interrupts" else ", ".join(link.rules) or link.label
        if what not in crossing[(s.owner_of(link.tail), s.owner_of(link.head), link.kind)]:
            crossing[(s.owner_of(link.tail), s.owner_of(link.head), link.kind)].append(what)
    for (tail, head, kind), texts in crossing.items():
        a, b = s.module_of(tail), s.module_of(head)
        dot.edge(a, b, **label(a, b, "\n".join(t for t in texts if t) or None),
                 tailport=ports.get(tail), headport=ports.get(head), constraint="false", **style.EDGES[kind][0])
        kinds.append(kind)
    dot.defaults("graph", label=style.title(f"functional level {s.system}", kinds))
    return str(dot)


def _atom_label(s: Structure, atom: str) -> str:
    role = s.roles.get(atom, "atom")
    name = atom.rsplit(".", 1)[-1]
    owner = s.owners.get(atom)
    if role in ("control", "activity") and owner:
        return f"{owner.split('.', 1)[1]}\n{role}"
    return name if role != "requests" else "request acceptor"


def module(s: Structure, name: str) -> str:
    """One module as a compound: services (controller + activity), tasks, posters, acceptor, and its connectors.

    Atoms of other modules that its connectors bind are drawn dashed, outside.
    """
    mine = [a for a in s.atoms if s.module_of(a) == name]
    if not mine:
        raise KeyError(name)
    links = [k for k in s.links if s.module_of(k.tail) == name or s.module_of(k.head) == name]
    outside = sorted({a for k in links for a in (k.tail, k.head) if s.module_of(a) != name})
    dot = Dot(name, rankdir="LR", compound="true", fontname=style.FONT, labelloc="t", nodesep="0.25",
              ranksep="0.5", newrank="true")
    style.start(dot)
    groups: dict[str, list[str]] = defaultdict(list)
    for a in mine:
        groups[s.owners.get(a) or (a.rsplit(".", 1)[0] if a.count(".") > 1 else "")].append(a)
    with dot.cluster(label=name, labeljust="l", style="rounded", color="#7a8ca8", fontsize=13, fontname=style.FONT):
        for group, atoms in groups.items():
            if not group:
                for a in atoms:
                    dot.node(a, label=_atom_label(s, a), **style.NODES[s.roles.get(a, "atom")])
                continue
            service = any(s.roles.get(a) == "control" for a in atoms)  # a service's atoms say its name
            # (an empty label, not none: a cluster without one takes its parent's, the module's name)
            with dot.cluster(label="" if service else group.split(".", 1)[1], style="rounded,filled",
                             fillcolor="#fafafa", color="#b8c2d6", fontname=style.FONT, fontsize=style.NODE_SIZE):
                for a in atoms:
                    dot.node(a, label=_atom_label(s, a), **style.NODES[s.roles.get(a, "atom")])
    by_module: dict[str, list[str]] = defaultdict(list)
    for a in outside:
        by_module[s.module_of(a)].append(a)
    for other, atoms in by_module.items():
        with dot.cluster(label=f"{other} (other module)", style="dashed", color="#aaaaaa", fontname=style.FONT):
            for a in atoms:
                dot.node(a, label=_atom_label(s, a), **style.NODES["outside"])
    # Atoms of other modules that only guard or interrupt this one come first, those it only guards come last: no
    # edge then joins two atoms of one rank, where Graphviz would lay their labels over one another.
    heads = {k.head for k in links}
    tails = {k.tail for k in links}
    for rank, atoms in (("min", [a for a in outside if a not in heads]),
                        ("max", [a for a in outside if a not in tails])):
        if atoms:
            dot.line(f"{{rank={rank}; {' '.join(quote(a) for a in atoms)}}}")
    kinds = _edges(dot, links, s)
    dot.defaults("graph", label=style.title(f"module {name}", kinds))
    return str(dot)


def _edges(dot: Dot, links: list[Link], s: Structure) -> list[str]:
    """One edge per (tail, head, kind), labelled with what its connectors do; returns the kinds drawn.

    An edge between the controller and the activity of one service is left unlabelled: it is always start, finish,
    fail and interrupted, and five copies of those words crowded the picture.
    """
    merged: dict[tuple[str, str, str], list[str]] = defaultdict(list)
    aborted = {(k.tail, k.head.rsplit(".", 1)[0]) for k in links if k.kind == "interrupts" and "abort" in k.ports}
    for k in links:
        if k.tail == k.head or (k.kind == "interrupts" and "abort" not in k.ports
                                and (k.tail, k.head.rsplit(".", 1)[0]) in aborted):
            continue  # a victim's cancel port goes with its abort port: one arrow per interruption
        text = (", ".join(k.rules) if k.kind in ("constraint", "rule") else
                "interrupts" if k.kind == "interrupts" else _short(k.label))
        if text not in merged[(k.tail, k.head, k.kind)]:
            merged[(k.tail, k.head, k.kind)].append(text)
    for (tail, head, kind), texts in merged.items():
        label = _wrap(texts) if len(texts) <= 4 else f"{texts[0]} ... (+{len(texts) - 1})"
        if kind == "sync" and s.owners.get(tail) and s.owners.get(tail) == s.owners.get(head) \
                and {s.roles.get(tail), s.roles.get(head)} == {"control", "activity"}:
            label = None
        dot.edge(tail, head, label=label, **style.EDGES[kind][0])
    return [kind for _, _, kind in merged]
