"""C preprocessing of description files with pcpp, keeping a map back to the original files.

GenoM descriptions go through ``cpp`` before parsing: ``#include``, ``#define``,
conditionals and comments.  pcpp does the work; this module routes its errors
into a :class:`Reporter`, collects ``#pragma`` lines, and records where every
output token came from so that a parse error in the output points at the
original ``file:line:column`` -- also inside an included file.

The map is built from pcpp's tokens themselves (each carries its source file
and line; its column is recovered from its offset in that file) rather than
from ``#line`` markers: markers only give lines, tokens also give columns,
and the output text therefore never contains markers.
"""
from __future__ import annotations

import bisect
import copy
import io
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

from pcpp.parser import trigraph
from pcpp.preprocessor import Action, OutputDirective, Preprocessor

from genom2bip.ir import Pragma
from runtime.diagnostics import Reporter, SourceCache, Span

_NEEDS_ARGUMENT = {"if": "an expression", "elif": "an expression", "ifdef": "a macro name",
                   "ifndef": "a macro name", "define": "a macro name", "undef": "a macro name",
                   "include": "a file name"}

# One output token: (output column, original file, original line, original column, exact).
# ``exact`` is False for tokens made by macro expansion: positions inside them map to the macro use.
_Origin = tuple[int, str, int, int, bool]


@dataclass
class Preprocessed:
    """The preprocessed text of one main file, with the map from output positions to original ones."""

    text: str
    file: str
    pragmas: list[Pragma] = field(default_factory=list)
    sources: SourceCache = field(default_factory=SourceCache, repr=False)
    # per output line (index 0 = line 1), the origins of its tokens in output-column order
    lines: list[list[_Origin]] = field(default_factory=list, repr=False)
    files: list[str] = field(default_factory=list)  # every file read, the main file first

    def origin(self, line: int, column: int) -> tuple[str, int, int]:
        """The original (file, line, column) of output position ``line:column`` (both 1-based)."""
        if not self.lines:
            return (self.file, max(line, 1), max(column, 1))
        line = min(max(line, 1), len(self.lines))
        entries = self.lines[line - 1]
        probe = line
        while not entries and probe > 1:  # an empty output line: use the end of the previous one
            probe -= 1
            entries = self.lines[probe - 1]
            column = 10**9
        if not entries:
            return (self.file, line, max(column, 1))
        i = bisect.bisect_right(entries, column, key=lambda e: e[0]) - 1
        if i < 0:
            i = 0
        out_col, file, oline, ocol, exact = entries[i]
        if exact and column >= out_col:
            ocol += column - out_col
        return (file, oline, ocol)

    def span(self, line: int, column: int, end_line: int | None = None, end_column: int | None = None) -> Span:
        """Map an output position (and optional end) to a :class:`Span` in the original file."""
        file, oline, ocol = self.origin(line, column)
        if end_line is None or end_column is None:
            return Span(file, oline, ocol)
        efile, eline, ecol = self.origin(end_line, max(end_column - 1, 1))
        if efile != file:
            return Span(file, oline, ocol)
        return Span(file, oline, ocol, eline, ecol + 1)


def _display(path: str) -> str:
    """How a file is named in messages: relative to the working directory when it lies below it."""
    rel = os.path.relpath(path)
    return path if rel.startswith("..") else rel


class _Cpp(Preprocessor):
    """pcpp with its hooks turned into diagnostics, pragma collection and origin tracking."""

    def __init__(self, reporter: Reporter, display: dict[str, str], texts: dict[str, str]) -> None:
        super().__init__()
        self.reporter = reporter
        self.display = display  # absolute path -> name used in messages
        self.texts = texts  # absolute path -> text read (for columns and quoting)
        self.line_starts: dict[str, list[int]] = {}
        self.pragmas: list[Pragma] = []
        self.tried_fallback: set[tuple[str, str]] = set()
        self.rewrite_paths = []  # keep absolute paths in token sources
        self.auto_pragma_once_enabled = True

    def add_path(self, path: str) -> None:
        """Add an include directory, without pcpp's rewriting of token sources relative to it.

        pcpp would name the tokens of every file below an include directory by a
        relative path; the origin map knows files by absolute path, so a rewritten
        name lost every column (errors at column 1 whenever ``-I`` covered the file).
        """
        self.path.append(path)

    # ------------------------------------------------------------------ positions

    def name_of(self, source: str | None) -> str:
        if not source:
            return "<unknown>"
        return self.display.get(source) or self.display.setdefault(source, _display(source))

    def starts(self, source: str) -> list[int]:
        """Offsets of line starts in the text pcpp lexes for ``source`` (trailing blanks stripped)."""
        found = self.line_starts.get(source)
        if found is None:
            text = self.texts.get(source, "")
            joined = "\n".join(x.rstrip() for x in trigraph(text).splitlines())
            found = [0]
            for i, ch in enumerate(joined):
                if ch == "\n":
                    found.append(i + 1)
            self.line_starts[source] = found
        return found

    def column_of(self, tok) -> int | None:
        """The 1-based original column of a token read verbatim from its file, else None."""
        if getattr(tok, "expanded", False) or not getattr(tok, "source", None):
            return None
        starts = self.starts(tok.source)
        line = getattr(tok, "lineno", 0)
        pos = getattr(tok, "lexpos", None)
        if pos is None or not 1 <= line <= len(starts):
            return None
        start = starts[line - 1]
        end = starts[line] if line < len(starts) else 10**12
        if not start <= pos < end:
            return None
        return pos - start + 1

    def directive_span(self, tok, needle: str | None = None) -> Span:
        file = self.name_of(tok.source)
        col = self.column_of(tok) or 1
        if needle:
            text = self.reporter.sources.line(file, tok.lineno) or ""
            at = text.find(needle)
            if at > 0:
                col = at  # the opening quote or angle bracket
        return Span(file, tok.lineno, col)

    # ------------------------------------------------------------------ pcpp hooks

    def expand_macros(self, tokens, expanding_from=[]):  # noqa: B006 - pcpp's signature
        """Mark tokens made by an expansion, remembering the column of the macro use they replace."""
        original = list(tokens)  # pcpp rewrites the list in place
        index = {id(t): i for i, t in enumerate(original)}
        out = super().expand_macros(tokens, expanding_from)
        pos = 0
        for t in out:
            i = index.get(id(t))
            if i is not None and i >= pos:
                pos = i + 1
                continue
            t.expanded = True
            if pos < len(original):
                use = original[pos]
                t.origin_col = self.column_of(use) or getattr(use, "origin_col", None)
        return out

    def on_file_open(self, is_system_include, includepath):
        with open(includepath, "r", encoding="utf-8", errors="replace") as fh:
            data = fh.read()
        if data.startswith("\ufeff"):
            data = data[1:]
        self.texts[includepath] = data
        self.reporter.sources.add(self.name_of(includepath), data)
        return io.StringIO(data)

    def on_error(self, file, line, msg):
        text = msg[:1].lower() + msg[1:]
        self.reporter.error(Span(self.name_of(file), line or 1, 1), text)
        self.return_code += 1

    def include(self, tokens, original_line):
        # pcpp appends fallback directories to its -I list for <...> includes; undo that afterwards
        kept = len(self.path)
        try:
            yield from super().include(tokens, original_line)
        finally:
            del self.path[kept:]

    def on_include_not_found(self, is_malformed, is_system_include, curdir, includepath):
        where = self.lastdirective
        if is_malformed:
            self.reporter.error(self.directive_span(where), f"malformed #include: {includepath}",
                                hint='write #include "file" or #include <file>')
            raise OutputDirective(Action.IgnoreAndRemove)
        if is_system_include and (includepath, curdir) not in self.tried_fallback:
            # <...> also falls back to the including file's directory
            self.tried_fallback.add((includepath, curdir))
            return curdir or "."
        dirs = ([] if is_system_include else list(self.temp_path)) + list(self.path)
        shown = ", ".join(dict.fromkeys(_display(os.path.abspath(d or ".")) for d in dirs)) or "."
        self.reporter.error(self.directive_span(where, includepath),
                            f"cannot find include file '{includepath}' (searched: {shown})",
                            hint="add the directory with an include path (-I)")
        raise OutputDirective(Action.IgnoreAndRemove)

    def on_directive_handle(self, directive, toks, ifpassthru, precedingtoks):
        # pcpp indexes the arguments of these directives without checking that there are any
        name = directive.value
        if not toks and name in _NEEDS_ARGUMENT:
            self.reporter.error(self.directive_span(directive), f"#{name} needs {_NEEDS_ARGUMENT[name]}")
            if name in ("if", "elif", "ifdef", "ifndef"):
                # keep the conditional structure (so that #endif still matches) with a false condition
                filler = copy.copy(directive)
                filler.type, filler.value = (self.t_INTEGER, "0") if name in ("if", "elif") else (
                    self.t_ID, "__genom2bip_missing_macro__")
                toks.append(filler)
                if name == "ifndef":
                    filler.value = "__PCPP__"  # always defined: the block is skipped
            else:
                raise OutputDirective(Action.IgnoreAndRemove)
        if name == "pragma" and not toks:
            raise OutputDirective(Action.IgnoreAndRemove)
        return super().on_directive_handle(directive, toks, ifpassthru, precedingtoks)

    def on_directive_unknown(self, directive, toks, ifpassthru, precedingtoks):
        span = self.directive_span(directive)
        words = "".join(t.value for t in toks).strip()
        if directive.value == "pragma":
            name = toks[0].value
            args = "".join(t.value for t in toks[1:]).strip()
            self.pragmas.append(Pragma(name, args, span=span))
            return True
        if directive.value == "error":
            self.reporter.error(span, f"#error {words}".rstrip())
            return True
        if directive.value == "warning":
            self.reporter.warning(span, f"#warning {words}".rstrip())
            return True
        self.reporter.warning(span, f"unknown preprocessor directive '#{directive.value}' ignored")
        return True


def preprocess(
    path_or_text: str | Path,
    *,
    filename: str,
    include_dirs: Sequence[str] = (),
    defines: Mapping[str, str] | None = None,
    reporter: Reporter,
) -> Preprocessed | None:
    """Run cpp on a file (a :class:`Path`) or on text (a ``str``, named ``filename`` in messages).

    Errors (missing file, include not found, ``#error``, unbalanced conditionals)
    go to ``reporter``; ``None`` is returned only when the main file cannot be read.
    """
    if isinstance(path_or_text, Path):
        try:
            text = path_or_text.read_text(encoding="utf-8", errors="replace")
        except OSError as exc:
            reporter.error(Span(filename, 1, 1), f"cannot read '{filename}': {exc.strerror or exc}")
            return None
        if text.startswith("\ufeff"):
            text = text[1:]
        abspath = os.path.abspath(str(path_or_text))
    else:
        text = path_or_text
        abspath = os.path.abspath(filename)
    reporter.sources.add(filename, text)
    display = {abspath: filename}
    texts = {abspath: text}
    cpp = _Cpp(reporter, display, texts)
    for d in include_dirs:
        cpp.add_path(str(d))
    for name, value in (defines or {}).items():
        cpp.define(f"{name} {value}" if value not in (None, "") else f"{name} 1")

    cpp.parse(text, source=abspath)
    out, lines = _write(cpp)
    return Preprocessed(
        text=out,
        file=filename,
        pragmas=cpp.pragmas,
        sources=reporter.sources,
        lines=lines,
        files=[cpp.name_of(p) for p in texts],
    )


def _write(cpp: _Cpp) -> tuple[str, list[list[_Origin]]]:
    """Concatenate pcpp's output tokens, recording the origin of each one."""
    chunks: list[str] = []
    lines: list[list[_Origin]] = [[]]
    out_col = 1
    last_exact: dict[tuple[str, int], int] = {}
    last = None
    while True:
        try:
            tok = cpp.token()
        except Exception as exc:  # noqa: BLE001 - pcpp has unchecked corners; report, never crash
            file = cpp.name_of(getattr(last, "source", None)) if last is not None else "<unknown>"
            line = getattr(last, "lineno", 1) if last is not None else 1
            cpp.reporter.error(Span(file, line, 1), f"the preprocessor cannot read this: {exc}")
            break
        if tok is None:
            break
        last = tok
        value = tok.value
        if not value:
            continue
        source = getattr(tok, "source", None)
        file = cpp.name_of(source)
        line = getattr(tok, "lineno", 1) or 1
        col = cpp.column_of(tok)
        exact = col is not None
        if exact:
            last_exact[(file, line)] = col
        else:
            col = getattr(tok, "origin_col", None) or last_exact.get((file, line), 1)
        if not value.isspace():
            lines[-1].append((out_col, file, line, col, exact))
        chunks.append(value)
        if "\n" in value:
            for _ in range(value.count("\n")):
                lines.append([])
            out_col = len(value) - value.rfind("\n")
        else:
            out_col += len(value)
    return "".join(chunks), lines
