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

Every file, the main one and each include, is read by :func:`read_source`:
a regular file (a device or a pipe would be read for ever), UTF-8, within
what is left of :data:`~genom2bip.parser.limits.MAX_INPUT_BYTES`.  An
include of a file being read, or nested deeper than
:data:`~genom2bip.parser.limits.MAX_INCLUDE_DEPTH`, is refused with the chain
of includes.  pcpp's lexer matches comments and strings with patterns that
keep a backtracking frame per character (500 bytes of memory per byte of a
long comment); :func:`_lexer` swaps them for patterns that match the same
text in constant memory.
"""
from __future__ import annotations

import bisect
import copy
import io
import os
import re
import stat
from array import array
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Mapping, Sequence

from pcpp.parser import default_lexer, trigraph
from pcpp.preprocessor import Action, OutputDirective, Preprocessor

from genom2bip.ir import Pragma
from genom2bip.parser.limits import (MAX_EXPANDED_TOKENS, MAX_INCLUDE_DEPTH, MAX_INPUT_BYTES, MAX_OUTPUT_CHARS,
                                     megabytes)
from runtime.diagnostics import Diagnostic, Reporter, SourceCache, Span
from runtime.textfile import decode_error

_NEEDS_ARGUMENT = {"if": "an expression", "elif": "an expression", "ifdef": "a macro name",
                   "ifndef": "a macro name", "define": "a macro name", "undef": "a macro name",
                   "include": "a file name"}

class Origins:
    """Where each output token came from, four integers a token (a tuple per token cost 90 bytes).

    Entries are in output order; ``line_starts[L - 1]`` is the first entry of
    output line ``L``.  ``code`` is the original column times two, plus one
    when it is exact: tokens made by macro expansion are not, positions inside
    them map to the macro use.
    """

    def __init__(self) -> None:
        self.files: list[str] = []
        self._file_index: dict[str, int] = {}
        self.line_starts = array("i", [0])
        self.out_cols, self.file_ids, self.lines, self.codes = array("i"), array("i"), array("i"), array("i")

    def add(self, out_col: int, file: str, line: int, col: int, exact: bool) -> None:
        index = self._file_index.get(file)
        if index is None:
            index = self._file_index[file] = len(self.files)
            self.files.append(file)
        self.out_cols.append(out_col)
        self.file_ids.append(index)
        self.lines.append(line)
        self.codes.append(2 * col + exact)

    def new_line(self) -> None:
        self.line_starts.append(len(self.out_cols))

    def __len__(self) -> int:
        """The number of output lines."""
        return len(self.line_starts)

    def on_line(self, line: int) -> range:
        """The entries of output line ``line`` (1-based)."""
        end = self.line_starts[line] if line < len(self.line_starts) else len(self.out_cols)
        return range(self.line_starts[line - 1], end)

    def entry(self, i: int) -> tuple[int, str, int, int, bool]:
        """(output column, original file, original line, original column, exact) of entry ``i``."""
        code = self.codes[i]
        return self.out_cols[i], self.files[self.file_ids[i]], self.lines[i], code >> 1, bool(code & 1)


@dataclass
class Preprocessed:
    """The preprocessed text of one main file, with the map from output positions to original ones."""

    text: str
    file: str
    pragmas: list[Pragma] = field(default_factory=list)
    sources: SourceCache = field(default_factory=SourceCache, repr=False)
    origins: Origins = field(default_factory=Origins, repr=False)
    files: list[str] = field(default_factory=list)  # every file read, the main file first

    def origin(self, line: int, column: int) -> tuple[str, int, int]:
        """The original (file, line, column) of output position ``line:column`` (both 1-based)."""
        origins = self.origins
        if not origins.out_cols:
            return (self.file, max(line, 1), max(column, 1))
        line = min(max(line, 1), len(origins))
        entries = origins.on_line(line)
        probe = line
        while not entries and probe > 1:  # an empty output line: use the end of the previous one
            probe -= 1
            entries = origins.on_line(probe)
            column = 10**9
        if not entries:
            return (self.file, line, max(column, 1))
        i = max(bisect.bisect_right(origins.out_cols, column, entries.start, entries.stop) - 1, entries.start)
        out_col, file, oline, ocol, exact = origins.entry(i)
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


# ---------------------------------------------------------------------- reading files within bounds

_BEYOND = "the {limit} genom2bip reads for a description and its includes"


class Unreadable(Exception):
    """A file that is not read: why (a message completing "cannot read/include X: ..."), or where it is not UTF-8."""

    def __init__(self, why: str, hint: str | None = None, diagnostic: Diagnostic | None = None) -> None:
        super().__init__(why)
        self.why, self.hint, self.diagnostic = why, hint, diagnostic


def _too_large(size: int, already: int) -> Unreadable:
    limit = _BEYOND.format(limit=megabytes(MAX_INPUT_BYTES).replace(".0 ", " "))
    if not already or size > MAX_INPUT_BYTES:
        return Unreadable(f"it holds {megabytes(size)} of text, more than {limit}",
                          hint="split it into several description files (each is read on its own)")
    return Unreadable(f"its {megabytes(size)} of text, after the {megabytes(already)} read already, make more "
                      f"than {limit}", hint="split the description into several files (each is read on its own)")


def read_source(path: str, name: str, already: int = 0) -> tuple[str, int]:
    """The UTF-8 text of the regular file ``path`` (named ``name`` in messages), a leading BOM dropped, and its size.

    ``already`` bytes have been read for the same description: the file may
    bring the total up to :data:`MAX_INPUT_BYTES`, and no more than that is
    ever read.  Raises :class:`Unreadable` for a device, a pipe, a directory,
    a file too large or not UTF-8; OSError when it cannot be opened.
    """
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))  # a pipe must not block here
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise Unreadable("not a regular file (a device, a pipe or a directory)")
        budget = MAX_INPUT_BYTES - already
        if info.st_size > budget:
            raise _too_large(info.st_size, already)
        with open(fd, "rb", closefd=False) as fh:
            data = fh.read(budget + 1)  # a file growing, or a size the system does not know (/proc)
    finally:
        os.close(fd)
    if len(data) > budget:
        raise _too_large(len(data), already)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise Unreadable("not UTF-8", diagnostic=decode_error(name, data, err)) from None
    return (text[1:] if text.startswith("\ufeff") else text), len(data)


# pcpp's rule -> one for the same text whose memory does not grow with the match (no frame per character),
# with the same number of groups, so that every rule after it keeps its group number in ply's master pattern.
_LINEAR_RULES = {
    r"(/\*(.|\n)*?\*/)": r"(/\*[^*]*\*+(?:[^/*][^*]*\*+)*/)()",
    r"\"([^\\\n]|(\\(.|\n)))*?\"": r"\"([^\"\\\n]*(?:\\(.|\n)[^\"\\\n]*)*)()\"",
    r"\'([^\\\n]|(\\(.|\n)))*?\'": r"\'([^'\\\n]*(?:\\(.|\n)[^'\\\n]*)*)()\'",
}


@lru_cache(maxsize=1)
def _lexer():
    """pcpp's lexer with comments, strings and characters matched in constant memory (cloned for each use)."""
    lexer = default_lexer()
    for state, tables in lexer.lexstatere.items():
        for i, (old, functions) in enumerate(tables):
            text = old.pattern
            for slow, linear in _LINEAR_RULES.items():
                text = text.replace(slow, linear)
            new = re.compile(text, old.flags)
            if new.groupindex == old.groupindex:  # else pcpp changed its rules: keep them as they are
                tables[i] = (new, functions)
    lexer.begin("INITIAL")
    return lexer


#: Names pcpp expands without a macro of that name.
_SPECIAL = ("__LINE__", "__COUNTER__")


class _Token:
    """A token as pcpp's lexer makes it, without a dict of its own: pcpp holds every token of a file at once."""

    __slots__ = ("type", "value", "lineno", "lexpos", "source", "expanded_from", "expanded", "origin_col")

    def __init__(self, tok) -> None:
        self.type, self.value, self.lineno, self.lexpos, self.source = (
            tok.type, tok.value, tok.lineno, tok.lexpos, tok.source)

    def __repr__(self) -> str:
        return f"_Token({self.type}, {self.value!r}, {self.lineno}, {self.lexpos})"


class Exhausted(Exception):
    """Preprocessing stopped: macros expand to more than a description may hold."""

    def __init__(self, span: Span | None, message: str) -> None:
        super().__init__(message)
        self.span, self.message = span, message  # the span is the use in the text, once known


def _written_name(tokens) -> str | None:
    """The file name of ``#include "name"`` or ``#include <name>`` as written (None when a macro gives it)."""
    words = [t.value for t in tokens if not t.value.isspace()]
    if words and words[0][:1] == '"':
        return words[0][1:-1]
    if words and words[0] == "<" and ">" in words:
        return "".join(t.value for t in tokens).strip()[1:].split(">", 1)[0]
    return None


class _Cpp(Preprocessor):
    """pcpp with its hooks turned into diagnostics, pragma collection and origin tracking."""

    def __init__(self, reporter: Reporter, display: dict[str, str], texts: dict[str, str], size: int) -> None:
        super().__init__(_lexer().clone())
        self.reporter = reporter
        self.display = display  # absolute path -> name used in messages
        self.texts = texts  # absolute path -> text read (for columns and quoting)
        self.line_starts: dict[str, array] = {}
        self.pragmas: list[Pragma] = []
        self.tried_fallback: set[tuple[str, str]] = set()
        self.rewrite_paths = []  # keep absolute paths in token sources
        self.auto_pragma_once_enabled = True
        self.size = size  # bytes read so far: the main file's, then each include's
        # the files being read, outermost first: (real path, the #include that opened it, its name there)
        self.reading: list[tuple[str, Span | None, str | None]] = []
        self.opening: tuple[Span, str] | None = None  # the include read last, for the next parsegen
        self.written: str | None = None  # the file name of the #include being handled, as written
        self.expanded = 0  # tokens made by macro expansion so far
        self.depth = 0  # expand_macros calls under way

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

    def starts(self, source: str) -> array:
        """Offsets of line starts in the text pcpp lexes for ``source`` (trailing blanks stripped)."""
        found = self.line_starts.get(source)
        if found is None:
            text = self.texts.get(source, "")
            joined = "\n".join(x.rstrip() for x in trigraph(text).splitlines())
            found = array("q", [0])
            at = joined.find("\n")
            while at >= 0:
                found.append(at + 1)
                at = joined.find("\n", at + 1)
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

    def group_lines(self, input, abssource):
        """pcpp's lines of tokens, each token a :class:`_Token`."""
        for line in super().group_lines(input, abssource):
            yield [_Token(t) for t in line]

    def expand_macros(self, tokens, expanding_from=[]):  # noqa: B006 - pcpp's signature
        """pcpp's expansion, its tokens marked (:meth:`mark_expanded`); stops once expansions made too many.

        A macro using another twice, and so on, doubles at each level: past
        :data:`MAX_EXPANDED_TOKENS` tokens made, :class:`Exhausted` names the
        use in the text that started it.
        """
        if not any(t.value in self.macros or t.value in _SPECIAL for t in tokens if t.type == self.t_ID):
            return tokens  # nothing to expand (pcpp would still give each token a list: 56 bytes)
        original = list(tokens)  # pcpp rewrites the list in place
        self.depth += 1
        try:
            out = super().expand_macros(tokens, expanding_from)
        except Exhausted as exc:
            if self.depth == 1 and exc.span is None:  # the text's tokens: the first use not yet replaced
                use = next((t for t in tokens if t.type == self.t_ID and t.value in self.macros
                            and not getattr(t, "expanded_from", None)), original[0])
                exc.span = Span(self.name_of(use.source), use.lineno or 1, self.column_of(use) or 1)
            raise
        finally:
            self.depth -= 1
        self.expanded += self.mark_expanded(original, out)
        if self.expanded > MAX_EXPANDED_TOKENS:
            raise Exhausted(None, f"macro expansion makes more than {MAX_EXPANDED_TOKENS} tokens")
        return out

    def mark_expanded(self, original: list, out: list) -> int:
        """Mark the tokens of ``out`` that are not in ``original``, with the column of the use they replace.

        pcpp replaces a macro use in the list by its expansion and keeps every
        other token, in order: walking ``out`` beside ``original`` finds, for
        each new token, the first input token not yet passed, the use.
        Returns how many tokens are new.
        """
        if len(out) == len(original) and all(a is b for a, b in zip(out, original)):
            return 0
        pos = made = 0
        for t in out:
            if pos < len(original) and original[pos] is t:
                pos += 1
                continue
            if not getattr(t, "expanded_from", None) and not t.value.isspace():
                # an input token after a use: pass the tokens the expansion replaced
                at = next((i for i in range(pos, len(original)) if original[i] is t), None)
                if at is not None:
                    pos = at + 1
                    continue
            t.expanded = True
            made += 1
            if pos < len(original):
                use = original[pos]
                t.origin_col = self.column_of(use) or getattr(use, "origin_col", None)
        return made

    def parsegen(self, input, source=None, abssource=None):
        """pcpp's reading of one file, the file on :attr:`reading` meanwhile."""
        self.reading.append((os.path.realpath(abssource or "."), *(self.opening or (None, None))))
        self.opening = None
        try:
            yield from super().parsegen(input, source, abssource)
        finally:
            self.reading.pop()

    def chain(self, start: int, last: Span, name: str) -> str:
        """The includes from the file ``reading[start]`` to ``last``, which includes ``name``: ``a:1 includes b``."""
        steps = [f"{where.file}:{where.line} includes {written}" for _, where, written in self.reading[start:]
                 if where is not None] + [f"{last.file}:{last.line} includes {name}"]
        if len(steps) > 6:
            steps[3:-2] = [f"... ({len(steps) - 5} more)"]
        return ", ".join(steps)

    def on_file_open(self, is_system_include, includepath):
        """Read an include within bounds; refuse it when recursive or too deep, a device, too large or not UTF-8."""
        name = self.written or os.path.basename(includepath)
        where = self.directive_span(self.lastdirective, self.written)
        real = os.path.realpath(includepath)
        again = next((i for i, (path, _, _) in enumerate(self.reading) if path == real), None)
        if again is not None:
            self.refuse(where, f"recursive #include of '{name}': {self.chain(again, where, name)} again",
                        "a file may not include itself, directly or through others")
        if len(self.reading) > MAX_INCLUDE_DEPTH:
            self.refuse(where, f"#include nested more than {MAX_INCLUDE_DEPTH} deep: {self.chain(0, where, name)}")
        try:
            data, size = read_source(includepath, self.name_of(includepath), self.size)
        except (FileNotFoundError, NotADirectoryError):
            raise  # pcpp looks in the next directory
        except OSError as exc:
            self.refuse(where, f"cannot include '{name}': {exc.strerror or exc}")
        except Unreadable as exc:
            if exc.diagnostic is not None:
                self.reporter.diagnostics.append(exc.diagnostic)
                raise OutputDirective(Action.IgnoreAndRemove) from None
            self.refuse(where, f"cannot include '{name}': {exc.why}", exc.hint)
        self.size += size
        self.opening = (where, name)
        self.texts[includepath] = data
        self.reporter.sources.add(self.name_of(includepath), data)
        return io.StringIO(data)

    def refuse(self, where: Span, message: str, hint: str | None = None):
        """Report an #include that is not read, and drop the directive."""
        self.reporter.error(where, message, hint)
        raise OutputDirective(Action.IgnoreAndRemove)

    def on_error(self, file, line, msg):
        text = msg[:1].lower() + msg[1:]
        self.reporter.error(Span(self.name_of(file), line or 1, 1), text)
        self.return_code += 1

    def include(self, tokens, original_line):
        # pcpp appends fallback directories to its -I list for <...> includes; undo that afterwards
        kept = len(self.path)
        self.written = _written_name(tokens)
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
            text, size = read_source(str(path_or_text), filename)
        except OSError as exc:
            reporter.error(Span(filename, 1, 1), f"cannot read '{filename}': {exc.strerror or exc}")
            return None
        except Unreadable as exc:
            reporter.diagnostics.append(exc.diagnostic or Diagnostic(Span(filename, 0, 0), f"not read: {exc.why}",
                                                                     hint=exc.hint))
            return None
        abspath = os.path.abspath(str(path_or_text))
    else:
        text, size = path_or_text, len(path_or_text.encode("utf-8", "surrogatepass"))
        abspath = os.path.abspath(filename)
        if size > MAX_INPUT_BYTES:
            exc = _too_large(size, 0)
            reporter.error(Span(filename, 0, 0), f"not read: {exc.why}", exc.hint)
            return None
    reporter.sources.add(filename, text)
    display = {abspath: filename}
    texts = {abspath: text}
    cpp = _Cpp(reporter, display, texts, size)
    for d in include_dirs:
        cpp.add_path(str(d))
    for name, value in (defines or {}).items():
        cpp.define(f"{name} {value}" if value not in (None, "") else f"{name} 1")

    cpp.parse(text, source=abspath)
    out, origins = _write(cpp)
    if out is None:
        return None
    return Preprocessed(
        text=out,
        file=filename,
        pragmas=cpp.pragmas,
        sources=reporter.sources,
        origins=origins,
        files=[cpp.name_of(p) for p in texts],
    )


def _write(cpp: _Cpp) -> tuple[str | None, Origins]:
    """Concatenate pcpp's output tokens, recording the origin of each one; None when preprocessing was stopped."""
    chunks: list[str] = []
    origins = Origins()
    out_col = 1
    size = 0
    last_exact = ("", 0, 1)  # (file, line, column) of the last token read as it stands in its file
    last = None
    while True:
        try:
            tok = cpp.token()
        except Exhausted as exc:
            cpp.reporter.error(exc.span, exc.message, "a macro that expands to itself twice or more doubles at "
                                                      "each level")
            return None, origins
        except Exception as exc:  # noqa: BLE001 - pcpp has unchecked corners; report, never crash
            file = cpp.name_of(getattr(last, "source", None)) if last is not None else "<unknown>"
            line = getattr(last, "lineno", 1) if last is not None else 1
            cpp.reporter.error(Span(file, line, 1), f"the preprocessor cannot read this: {exc or type(exc).__name__}")
            break
        if tok is None:
            break
        last = tok
        value = tok.value
        if not value:
            continue
        size += len(value)
        if size > MAX_OUTPUT_CHARS:
            cpp.reporter.error(Span(cpp.name_of(tok.source), tok.lineno or 1, 1),
                               f"the preprocessed text grows past {MAX_OUTPUT_CHARS} characters here")
            return None, origins
        file = cpp.name_of(getattr(tok, "source", None))
        line = getattr(tok, "lineno", 1) or 1
        col = cpp.column_of(tok)
        exact = col is not None
        if exact:
            last_exact = (file, line, col)
        else:
            col = getattr(tok, "origin_col", None) or (last_exact[2] if last_exact[:2] == (file, line) else 1)
        if not value.isspace():
            origins.add(out_col, file, line, col, exact)
        chunks.append(value)
        if "\n" in value:
            for _ in range(value.count("\n")):
                origins.new_line()
            out_col = len(value) - value.rfind("\n")
        else:
            out_col += len(value)
    return "".join(chunks), origins
