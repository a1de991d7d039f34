"""One line writer for every generated source: the Python step, the explorer's codec and successors, the C step.

In the spirit of Amaranth's ``_PythonEmitter``: blocks are ``with w.block(head):``
and ``with w.indent():`` instead of indentation carried in strings, and
``w.fresh("t")`` gives a name not used yet in the current ``with w.names():``.
:class:`PythonWriter` and :class:`CWriter` differ only in the syntax of a
block, a statement and a one-line ``if``.  Blocks are plain objects rather
than generator context managers: a model's step opens thousands of them.
"""
from __future__ import annotations

from typing import Iterable


class _Block:
    """One level of indentation; ``close`` (a line, when not None) is written after it."""

    __slots__ = ("w", "close")

    def __init__(self, w: "Writer", close: str | None = None) -> None:
        self.w, self.close = w, close

    def __enter__(self) -> None:
        w = self.w
        w.depth += 1
        w.prefix = w.unit * w.depth

    def __exit__(self, *exc) -> None:
        w = self.w
        w.depth -= 1
        w.prefix = w.unit * w.depth
        if self.close is not None:
            w(self.close)


class _Names:
    """A scope of fresh names: numbering starts again inside and resumes after."""

    __slots__ = ("w", "saved")

    def __init__(self, w: "Writer") -> None:
        self.w = w

    def __enter__(self) -> None:
        self.saved, self.w.counters = self.w.counters, {}

    def __exit__(self, *exc) -> None:
        self.w.counters = self.saved


class Writer:
    """Lines of generated source, indented by the blocks they are written in."""

    unit = "    "

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.depth = 0
        self.prefix = ""
        self.counters: dict[str, int] = {}
        self._indent = _Block(self)

    def __call__(self, line: str = "") -> None:
        """One line at the current indentation (an empty line stays empty)."""
        self.lines.append(self.prefix + line if line else "")

    def extend(self, lines: Iterable[str]) -> None:
        """Lines indented relative to the current block (as the expression translators return them)."""
        prefix = self.prefix
        self.lines.extend(prefix + line for line in lines)

    def indent(self) -> _Block:
        return self._indent

    def names(self) -> _Names:
        """A scope of fresh names (a function, a C block): numbering starts again inside and resumes after."""
        return _Names(self)

    def fresh(self, prefix: str) -> str:
        """``prefix0``, ``prefix1``, ...: a name not given yet in this scope of names."""
        n = self.counters.get(prefix, 0)
        self.counters[prefix] = n + 1
        return f"{prefix}{n}"

    def source(self) -> str:
        return "\n".join(self.lines) + "\n"


class PythonWriter(Writer):
    """Python syntax: ``head:`` opens a block, a statement is its line."""

    stmt = Writer.__call__

    def __init__(self) -> None:
        super().__init__()
        self._function = _Block(self, "")

    def block(self, head: str, comment: str | None = None) -> _Block:
        self(f"{head}:  # {comment}" if comment else f"{head}:")
        return self._indent

    def function(self, head: str, doc: str) -> _Block:
        """``def head:`` with its docstring; a blank line after the body."""
        self(f"def {head}:")
        self(f'{self.unit}"""{doc}"""')
        return self._function

    def if_then(self, cond: str, stmt: str) -> None:
        self(f"if {cond}:")
        self.lines.append(self.prefix + self.unit + stmt)

    def else_then(self, stmt: str) -> None:
        self("else:")
        self.lines.append(self.prefix + self.unit + stmt)

    def if_(self, cond: str, first: bool = True, comment: str | None = None) -> _Block:
        """``if`` (``elif`` after the first case) of a chain of cases."""
        return self.block(f"{'if' if first else 'elif'} {cond}", comment)


class CWriter(Writer):
    """C syntax: ``head {`` ... ``}`` (a bare ``{`` without a head), statements end with ``;``."""

    def __init__(self) -> None:
        super().__init__()
        self._close = _Block(self, "}")

    def block(self, head: str, comment: str | None = None) -> _Block:
        self((f"{head} {{" if head else "{") + (f"  /* {comment} */" if comment else ""))
        return self._close

    def stmt(self, text: str) -> None:
        self.lines.append(f"{self.prefix}{text};")

    def if_then(self, cond: str, stmt: str) -> None:
        self(f"if ({cond}) {stmt};")

    def else_then(self, stmt: str) -> None:
        self(f"else {stmt};")

    def if_(self, cond: str, first: bool = True, comment: str | None = None) -> _Block:
        """``if`` (``else if`` after the first case) of a chain of cases."""
        return self.block(f"{'if' if first else 'else if'} ({cond})", comment)
