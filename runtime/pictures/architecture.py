"""The functional level (paper Fig. 1) and one module as a compound (Fig. 7), as DOT text."""
from __future__ import annotations

from collections import defaultdict

from runtime.pictures import style
from runtime.pictures.dot import Dot
from runtime.pictures.structure import Link, Structure


def _short(label: str) -> str:
    """``NDD.GoTo:exec_plan`` -> ``exec_plan``."""
    return label.rsplit(":", 1)[-1]


def functional_level(s: Structure) -> str:
    """Modules with their services and posters, the data flow between them, and the links that cross modules."""
    dot = Dot(s.system, rankdir="LR", fontname=style.FONT, label=f"functional level {s.system}", labelloc="t",
              nodesep="0.4", ranksep="1.1")
    style.start(dot)
    kinds: list[str] = []
    services: dict[str, list[str]] = defaultdict(list)
    for owner in dict.fromkeys(s.owners.values()):
        module, name = owner.split(".", 1)
        period = s.periods.get(owner)
        services[module].append(f"{name} ({period})" if period else name)
    posters = {(a.split(".", 1)[0], a.rsplit(".", 1)[-1]) for a, r in s.roles.items() if r == "poster"}
    for module in s.modules:
        with dot.cluster(label=module, style="rounded", color="#7a8ca8", fontname=style.FONT, fontsize=13):
            names = services.get(module, [])
            dot.node(module, label="\n".join(names) or module, **style.NODES["control"])
            for m, p in sorted(posters):
                if m == module:
                    dot.node(f"{m}.{p}", label=p, **style.NODES["poster"])
                    dot.edge(module, f"{m}.{p}", **style.EDGES["write"][0])
                    kinds.append("write")
    for f in s.flows:
        dot.edge(f"{f.module}.{f.poster}", f.reader, label=", ".join(f.codels), **style.EDGES["read"][0])
        kinds.append("read")
    crossing: dict[tuple[str, str, str], list[str]] = defaultdict(list)
    for link in s.links:
        a, b = s.module_of(link.tail), s.module_of(link.head)
        if a == b or link.kind not in ("constraint", "rule", "interrupts"):
            continue
        what = (f"{s.owner_of(link.tail)} interrupts {s.owner_of(link.head)}" if link.kind == "interrupts"
                else f"{', '.join(link.rules) or link.label}:\n{s.owner_of(link.head)} guarded by "
                     f"{s.owner_of(link.tail)}")
        if what not in crossing[(a, b, link.kind)]:
            crossing[(a, b, link.kind)].append(what)
    for (a, b, kind), texts in crossing.items():
        dot.edge(a, b, label="\n".join(texts), constraint="false", **style.EDGES[kind][0])
        kinds.append(kind)
    style.legend(dot, kinds)
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
    dot = Dot(name, rankdir="TB", compound="true", fontname=style.FONT, label=f"module {name}", labelloc="t",
              nodesep="0.35", ranksep="0.7", newrank="true")
    style.start(dot)
    groups: dict[str, list[str]] = defaultdict(list)
    for a in mine:
        groups[s.owners.get(a) or (a.rsplit(".", 1)[0] if a.count(".") > 1 else "")].append(a)
    with dot.cluster(label=name, style="rounded", color="#7a8ca8", fontsize=13, fontname=style.FONT):
        for group, atoms in groups.items():
            if not group:
                for a in atoms:
                    dot.node(a, label=_atom_label(s, a), **style.NODES[s.roles.get(a, "atom")])
                continue
            with dot.cluster(label=group.split(".", 1)[1], style="rounded,filled", fillcolor="#fafafa",
                             color="#b8c2d6", fontname=style.FONT, fontsize=11):
                for a in atoms:
                    dot.node(a, label=_atom_label(s, a), **style.NODES[s.roles.get(a, "atom")])
    by_module: dict[str, list[str]] = defaultdict(list)
    for a in outside:
        by_module[s.module_of(a)].append(a)
    for other, atoms in by_module.items():
        with dot.cluster(label=f"{other} (other module)", style="dashed", color="#aaaaaa", fontname=style.FONT):
            for a in atoms:
                dot.node(a, label=_atom_label(s, a), **style.NODES["outside"])
    kinds = _edges(dot, links)
    style.legend(dot, kinds)
    return str(dot)


def _edges(dot: Dot, links: list[Link]) -> list[str]:
    """One edge per (tail, head, kind), labelled with what its connectors do; returns the kinds drawn."""
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
        label = texts[0] if len(texts) == 1 else f"{texts[0]} … (+{len(texts) - 1})" if len(texts) > 4 else \
            "\n".join(texts)
        dot.edge(tail, head, label=label, **style.EDGES[kind][0])
    return [kind for _, _, kind in merged]
