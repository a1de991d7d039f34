"""One look for every picture: fonts, and the colour and line style of each kind of link, with its legend."""
from __future__ import annotations

from runtime.pictures.dot import Dot

FONT = "Helvetica"

#: kind -> (edge attributes, legend text)
EDGES: dict[str, tuple[dict[str, str], str]] = {
    "sync": ({"color": "#444444"}, "rendezvous (codel, start, report)"),
    "write": ({"color": "#1f5fbf"}, "codel writes a poster"),
    "read": ({"color": "#1f5fbf", "style": "dashed"}, "codel reads a poster (port in)"),
    "constraint": ({"color": "#2e8b57", "style": "dashed", "penwidth": "1.6"},
                   "constraint of the description (after/before)"),
    "rule": ({"color": "#c0392b", "style": "dashed", "penwidth": "1.8"}, "rule of the rule file"),
    "interrupts": ({"color": "#e67e22", "penwidth": "2.2", "arrowhead": "tee"}, "interruption"),
}

#: atom role -> node attributes
NODES: dict[str, dict[str, str]] = {
    "requests": {"shape": "invhouse", "style": "filled", "fillcolor": "#fff4d6"},
    "control": {"shape": "box", "style": "rounded,filled", "fillcolor": "#e8eefc"},
    "activity": {"shape": "box", "style": "filled", "fillcolor": "#eef7ee"},
    "timer": {"shape": "box", "style": "filled", "fillcolor": "#f3e8fc"},
    "scheduler": {"shape": "box", "style": "filled", "fillcolor": "#f3e8fc"},
    "poster": {"shape": "cylinder", "style": "filled", "fillcolor": "#e6f1fb"},
    "atom": {"shape": "box"},
    "outside": {"shape": "box", "style": "dashed", "color": "#888888", "fontcolor": "#666666"},
}


def start(dot: Dot) -> None:
    """Default fonts for nodes and edges."""
    dot.defaults("node", fontname=FONT, fontsize=11)
    dot.defaults("edge", fontname=FONT, fontsize=9)


def legend(dot: Dot, kinds: list[str]) -> None:
    """A cluster that shows each kind of link drawn in the picture, in the order of ``EDGES``."""
    used = [k for k in EDGES if k in kinds]
    if not used:
        return
    with dot.cluster(label="legend", style="rounded", color="#bbbbbb", fontname=FONT, fontsize=10):
        for k in used:
            attrs, text = EDGES[k]
            dot.node(f"legend:{k}:a", label="", shape="point", width=0.05)
            dot.node(f"legend:{k}:b", label=text, shape="plaintext", fontsize=9)
            dot.edge(f"legend:{k}:a", f"legend:{k}:b", **attrs)
