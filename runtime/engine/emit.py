"""One line writer for every generated source: the Python step, the explorer's codec and successors, the C step.

In the spirit of Amaranth's ``_PythonEmitter``: blocks are ``with w.block(head):``
and ``with w.indent():`` instead of indentation carried in strings, and
``w.fresh("t")`` gives a name not used yet in the current ``with w.names():``.
:class:`PythonWriter` and :class:`CWriter` differ only in the syntax of a
block, a statement and a one-line ``if``.
"""
from __future__ import annotations

from contextlib import contextmanager
from typing import Iterable, Iterator


class Writer:
    """Lines of generated source, indented by the blocks they are written in."""

    unit = "    "

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.depth = 0
        self._counters: dict[str, int] = {}

    def __call__(self, line: str = "") -> None:
        """One line at the current indentation (an empty line stays empty)."""
        self.lines.append(self.unit * self.depth + line if line else "")

    def extend(self, lines: Iterable[str]) -> None:
        """Lines indented relative to the current block (as the expression translators return them)."""
        for line in lines:
            self(line)

    @contextmanager
    def indent(self) -> Iterator[None]:
        self.depth += 1
        try:
            yield
        finally:
            self.depth -= 1

    @contextmanager
    def names(self) -> Iterator[None]:
        """A scope of fresh names (a function, a C block): numbering starts again inside and resumes after."""
        saved, self._counters = self._counters, {}
        try:
            yield
        finally:
            self._counters = saved

    def fresh(self, prefix: str) -> str:
        """``prefix0``, ``prefix1``, ...: a name not given yet in this scope of names."""
        n = self._counters.get(prefix, 0)
        self._counters[prefix] = n + 1
        return f"{prefix}{n}"

    def source(self) -> str:
        return "\n".join(self.lines) + "\n"


class PythonWriter(Writer):
    """Python syntax: ``head:`` opens a block, a statement is its line."""

    def block(self, head: str, comment: str | None = None):
        self(f"{head}:" + (f"  # {comment}" if comment else ""))
        return self.indent()

    def stmt(self, text: str) -> None:
        self(text)

    def if_then(self, cond: str, stmt: str) -> None:
        with self.block(f"if {cond}"):
            self(stmt)

    def else_then(self, stmt: str) -> None:
        with self.block("else"):
            self(stmt)

    def if_(self, cond: str, first: bool = True, comment: str | None = None):
        """``if`` (``elif`` after the first case) of a chain of cases."""
        return self.block(f"{'if' if first else 'elif'} {cond}", comment)


class CWriter(Writer):
    """C syntax: ``head {`` ... ``}`` (a bare ``{`` without a head), statements end with ``;``."""

    @contextmanager
    def block(self, head: str, comment: str | None = None) -> Iterator[None]:
        self((f"{head} {{" if head else "{") + (f"  /* {comment} */" if comment else ""))
        with self.indent():
            yield
        self("}")

    def stmt(self, text: str) -> None:
        self(f"{text};")

    def if_then(self, cond: str, stmt: str) -> None:
        self(f"if ({cond}) {stmt};")

    def else_then(self, stmt: str) -> None:
        self(f"else {stmt};")

    def if_(self, cond: str, first: bool = True, comment: str | None = None):
        """``if`` (``else if`` after the first case) of a chain of cases."""
        return self.block(f"{'if' if first else 'else if'} ({cond})", comment)
