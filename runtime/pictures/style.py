"""One look for every picture: fonts, and the colour and line style of each kind of link, with its legend."""
from __future__ import annotations

from runtime.pictures.dot import Dot, Html, escape

FONT = "Helvetica"
#: Point sizes: a picture shown at 85 % of its size on a page still has text of 11 px (1 pt = 4/3 px).
NODE_SIZE, EDGE_SIZE, TITLE_SIZE = 12, 10, 14

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

#: kind -> how its line looks, in words (the legend is text: a few lines, not a picture of its own)
LOOKS: dict[str, str] = {
    "sync": "grey", "write": "blue", "read": "blue dashed", "constraint": "green dashed", "rule": "red dashed",
    "interrupts": "orange, bar head",
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
    dot.defaults("node", fontname=FONT, fontsize=NODE_SIZE)
    dot.defaults("edge", fontname=FONT, fontsize=EDGE_SIZE)


def title(text: str, kinds: list[str], per_row: int = 3) -> Html:
    """The picture's title over a few lines of legend: each kind of link drawn, its look in its own colour.

    Text rather than sample edges: a legend of edges is laid out as part of the graph and took a third of it.
    """
    used = [k for k in EDGES if k in kinds]
    cells = [f'<td align="left"><font point-size="{EDGE_SIZE}"><font color="{EDGES[k][0]["color"]}"><b>'
             f"{escape(LOOKS[k])}</b></font>: {escape(EDGES[k][1])}</font></td>" for k in used]
    rows = "".join(f"<tr>{''.join(cells[i:i + per_row])}</tr>" for i in range(0, len(cells), per_row))
    legend = (f'<tr><td><table border="0" cellspacing="0" cellpadding="1">{rows}</table></td></tr>') if rows else ""
    return Html(f'<table border="0" cellspacing="0" cellpadding="2"><tr><td><font point-size="{TITLE_SIZE}">'
                f"{escape(text)}</font></td></tr>{legend}</table>")
