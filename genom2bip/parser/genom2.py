"""GenoM2 front end: ``module``/``request``/``poster``/``exec_task`` files into the description IR.

The preprocessed text is cut into top-level declarations (each ending with a
``;`` outside braces) and each one is parsed on its own with the LALR grammar
in ``genom2.lark``, so that one syntax error does not hide the next ones.
Blocks are then desugared as docs/genom2.md says: requests become services
whose codels form an FSM, posters become ``out`` ports, exec tasks become
tasks with their period in seconds.  Every problem is a Diagnostic with the
original ``file:line:column`` (through ``source.span``), never a traceback.
"""
from __future__ import annotations

import difflib
import re
from typing import Any, Iterator

from lark import Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from genom2bip.ir import Description
from genom2bip.parser.expected import expected_genom2
from genom2bip.parser.genom2_base import Block, Field, FieldError, grammar_parser
from genom2bip.parser.genom2_components import ComponentReader
from genom2bip.parser.genom2_services import RequestReader
from genom2bip.parser.genom2_types import TypeReader
from genom2bip.parser.limits import TOO_DEEP, TOO_DEEP_HINT, deep_place
from runtime.diagnostics import Reporter

# --------------------------------------------------------------------------- accepted fields
# canonical name -> older spellings accepted for it

MODULE_FIELDS: dict[str, tuple[str, ...]] = {
    "number": (), "internal_data": (), "codel_files": (), "version": (), "iface_version": (),
    "email": (), "lang": (), "uses_cxx": (), "requires": ("require",), "codels_requires": (),
    "clkrate": ("clock_rate",), "max_rqst_size": (), "max_reply_size": (), "doc": (),
}
REQUEST_FIELDS: dict[str, tuple[str, ...]] = {
    "doc": (), "type": (), "exec_task": (), "input": (), "input_info": (), "output": (),
    "posters_input": (),
    "codel_control": ("c_control_func",),
    "codel_start": ("c_exec_func_start",),
    "codel_main": ("c_exec_func",),
    "codel_end": ("c_exec_func_end",),
    "codel_fail": ("c_exec_func_fail",),
    "codel_inter": ("c_exec_func_inter",),
    "interrupt_activity": ("incompatible_with",),
    "fail_reports": ("fail_msg",),
    "resources": (), "rqst_num": (),
}
EXEC_TASK_FIELDS: dict[str, tuple[str, ...]] = {
    "period": (), "delay": (), "priority": (), "stack_size": (),
    "codel_task_start": ("c_init_func",),
    "codel_task_main": ("c_func",),
    "codel_task_end": ("c_end_func",),
    "codel_task_main2": (),
    "codel_task_wait": (),
    "posters_input": (), "cs_client_from": (), "poster_client_from": (), "resources": (),
    "fail_reports": ("fail_msg",), "doc": (),
}
POSTER_FIELDS: dict[str, tuple[str, ...]] = {
    "update": (), "data": (), "type": (), "exec_task": (), "address": (),
    "codel_poster_create": ("c_create_func", "create_func"), "doc": (),
}
BLOCK_FIELDS = {
    "module": MODULE_FIELDS,
    "request": REQUEST_FIELDS,
    "exec_task": EXEC_TASK_FIELDS,
    "poster": POSTER_FIELDS,
}

# --------------------------------------------------------------------------- cutting the text


def split_declarations(text: str) -> Iterator[tuple[int, int, int, int]]:
    """Yield (start, end, line, column) of each top-level declaration: up to a ``;`` outside braces.

    Strings, character literals, comments and ``#`` lines are skipped so that
    their ``;`` and braces do not count.
    """
    i, n = 0, len(text)
    line, col = 1, 1
    depth = 0
    start: tuple[int, int, int] | None = None  # offset, line, column of the current declaration

    def advance(to: int) -> None:
        nonlocal i, line, col
        chunk = text[i:to]
        nl = chunk.count("\n")
        if nl:
            line += nl
            col = to - text.rindex("\n", 0, to)
        else:
            col += to - i
        i = to

    at_line_start = True
    while i < n:
        ch = text[i]
        if ch == "\n":
            advance(i + 1)
            at_line_start = True
            continue
        if ch in " \t\r\f":
            advance(i + 1)
            continue
        if ch == "#" and at_line_start:
            end = text.find("\n", i)
            advance(n if end < 0 else end)
            continue
        at_line_start = False
        if text.startswith("/*", i):
            end = text.find("*/", i + 2)
            if end < 0:  # unclosed: hand the rest to the parser, which reports it
                begin = start if start is not None else (i, line, col)
                yield begin[0], n, begin[1], begin[2]
                return
            advance(end + 2)
            continue
        if text.startswith("//", i):
            end = text.find("\n", i)
            advance(n if end < 0 else end)
            continue
        if start is None:
            start = (i, line, col)
        if ch in "\"'":
            j = i + 1
            while j < n and text[j] != ch and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            advance(min(j + 1, n))
            continue
        if ch in "{([":
            depth += 1
        elif ch in "})]":
            depth = max(depth - 1, 0)
        elif ch == ";" and depth == 0:
            advance(i + 1)
            if text[start[0]:i].strip() != ";":
                yield start[0], i, start[1], start[2]
            start = None
            continue
        advance(i + 1)
    if start is not None and text[start[0]:].strip():
        yield start[0], n, start[1], start[2]


# --------------------------------------------------------------------------- front end


class Genom2Frontend(TypeReader, ComponentReader, RequestReader):
    """Parses one preprocessed GenoM2 file into ``description``, reporting into ``reporter``.

    Blocks of each topic are read by their own reader: constants and data
    (:mod:`.genom2_types`), the module, tasks and posters
    (:mod:`.genom2_components`), requests (:mod:`.genom2_services`).
    """

    def run(self) -> None:
        self._harvest_macros()
        text = self.source.text
        for start, end, line, column in split_declarations(text):
            tree = self._parse_chunk(text[start:end], line, column, end, text)
            if tree is None:
                continue
            for decl in tree.children:
                self._top(decl)
        self._build()

    def _parse_chunk(self, chunk: str, line: int, column: int, end: int, text: str) -> Tree | None:
        padded = "\n" * (line - 1) + " " * (column - 1) + chunk
        try:
            tree = grammar_parser().parse(padded, start="start")
        except UnexpectedInput as err:
            self._syntax_error(err, text, end)
            if _MODULE_HEAD.match(chunk):  # its requests are not "outside a module"
                self.broken_module = True
            return None
        deep = deep_place(tree)
        if deep is not None:
            self.reporter.error(self._span_at(*deep), TOO_DEEP, TOO_DEEP_HINT)
            return None
        return tree

    def _syntax_error(self, err: UnexpectedInput, text: str, end: int) -> None:
        if isinstance(err, UnexpectedToken) and err.token.type != "$END":
            tok = err.token
            if str(tok) == "/" and text.startswith("/*", _offset(text, tok.line, tok.column)):
                self.reporter.error(self.span_of(tok), "unterminated comment",
                                    "a comment opened with '/*' must be closed with '*/'")
                return
            shown = f"'{tok}'" if tok.type not in ("NAME", "STRING") else (
                f"name '{tok}'" if tok.type == "NAME" else f"string {tok}")
            message = f"syntax error: unexpected {shown}; expected {expected_genom2(set(err.expected))}"
            self.reporter.error(self.span_of(tok), message, self._hint(err))
            return
        if isinstance(err, UnexpectedCharacters):
            ch = text and err.char
            if err.char == "/" and text.startswith("/*", _offset(text, err.line, err.column)):
                self.reporter.error(self._span_at(err.line, err.column), "unterminated comment",
                                    "a comment opened with '/*' must be closed with '*/'")
                return
            field = _field_before(text, err.line, err.column)
            if field in _STRING_FIELDS:
                self.reporter.error(self._span_at(err.line, err.column),
                                    f"'{field}' needs a quoted string: write {field}: \"...\";")
                return
            message = f"syntax error: unexpected character {ch!r}"
            if err.allowed:
                message += f"; expected {expected_genom2(set(err.allowed))}"
            self.reporter.error(self._span_at(err.line, err.column), message)
            return
        expected = set(getattr(err, "expected", None) or [])
        last = max(len(text[:end].rstrip()) - 1, 0)  # the last character of the declaration
        line = text.count("\n", 0, last) + 1
        column = last - (text.rfind("\n", 0, last) + 1) + 2
        message = "syntax error: unexpected end of declaration"
        if expected:
            message += f"; expected {expected_genom2(expected)}"
        self.reporter.error(self._span_at(line, column), message,
                            "is a '}' or a ';' missing?")

    @staticmethod
    def _hint(err: UnexpectedToken) -> str | None:
        if "SEMICOLON" in err.expected and err.token.type in ("NAME", "RBRACE"):
            return "is a ';' missing before it?"
        return None

    # ------------------------------------------------------------------ top-level declarations

    def _top(self, decl: Tree) -> None:
        if decl.data == "genom_block":
            self._collect_block(decl)
        elif decl.data == "import_decl":
            kw = decl.children[0]
            if str(kw) != "import" or (len(decl.children) > 1 and isinstance(decl.children[1], Token)
                                        and decl.children[1].type == "NAME" and str(decl.children[1]) != "from"):
                self.reporter.error(self.span_of(kw), f"unknown declaration '{kw}'; expected "
                                    "'import from \"file.h\" { ... }'")
                return
            source = decl.children[2] if len(decl.children) > 2 else None
            if isinstance(source, Token) and source.type == "STRING":  # parser.y: IMPORT_TYPE FROM identificateur
                self.reporter.error(self.span_of(source), "import from takes the name of the module the types "
                                    f"come from, not a file: {source}",
                                    f"write import from MODULE {{ #include {source} }};")
                return
            for child in decl.children:
                if isinstance(child, Tree) and child.data in (
                    "typedef",
                    "tag_decl",
                    "var_decl",
                    "named_var_decl",
                    "storage_decl",
                ):
                    self.c.declare(child)
        else:
            self.c.declare(decl)

    def _collect_block(self, decl: Tree) -> None:
        kind_tok, name_tok, *fields = decl.children
        kind = str(kind_tok)
        accepted = BLOCK_FIELDS.get(kind)
        if accepted is None:
            close = difflib.get_close_matches(kind, list(BLOCK_FIELDS), n=1)
            self.reporter.error(self.span_of(kind_tok), f"unknown declaration '{kind}'; expected "
                                "module, request, poster, exec_task, import, typedef, struct or enum",
                                f"did you mean '{close[0]}'?" if close else None)
            return
        aliases = {alt: canon for canon, alts in accepted.items() for alt in alts}
        block = Block(kind, kind_tok, name_tok)
        for f in fields:
            fname_tok, value = f.children
            fname = str(fname_tok)
            canonical = fname if fname in accepted else aliases.get(fname)
            if canonical is None:
                every = sorted(set(accepted) | set(aliases))
                close = difflib.get_close_matches(fname, every, n=1)
                self.reporter.error(
                    self.span_of(fname_tok),
                    f"unknown field '{fname}' in {kind} '{name_tok}'; accepted fields: {', '.join(every)}",
                    f"did you mean '{close[0]}'?" if close else None)
                continue
            if canonical in block.fields:
                first = block.fields[canonical].name
                same = "" if str(first) == fname else f" (as '{first}')"
                self.reporter.error(self.span_of(fname_tok),
                                    f"field '{fname}' given twice in {kind} '{name_tok}': first{same} at "
                                    f"{self.span_of(first)}")
                continue
            block.fields[canonical] = Field(fname_tok, canonical, value)
        self.blocks.append(block)


    def _build(self) -> None:
        modules = [b for b in self.blocks if b.kind == "module"]
        others = [b for b in self.blocks if b.kind != "module"]
        if not modules:
            if others and not self.broken_module:
                first = others[0]
                self.reporter.error(self.span_of(first.kind_token),
                                    f"{first.kind} '{first.name}' outside a module: this file has no "
                                    "'module NAME { ... };' declaration")
            return
        for extra in modules[1:]:
            self.reporter.error(self.span_of(extra.kind_token),
                                f"second module '{extra.name}' in one file (first is '{modules[0].name}' at "
                                f"{self.span_of(modules[0].name)}); a GenoM2 file describes one module")
        self.component = self._module(modules[0])
        for block in others:
            if block.kind == "exec_task":
                self._guard(self._exec_task, block)
        for block in others:
            if block.kind == "poster":
                self._guard(self._poster, block)
        for block in others:
            if block.kind == "request":
                self._guard(self._request, block)
        self._expand_all()
        self._pragmas()
        self.description.components.append(self.component)
        if self.source.file and self.source.file not in self.description.files:
            self.description.files.append(self.source.file)

    def _pragmas(self) -> None:
        """``#pragma`` lines are kept on the description; ``requires`` ones also on the module, as in GenoM3."""
        assert self.component is not None
        for pragma in getattr(self.source, "pragmas", None) or []:
            self.description.pragmas.append(pragma)
            if pragma.name in ("requires", "require"):
                value = pragma.arguments.strip().strip('"')
                reqs = self.component.properties.setdefault("require", [])
                if value and value not in reqs:
                    reqs.append(value)

    def _guard(self, build: Any, block: Block) -> None:
        try:
            build(block)
        except FieldError as err:
            self.reporter.error(err.span, err.message, err.hint)


_MODULE_HEAD = re.compile(r"\s*module\s+[A-Za-z_]\w*\s*\{")
_STRING_FIELDS = {"email", "version", "doc", "lang"}


def _offset(text: str, line: int, column: int) -> int:
    """The character offset of 1-based ``line:column`` in ``text`` (its end when out of range)."""
    start = 0
    for _ in range(line - 1):
        start = text.find("\n", start) + 1
        if start == 0:
            return len(text)
    return start + column - 1


def _field_before(text: str, line: int, column: int) -> str | None:
    """The name of the ``field:`` whose value holds output position ``line:column``, if any."""
    head = text[:_offset(text, line, column)]
    cut = max(head.rfind(";"), head.rfind("{"))
    m = re.match(r"\s*([A-Za-z_]\w*)\s*:", head[cut + 1:])
    return m.group(1) if m else None


def parse_genom2(source: Any, reporter: Reporter, description: Description) -> None:
    """Parse one preprocessed GenoM2 file and append its component, types and constants to ``description``.

    ``source`` is a :class:`genom2bip.parser.preprocess.Preprocessed` (``.text``,
    ``.file``, ``.span(line, column, ...)``).  Problems go to ``reporter``.
    """
    try:
        Genom2Frontend(source, reporter, description).run()
    except RecursionError:
        reporter.error(source.span(1, 1), "declaration nested too deeply to parse")
