"""A small writer of Graphviz DOT text: nodes, edges and clusters, with quoting done once."""
from __future__ import annotations

from contextlib import contextmanager
from typing import Iterator


def quote(text: object) -> str:
    """A DOT string literal: double quotes, with backslashes and quotes escaped, newlines as ``\\n``."""
    s = str(text).replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
    return f'"{s}"'


class Html(str):
    """An HTML-like label (a table): written between ``<`` and ``>``, not quoted; build it with :func:`escape`."""


def escape(text: object) -> str:
    """``text`` as it may appear inside an HTML-like label."""
    return str(text).replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")


def attributes(attrs: dict[str, object]) -> str:
    """``[a="1", b="x"]`` for the attributes that are not None (empty string when there are none)."""
    items = [f"{k}=<{v}>" if isinstance(v, Html) else f"{k}={quote(v)}" for k, v in attrs.items() if v is not None]
    return f" [{', '.join(items)}]" if items else ""


class Dot:
    """Accumulates the lines of one digraph; ``str(dot)`` is the finished text."""

    def __init__(self, name: str, **graph: object) -> None:
        self.lines = [f"digraph {quote(name)} {{"]
        self.depth = 1
        self.clusters = 0
        if graph:
            self.line(f"graph{attributes(graph)};")

    def line(self, text: str) -> None:
        self.lines.append("  " * self.depth + text)

    def defaults(self, kind: str, **attrs: object) -> None:
        """Default attributes for every ``node``, ``edge`` or ``graph`` that follows."""
        self.line(f"{kind}{attributes(attrs)};")

    def node(self, ident: str, **attrs: object) -> None:
        self.line(f"{quote(ident)}{attributes(attrs)};")

    def edge(self, tail: str, head: str, **attrs: object) -> None:
        self.line(f"{quote(tail)} -> {quote(head)}{attributes(attrs)};")

    @contextmanager
    def cluster(self, **attrs: object) -> Iterator[None]:
        """A ``subgraph cluster_N`` around what is written inside the ``with`` block."""
        self.clusters += 1
        self.line(f"subgraph cluster_{self.clusters} {{")
        self.depth += 1
        if attrs:
            self.line(f"graph{attributes(attrs)};")
        try:
            yield
        finally:
            self.depth -= 1
            self.line("}")

    def __str__(self) -> str:
        return "\n".join(self.lines + ["}"]) + "\n"
