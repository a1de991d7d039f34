"""Source locations and compiler-style error reports shared by every front end.

Both the GenoM front end (``genom2bip.parser``) and the BIP2 reader
(``runtime.bip2``) report problems as :class:`Diagnostic` objects that name
``file:line:column``, quote the source line with a caret under the column and
say what was expected.  Several diagnostics are collected and raised together
as one :class:`DiagnosticError`, so that a user sees every problem in a file at
once.  This module lives in ``runtime`` because the runtime reads ``.bip`` files
on its own and must never import the generator.
"""
from __future__ import annotations

import os
import stat
from dataclasses import dataclass, field

from runtime.errors import Genom2bipError


@dataclass(frozen=True)
class Span:
    """A position in a source file: 1-based line and column."""

    file: str
    line: int
    column: int
    end_line: int | None = None
    end_column: int | None = None

    def __str__(self) -> str:
        if self.line <= 0:  # the file as a whole (it cannot be read, say): no made-up position
            return self.file
        return f"{self.file}:{self.line}:{self.column}"


NOWHERE = Span("<unknown>", 0, 0)


@dataclass(frozen=True)
class Diagnostic:
    """One problem found in an input: where, what, and (optionally) a hint."""

    span: Span
    message: str
    severity: str = "error"
    hint: str | None = None
    source_line: str | None = None

    def render(self, sources: "SourceCache | None" = None) -> str:
        """Format as ``file:line:col: error: message`` plus the quoted line and caret."""
        head = f"{self.span}: {self.severity}: {self.message}"
        lines = [head]
        text = self.source_line
        if text is None and sources is not None and self.span.line > 0:
            text = sources.line(self.span.file, self.span.line)
        if text is not None and self.span.line > 0:
            col = max(self.span.column, 1)
            width = 1
            if self.span.end_line == self.span.line and self.span.end_column:
                width = max(1, self.span.end_column - col)
            text, col = _clipped(text.rstrip("\n"), col)
            width = min(width, max(1, len(text) - col + 1))
            # control characters (a NUL byte...) are shown as '?', one for one so the caret stays aligned
            text = "".join(ch if ch.isprintable() or ch == "\t" else "?" for ch in text)
            lines.append(f"    {text}")
            prefix = "".join(ch if ch == "\t" else " " for ch in text[: col - 1])
            lines.append(f"    {prefix}{'^' * width}")
        if self.hint:
            lines.append(f"    hint: {self.hint}")
        return "\n".join(lines)


#: A quoted line longer than this is shown as the part around the column, so that a huge line is not printed.
QUOTE_WIDTH = 200


def _clipped(text: str, col: int) -> tuple[str, int]:
    """``text`` cut to :data:`QUOTE_WIDTH` characters around ``col`` (marked ``...``), and the column in it."""
    if len(text) <= QUOTE_WIDTH:
        return text, col
    start = max(0, min(col - 1 - QUOTE_WIDTH // 2, len(text) - QUOTE_WIDTH))
    shown = text[start:start + QUOTE_WIDTH]
    if start > 0:
        shown, col = "..." + shown, col - start + 3
    if start + QUOTE_WIDTH < len(text):
        shown += "..."
    return shown, col


#: Bytes of a file read to quote one of its lines: above every input a reader accepts (a description and its
#: includes: 2 MB), so that a message about a huge or endless file never reads it all.
MAX_QUOTED_FILE_BYTES = 16 * 1024 * 1024


def _read_quotable(file: str) -> list[str] | None:
    """The lines of ``file`` when it is a regular file of at most MAX_QUOTED_FILE_BYTES; None otherwise.

    A device (``/dev/zero``) or a FIFO is never read: it is opened without waiting for a writer and
    refused on what ``fstat`` says, so that printing an error about it neither hangs nor fills memory.
    """
    try:
        if not stat.S_ISREG(os.stat(file).st_mode):  # not even opened: opening a FIFO wakes its writer
            return None
        fd = os.open(file, os.O_RDONLY | os.O_NONBLOCK)
    except OSError:
        return None
    with os.fdopen(fd, "rb") as f:
        try:
            info = os.fstat(fd)
            if not stat.S_ISREG(info.st_mode) or info.st_size > MAX_QUOTED_FILE_BYTES:
                return None
            data = f.read(MAX_QUOTED_FILE_BYTES + 1)
        except OSError:
            return None
    if len(data) > MAX_QUOTED_FILE_BYTES:  # it grew while being read
        return None
    return data.decode("utf-8", errors="replace").splitlines()


class SourceCache:
    """Reads source lines lazily so that diagnostics can quote them; never more than a bounded regular file."""

    def __init__(self) -> None:
        self._texts: dict[str, list[str] | None] = {}

    def add(self, file: str, text: str) -> None:
        self._texts[file] = text.splitlines()

    def line(self, file: str, line: int) -> str | None:
        if line <= 0:  # the file as a whole: nothing to quote, nothing to read
            return None
        if file not in self._texts:
            self._texts[file] = _read_quotable(file)
        lines = self._texts[file]
        if lines is not None and 1 <= line <= len(lines):
            return lines[line - 1]
        return None


@dataclass
class DiagnosticError(Genom2bipError):
    """Raised when an input has one or more errors; carries all of them."""

    diagnostics: list[Diagnostic] = field(default_factory=list)
    sources: SourceCache | None = None

    def __post_init__(self) -> None:
        super().__init__(self.render())

    def render(self) -> str:
        body = "\n".join(d.render(self.sources) for d in self.diagnostics)
        n = sum(1 for d in self.diagnostics if d.severity == "error")
        if n > 1:
            body += f"\n{n} errors"
        return body

    def __str__(self) -> str:
        return self.render()


class Reporter:
    """Collects diagnostics while a front end works; raises them all at the end."""

    def __init__(self, sources: SourceCache | None = None) -> None:
        self.sources = sources or SourceCache()
        self.diagnostics: list[Diagnostic] = []

    def error(self, span: Span, message: str, hint: str | None = None) -> None:
        self.diagnostics.append(Diagnostic(span, message, "error", hint))

    def warning(self, span: Span, message: str, hint: str | None = None) -> None:
        self.diagnostics.append(Diagnostic(span, message, "warning", hint))

    @property
    def has_errors(self) -> bool:
        return any(d.severity == "error" for d in self.diagnostics)

    def raise_if_errors(self) -> None:
        if self.has_errors:
            ordered = sorted(self.diagnostics, key=lambda d: (d.span.file, d.span.line, d.span.column))
            raise DiagnosticError(ordered, self.sources)
