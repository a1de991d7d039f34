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
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any, Iterator

from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from genom2bip.ir import (
    ArrayType,
    BaseType,
    Codel,
    CodelParam,
    Component,
    Constant,
    Description,
    Duration,
    ExceptionDecl,
    Member,
    NamedType,
    Parameter,
    Port,
    SequenceType,
    Service,
    StringType,
    StructType,
    Task,
    Type,
    Yield,
)
from genom2bip.parser.genom2_c import (
    CDeclarations,
    CError,
    evaluate,
    first_token,
    path_text,
    string_literal,
)
from runtime.diagnostics import Reporter, Span

GRAMMAR = Path(__file__).with_name("genom2.lark")

#: Ticks per second of the module clock when the module does not say (``clkrate:``).
DEFAULT_CLOCK_RATE = 100

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
BLOCK_FIELDS = {"module": MODULE_FIELDS, "request": REQUEST_FIELDS, "exec_task": EXEC_TASK_FIELDS, "poster": POSTER_FIELDS}

WCET_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}

# --------------------------------------------------------------------------- terminals, for messages

_TERMINAL_NAMES = {
    "NAME": "a name", "STRING": "a string", "INT_NUMBER": "a number", "FLOAT_NUMBER": "a number",
    "CHAR_LIT": "a character", "BASE_WORD": "a C type", "QUALIFIER": "'const'", "STORAGE": "'extern'",
    "STRUCT": "'struct'", "UNION": "'union'", "ENUM": "'enum'", "TYPEDEF": "'typedef'", "WCET": "'wcet'",
    "STAR": "'*'", "ELLIPSIS": "'...'", "OROR": "'||'", "ANDAND": "'&&'", "BAR": "'|'", "CARET": "'^'",
    "AMP": "'&'", "EQOP": "'=='", "RELOP": "'<'", "SHIFTOP": "'<<'", "ADDOP": "'+'", "MULOP": "'/'",
    "UNOP": "'!'", "$END": "end of input",
}


@lru_cache(maxsize=1)
def _parser() -> Lark:
    return Lark(GRAMMAR.read_text(encoding="utf-8"), parser="lalr", start=["start", "expr"],
                propagate_positions=False, maybe_placeholders=False)


def _terminal_text(name: str) -> str:
    if name in _TERMINAL_NAMES:
        return _TERMINAL_NAMES[name]
    try:
        pattern = _parser().get_terminal(name).pattern
    except KeyError:
        return name
    if pattern.type == "str":
        return f"'{pattern.value}'"
    return name.lower()


_OPERATORS = {"OROR", "ANDAND", "BAR", "CARET", "AMP", "EQOP", "RELOP", "SHIFTOP", "ADDOP", "MULOP", "UNOP",
              "STAR", "QMARK", "DOT", "LSQB", "LPAR", "COLON"}
_FIRST = ["';'", "'}'", "'{'", "':'", "','", "a name"]


def _expected_text(names: set[str]) -> str:
    """The expected terminals in words, punctuation that ends things first, operators dropped when other choices exist."""
    if names & {"SEMICOLON", "COMMA", "RBRACE"}:
        names = names - _OPERATORS
    texts = sorted({_terminal_text(n) for n in names})
    if "ADDOP" in names and "INT_NUMBER" in names:
        texts = [t for t in texts if t not in ("'+'", "'!'", "'('")] + ["an expression"]
    texts = [t for t in _FIRST if t in texts] + [t for t in texts if t not in _FIRST]
    if len(texts) > 8:
        texts = texts[:8] + ["..."]
    if len(texts) == 1:
        return texts[0]
    return ", ".join(texts[:-1]) + " or " + texts[-1]


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


@dataclass
class _Field:
    name: Token
    canonical: str
    value: Tree


@dataclass
class _Block:
    kind: str
    kind_token: Token
    name: Token
    fields: dict[str, _Field] = field(default_factory=dict)

    def get(self, canonical: str) -> _Field | None:
        return self.fields.get(canonical)


class _FieldError(Exception):
    """A field value of the wrong shape; reported at ``span``."""

    def __init__(self, span: Span, message: str, hint: str | None = None) -> None:
        super().__init__(message)
        self.span, self.message, self.hint = span, message, hint


class Genom2Frontend:
    """Parses one preprocessed GenoM2 file into ``description``, reporting into ``reporter``."""

    def __init__(self, source: Any, reporter: Reporter, description: Description) -> None:
        self.source = source
        self.reporter = reporter
        self.description = description
        self.symbols: dict[str, Any] = {}
        self.c = CDeclarations(description, reporter, self.span_of, self.symbols)
        self.blocks: list[_Block] = []
        self.component: Component | None = None
        self.broken_module = False  # a module declaration with a syntax error (already reported)
        self.init_requests: list[Service] = []  # type: init requests, incompatible with all others
        self.tick = 1.0 / DEFAULT_CLOCK_RATE
        self.poster_tasks: dict[str, Token] = {}

    # ------------------------------------------------------------------ positions

    def span_of(self, node: Any) -> Span:
        tok = first_token(node) if not isinstance(node, Token) else node
        if tok is None or getattr(tok, "line", None) is None:
            return self.source.span(1, 1)
        return self.source.span(tok.line, tok.column, tok.end_line, tok.end_column)

    def _span_at(self, line: int, column: int) -> Span:
        return self.source.span(max(line, 1), max(column, 1))

    # ------------------------------------------------------------------ driver

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
            return _parser().parse(padded, start="start")
        except UnexpectedInput as err:
            self._syntax_error(err, text, end)
            if _MODULE_HEAD.match(chunk):  # its requests are not "outside a module"
                self.broken_module = True
            return None

    def _syntax_error(self, err: UnexpectedInput, text: str, end: int) -> None:
        if isinstance(err, UnexpectedToken) and err.token.type != "$END":
            tok = err.token
            if str(tok) == "/" and text.startswith("/*", _offset(text, tok.line, tok.column)):
                self.reporter.error(self.span_of(tok), "unterminated comment",
                                    "a comment opened with '/*' must be closed with '*/'")
                return
            shown = f"'{tok}'" if tok.type not in ("NAME", "STRING") else (
                f"name '{tok}'" if tok.type == "NAME" else f"string {tok}")
            message = f"syntax error: unexpected {shown}; expected {_expected_text(set(err.expected))}"
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
                message += f"; expected {_expected_text(set(err.allowed))}"
            self.reporter.error(self._span_at(err.line, err.column), message)
            return
        expected = set(getattr(err, "expected", None) or [])
        last = max(len(text[:end].rstrip()) - 1, 0)  # the last character of the declaration
        line = text.count("\n", 0, last) + 1
        column = last - (text.rfind("\n", 0, last) + 1) + 2
        message = "syntax error: unexpected end of declaration"
        if expected:
            message += f"; expected {_expected_text(expected)}"
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
                if isinstance(child, Tree) and child.data in ("typedef", "tag_decl", "var_decl", "named_var_decl", "storage_decl"):
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
        block = _Block(kind, kind_tok, name_tok)
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
            block.fields[canonical] = _Field(fname_tok, canonical, value)
        self.blocks.append(block)

    # ------------------------------------------------------------------ constants from #define

    def _harvest_macros(self) -> None:
        """Object-like ``#define NAME value`` macros with a constant value become IR constants."""
        macros = getattr(self.source, "macros", None)
        items: list[tuple[str, str, Span]] = []
        if isinstance(macros, dict):
            for name, value in macros.items():
                text = value if isinstance(value, str) else getattr(value, "text", None)
                span = getattr(value, "span", None) or self.source.span(1, 1)
                if isinstance(text, str):
                    items.append((name, text, span))
        else:
            items = list(self._scan_defines())
        values: dict[str, set[str]] = {}
        for name, value_text, _span in items:
            values.setdefault(name, set()).add(value_text.strip())
        for name, value_text, span in items:
            if len(values[name]) > 1:
                continue  # defined differently in #if branches: which one cpp kept is unknown here
            if name.startswith("_") or name in self.description.constants:
                continue
            value = self._macro_value(value_text)
            if value is None:
                continue
            self.symbols.setdefault(name, value)
            if isinstance(value, str):
                typ: Type = StringType()
            elif isinstance(value, float):
                typ = BaseType("double")
            else:
                typ = BaseType("long")
            self.description.constants[name] = Constant(name, typ, value, span=span)

    _DEFINE = re.compile(r"^[ \t]*#[ \t]*define[ \t]+([A-Za-z_]\w*)(?![\w(])[ \t]+(.*?)[ \t]*$", re.M)

    def _scan_defines(self) -> Iterator[tuple[str, str, Span]]:
        for path in self._source_files():
            text = self._file_text(path)
            if text is None:
                continue
            for m in self._DEFINE.finditer(text):
                line = text.count("\n", 0, m.start()) + 1
                column = m.start(1) - (text.rfind("\n", 0, m.start(1)) + 1) + 1
                yield m.group(1), m.group(2), Span(str(path), line, column, line, column + len(m.group(1)))

    def _source_files(self) -> list[str]:
        files = [str(f) for f in getattr(self.source, "files", None) or []]
        if not files and getattr(self.source, "file", None):
            files = [str(self.source.file)]
        return files

    def _file_text(self, path: str) -> str | None:
        cached = getattr(getattr(self.source, "sources", None), "_texts", {}).get(path)
        if cached is not None:
            return "\n".join(cached)
        try:
            return Path(path).read_text(encoding="utf-8", errors="replace")
        except OSError:
            return None

    def _macro_value(self, text: str) -> Any:
        text = re.sub(r"/\*.*?\*/|//.*$", "", text).strip()
        if not text:
            return None
        if re.fullmatch(r'"(\\.|[^"\\])*"', text):
            return string_literal(text)
        try:
            tree = _parser().parse(text, start="expr")
            return evaluate(tree, self.symbols, lambda _n: Span("", 0, 0))
        except (UnexpectedInput, CError, ArithmeticError, ValueError, TypeError, RecursionError):
            return None

    # ------------------------------------------------------------------ building the component

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

    def _guard(self, build: Any, block: _Block) -> None:
        try:
            build(block)
        except _FieldError as err:
            self.reporter.error(err.span, err.message, err.hint)

    # ------------------------------------------------------------------ value helpers

    def _items(self, f: _Field) -> list[Any]:
        return list(f.value.children)

    def _one(self, f: _Field, what: str) -> Any:
        items = self._items(f)
        if len(items) != 1:
            raise _FieldError(self.span_of(items[1]), f"field '{f.name}' takes one {what}, not a list")
        return items[0]

    def _name(self, f: _Field, item: Any = None) -> Token:
        node = self._one(f, "name") if item is None else item
        if isinstance(node, Tree) and node.data == "path" and len(node.children) == 1 and isinstance(node.children[0], Token):
            return node.children[0]
        raise _FieldError(self.span_of(node), f"field '{f.name}' expects a name here")

    def _names(self, f: _Field) -> list[Token]:
        return [self._name(f, item) for item in self._items(f)]

    def _number(self, f: _Field, item: Any = None) -> Any:
        node = self._one(f, "number") if item is None else item
        if isinstance(node, Tree) and node.data in ("strings", "value_type", "pair", "colon_list", "wcet"):
            raise _FieldError(self.span_of(node), f"field '{f.name}' expects a number")
        try:
            return evaluate(node, self.symbols, self.span_of)
        except CError as err:
            raise _FieldError(err.span, err.message, err.hint) from None

    def _int(self, f: _Field) -> int:
        value = self._number(f)
        if not isinstance(value, int):
            raise _FieldError(self.span_of(f.value), f"field '{f.name}' expects an integer, not {value!r}")
        return value

    def _string(self, f: _Field, item: Any = None) -> str:
        node = self._one(f, "string") if item is None else item
        if isinstance(node, Tree) and node.data == "strings":
            return "".join(string_literal(str(t)) for t in node.children)
        raise _FieldError(self.span_of(node), f"field '{f.name}' expects a quoted string")

    def _text(self, f: _Field) -> list[str]:
        """Names or strings (``requires``, ``codel_files``...): their text."""
        out = []
        for item in self._items(f):
            if isinstance(item, Tree) and item.data == "strings":
                out.append(self._string(f, item))
            else:
                out.append(str(self._name(f, item)))
        return out

    def _packages(self, f: _Field) -> list[str]:
        """Package names (``mor-libs``, parser.l's PACKAGENAME) or strings: the lexer here reads ``-`` as minus."""
        def word(node: Any) -> str | None:
            if isinstance(node, Token):
                return str(node)
            if isinstance(node, Tree) and node.data == "path" and len(node.children) == 1:
                return word(node.children[0])
            if isinstance(node, Tree) and node.data == "int_lit":
                return str(node.children[0])
            if isinstance(node, Tree) and node.data == "binop" and str(node.children[1]) == "-":
                left, right = word(node.children[0]), word(node.children[2])
                return f"{left}-{right}" if left and right else None
            return None

        out = []
        for item in self._items(f):
            if isinstance(item, Tree) and item.data == "strings":
                out.append(self._string(f, item))
                continue
            name = word(item)
            if name is None:
                raise _FieldError(self.span_of(item), f"field '{f.name}' expects package names or strings")
            out.append(name)
        return out

    def _type(self, f: _Field, item: Any) -> Type:
        if isinstance(item, Tree) and item.data == "value_type":
            try:
                return self.c.type_spec_core(item.children[0], None)
            except CError as err:
                raise _FieldError(err.span, err.message, err.hint) from None
        tok = self._name(f, item)
        return NamedType(str(tok), span=self.span_of(tok))

    def _codel(self, f: _Field) -> tuple[Token, Duration | None]:
        node = self._one(f, "codel")
        if isinstance(node, Tree) and node.data == "wcet":
            name, _kw, amount, *unit = node.children
            seconds = self._wcet_seconds(f, amount, unit[0] if unit else None, name)
            return name, seconds
        return self._name(f, node), None

    def _wcet_seconds(self, f: _Field, amount: Any, unit: Token | None, name: Token) -> Duration:
        if unit is None or str(unit) not in WCET_UNITS:
            where = unit if unit is not None else name
            raise _FieldError(self.span_of(where), f"wcet of codel '{name}' needs a unit: "
                              + ", ".join(WCET_UNITS))
        try:
            value = evaluate(amount, self.symbols, self.span_of)
        except CError as err:
            raise _FieldError(err.span, err.message) from None
        if value < 0:
            raise _FieldError(self.span_of(amount), "a wcet cannot be negative")
        return Duration(value * WCET_UNITS[str(unit)], f"{value} {unit}")

    def _ticks(self, f: _Field) -> Duration | None:
        node = self._one(f, "number of ticks")
        if isinstance(node, Tree) and node.data == "path" and len(node.children) == 1 and str(node.children[0]) == "none":
            return None
        value = self._number(f, node)
        if not isinstance(value, int):
            raise _FieldError(self.span_of(node), f"field '{f.name}' counts clock ticks: an integer, not {value!r}")
        if value == 0:
            return None  # GenoM2: 0 (or none) means no period
        return Duration(value * self.tick, f"{value} tick{'s' if abs(value) != 1 else ''}")

    def _refs(self, f: _Field) -> list[tuple[Tree, Tree]]:
        """``name::sdi.path`` items."""
        out = []
        for item in self._items(f):
            if isinstance(item, Tree) and item.data == "obsolete_ref":
                # parser.y accepts 'TYPE sdi_ref name' (before 2007) with a warning
                _type, sdi, name = item.children
                self.reporter.warning(self.span_of(item), "deprecated syntax: use 'name::sdi_ref'",
                                      f"write {path_text(name)}::{path_text(sdi)}")
                item = Tree("pair", [name, sdi], item.meta)
            if not (isinstance(item, Tree) and item.data == "pair"):
                raise _FieldError(self.span_of(item), f"field '{f.name}' expects 'name::sdi_field'")
            left, right = item.children
            for side in (left, right):
                if not (isinstance(side, Tree) and side.data == "path"):
                    raise _FieldError(self.span_of(side), f"field '{f.name}' expects 'name::sdi_field'")
            out.append((left, right))
        return out

    # ------------------------------------------------------------------ internal data

    def _ids_path(self, path: Tree) -> Type | None:
        """Type of an internal-data path (``speed.v``, ``tab[2]``); reports unknown fields."""
        assert self.component is not None
        members = {m.name: m for m in self.component.ids}
        typ: Type | None = None
        where = self.component.properties.get("internal_data", "the internal data")
        for i, part in enumerate(path.children):
            if isinstance(part, Token):
                if i == 0:
                    member = members.get(str(part))
                else:
                    resolved = self.c.resolve(typ)
                    if not isinstance(resolved, StructType):
                        raise _FieldError(self.span_of(part), f"'{path_text(path)}': '{path.children[i - 1]}' "
                                          "is not a struct")
                    member = next((m for m in resolved.members if m.name == str(part)), None)
                    where = resolved.name
                if member is None:
                    raise _FieldError(self.span_of(part), f"'{part}' is not a field of {where}")
                typ = member.type
            else:
                resolved = self.c.resolve(typ)
                if isinstance(resolved, ArrayType):
                    typ = resolved.element if len(resolved.dims) == 1 else ArrayType(resolved.element, resolved.dims[1:])
                elif isinstance(resolved, SequenceType):
                    typ = resolved.element
                else:
                    raise _FieldError(self.span_of(part), f"'{path_text(path)}' indexes something that is not an array")
        return typ

    # ------------------------------------------------------------------ module

    def _module(self, block: _Block) -> Component:
        comp = Component(str(block.name), "genom2", file=str(self.source.file or ""), span=self.span_of(block.name))
        self.component = comp
        props = comp.properties
        for canonical, f in block.fields.items():
            try:
                self._module_field(comp, props, canonical, f)
            except _FieldError as err:
                self.reporter.error(err.span, err.message, err.hint)
        rate = props.get("clkrate", DEFAULT_CLOCK_RATE)
        self.tick = 1.0 / rate
        comp.clock_rate = Duration(self.tick, f"{rate} Hz")
        return comp

    def _module_field(self, comp: Component, props: dict, canonical: str, f: _Field) -> None:
        if canonical in ("number", "max_rqst_size", "max_reply_size"):
            props[canonical] = self._int(f)
        elif canonical == "uses_cxx":  # parser.y: deprecated, means lang "c++" whatever its value
            self._int(f)
            props["lang"] = "c++"
            self.reporter.warning(self.span_of(f.name), "usage of uses_cxx is deprecated", 'use lang: "c++";')
        elif canonical == "clkrate":
            value = self._number(f)
            if value <= 0:
                raise _FieldError(self.span_of(f.value), "clkrate (ticks per second) must be positive")
            props["clkrate"] = value
        elif canonical in ("version", "email", "lang", "doc"):
            props[canonical] = self._string(f)
        elif canonical == "iface_version":
            node = self._one(f, "version")
            if isinstance(node, Tree) and node.data == "colon_list":
                props[canonical] = ":".join(str(self._number(f, c)) for c in node.children)
            else:
                props[canonical] = self._string(f, node) if isinstance(node, Tree) and node.data == "strings" else str(self._number(f, node))
        elif canonical in ("codel_files", "requires", "codels_requires"):
            key = {"requires": "require", "codels_requires": "codels-require"}.get(canonical, canonical)
            props[key] = self._packages(f) if key != "codel_files" else self._text(f)
        elif canonical == "internal_data":
            typ = self._type(f, self._one(f, "type"))
            name = typ.name if isinstance(typ, NamedType) else None
            resolved = self.c.resolve(typ)
            if not isinstance(resolved, StructType):
                what = f"'{name}'" if name else "this type"
                raise _FieldError(self.span_of(f.value), f"internal_data {what} is not a known struct type",
                                  "declare it with 'typedef struct { ... } NAME;' or #include its header")
            props["internal_data"] = name or resolved.name
            comp.ids = [Member(m.name, m.type, m.initializer, m.doc, span=m.span) for m in resolved.members]

    # ------------------------------------------------------------------ exec_task

    def _exec_task(self, block: _Block) -> None:
        assert self.component is not None
        task = Task(str(block.name), span=self.span_of(block.name))
        fs = block.fields
        for canonical, f in fs.items():
            try:
                if canonical == "period":
                    task.period = self._ticks(f)
                    task.ref_spans["period"] = self.span_of(f.value)
                elif canonical == "delay":
                    task.delay = self._ticks(f)
                elif canonical == "priority":
                    task.priority = self._int(f)
                elif canonical == "stack_size":
                    task.stack = self._int(f)
                elif canonical == "doc":
                    task.doc = self._string(f)
                elif canonical == "fail_reports":
                    for tok in self._names(f):
                        task.throws.append(str(tok))
                        task.ref_spans[f"throws:{tok}"] = self.span_of(tok)
                elif canonical in ("posters_input",):
                    self._posters_input(f)
                elif canonical == "poster_client_from":
                    self._poster_client_from(f)
                elif canonical in ("cs_client_from", "resources"):
                    self.component.properties.setdefault(canonical, []).extend(self._text(f))
            except _FieldError as err:
                self.reporter.error(err.span, err.message, err.hint)
        start = self._codel_field(fs.get("codel_task_start"))
        main = self._codel_field(fs.get("codel_task_main"))
        main2 = self._codel_field(fs.get("codel_task_main2"))
        end = self._codel_field(fs.get("codel_task_end"))
        wait = self._codel_field(fs.get("codel_task_wait"))
        if wait:  # genom >= 2.8: an aperiodic task calls it to wait for its next wake-up instead of events
            self.component.properties.setdefault("codel_task_wait", {})[task.name] = wait[0]
        if start:
            name, wcet, span = start
            yields = ["pause::main"] if main else ["ether"]
            task.codels.append(self._make_codel(name, ["start"], yields, span, wcet))
        if main:
            name, wcet, span = main
            task.codels.append(self._make_codel(name, ["main"] if start else ["start", "main"], ["pause::main"], span, wcet))
        if main2:
            name, wcet, span = main2
            task.codels.append(self._make_codel(name, ["main2"], ["pause::main2"], span, wcet))
            self.reporter.warning(span, f"codel_task_main2 '{name}' has no GenoM3 equivalent: kept as state 'main2', never entered")
        if end:
            name, wcet, span = end
            task.codels.append(self._make_codel(name, ["stop"], ["ether"], span, wcet))
        task.throws = list(dict.fromkeys(task.throws))
        self._declare_exceptions(task.throws, task.ref_spans)
        self.component.tasks.append(task)

    def _posters_input(self, f: _Field) -> None:
        assert self.component is not None
        names = self.component.properties.setdefault("posters_input", [])
        for item in self._items(f):
            typ = self._type(f, item)
            text = typ.name if isinstance(typ, NamedType) else getattr(typ, "name", str(typ))
            if text not in names:
                names.append(text)

    def _poster_client_from(self, f: _Field) -> None:
        assert self.component is not None
        for left, right in self._refs(f):
            module, poster = path_text(left), path_text(right)
            name = f"{module}_{poster}"
            if self.component.port(name) is None:
                self.component.ports.append(Port(name, "in", NamedType(f"{module}::{poster}", span=self.span_of(left)),
                                                 doc=f"poster {poster} of module {module}", span=self.span_of(left)))

    # ------------------------------------------------------------------ codels

    def _codel_field(self, f: _Field | None) -> tuple[str, Duration | None, Span] | None:
        if f is None:
            return None
        try:
            tok, wcet = self._codel(f)
        except _FieldError as err:
            self.reporter.error(err.span, err.message, err.hint)
            return None
        return str(tok), wcet, self.span_of(tok)

    @staticmethod
    def _make_codel(name: str, triggers: list[str], yields: list[str], span: Span,
                    wcet: Duration | None, params: list[CodelParam] | None = None) -> Codel:
        ys = []
        for y in yields:
            pause = y.startswith("pause::")
            ys.append(Yield(y[len("pause::"):] if pause else y, pause, span=span))
        return Codel(name, list(triggers), ys, list(params or []), wcet=wcet, span=span)

    # ------------------------------------------------------------------ poster

    def _poster(self, block: _Block) -> None:
        assert self.component is not None
        fs = block.fields
        name = str(block.name)
        update = "auto"
        if "update" in fs:
            tok = self._name(fs["update"])
            if str(tok) not in ("auto", "user"):
                raise _FieldError(self.span_of(tok), f"poster update must be 'auto' or 'user', not '{tok}'")
            update = str(tok)
        doc = self._string(fs["doc"]) if "doc" in fs else None
        typ: Type | None = None
        if "data" in fs and "type" in fs:
            raise _FieldError(self.span_of(fs["type"].name), f"poster '{name}' has both 'data' and 'type'; "
                              "give 'data' (contents copied from the internal data) or 'type' (written by codels)")
        if "data" in fs:
            members: list[Member] = []
            for left, right in self._refs(fs["data"]):
                mtype = self._ids_path(right)
                mname = path_text(left)
                if any(m.name == mname for m in members):
                    raise _FieldError(self.span_of(left), f"duplicate data name '{mname}' in poster '{name}'")
                members.append(Member(mname, mtype if mtype is not None else NamedType("?"),
                                      doc=f"internal data {path_text(right)}", span=self.span_of(left)))
            typ = StructType(f"{self.component.name}_{name}_poster", members, span=self.span_of(block.name))
            self._register_poster_type(typ)
            typ = NamedType(typ.name, span=self.span_of(block.name))
        elif "type" in fs:
            named = self._poster_types(fs["type"])
            types = [t for _, t in named]
            if len(types) == 1 and named[0][0] is None:
                typ = types[0]
            else:
                members = [Member(n or f"data{i}", t, span=t.span) for i, (n, t) in enumerate(named)]
                struct = StructType(f"{self.component.name}_{name}_poster", members, span=self.span_of(block.name))
                self._register_poster_type(struct)
                typ = NamedType(struct.name, span=struct.span)
        else:
            raise _FieldError(self.span_of(block.name), f"poster '{name}' needs 'data: name::sdi_field, ...;' "
                              "(update: auto) or 'type: TYPE;' (update: user)")
        port = Port(name, "out", typ, doc=doc, span=self.span_of(block.name))
        self.component.ports.append(port)
        props = self.component.properties.setdefault("posters", {})
        info: dict[str, Any] = {"update": update}
        if "exec_task" in fs:
            tok = self._name(fs["exec_task"])
            info["exec_task"] = str(tok)
            if self.component.task(str(tok)) is None:
                self.reporter.error(self.span_of(tok), f"poster '{name}': unknown exec_task '{tok}'",
                                    self._known("tasks", [t.name for t in self.component.tasks], str(tok)))
        if "codel_poster_create" in fs:
            info["create"] = str(self._name(fs["codel_poster_create"]))
        if "address" in fs:
            info["address"] = " ".join(str(t) for t in fs["address"].value.scan_values(lambda v: isinstance(v, Token)))
        props[name] = info

    def _poster_types(self, f: _Field) -> list[tuple[str | None, Type]]:
        """``type: name::TYPE, ...`` (parser.y named_type); an unnamed ``TYPE`` is deprecated, as GenoM2 warns."""
        out: list[tuple[str | None, Type]] = []
        for item in self._items(f):
            if isinstance(item, Tree) and item.data == "pair":
                left, right = item.children
                out.append((str(self._name(f, left)), self._type(f, right)))
                continue
            typ = self._type(f, item)
            self.reporter.warning(self.span_of(item), "unnamed poster member is deprecated",
                                  f"write type: NAME::{getattr(typ, 'name', 'TYPE')};")
            out.append((None, typ))
        return out

    def _register_poster_type(self, struct: StructType) -> None:
        """The first poster of a name gets the type; a second one is a duplicate port, which the checks report."""
        if struct.name not in self.description.types:
            self.description.types[struct.name] = struct

    @staticmethod
    def _known(what: str, names: list[str], wrong: str) -> str:
        close = difflib.get_close_matches(wrong, names, n=1)
        if close:
            return f"did you mean '{close[0]}'?"
        return f"known {what}: {', '.join(names)}" if names else f"no {what} are declared"

    # ------------------------------------------------------------------ request

    def _request(self, block: _Block) -> None:
        assert self.component is not None
        fs = block.fields
        name = str(block.name)
        if "type" not in fs:
            raise _FieldError(self.span_of(block.name), f"request '{name}' has no 'type:' (control, exec or init)")
        type_tok = self._name(fs["type"])
        rtype = str(type_tok)
        if rtype not in ("control", "exec", "init"):
            raise _FieldError(self.span_of(type_tok), f"request type must be control, exec or init, not '{rtype}'")
        kind = "function" if rtype == "control" else "activity"
        service = Service(name, kind, span=self.span_of(block.name))
        if rtype == "init":
            # GenoM2 (genom.c) does not limit init requests; the first one is the module's init service
            if "init_service" in self.component.properties:
                self.reporter.warning(self.span_of(type_tok), f"second init request '{name}' (the first is "
                                      f"'{self.component.properties['init_service']}')",
                                      "GenoM2 accepts it; a module usually has one")
            else:
                self.component.properties["init_service"] = name
            self.init_requests.append(service)
        codel_params: list[CodelParam] = []
        for canonical, f in fs.items():
            try:
                self._request_field(service, canonical, f, codel_params, block)
            except _FieldError as err:
                self.reporter.error(err.span, err.message, err.hint)
        if "exec_task" in fs:
            try:
                tok = self._name(fs["exec_task"])
                if kind == "activity":
                    service.task = str(tok)
                    service.ref_spans["task"] = self.span_of(tok)
                else:
                    self.reporter.warning(self.span_of(fs["exec_task"].name),
                                          f"control request '{name}' runs in the control task: exec_task ignored")
            except _FieldError as err:
                self.reporter.error(err.span, err.message, err.hint)
        self._request_codels(service, fs, codel_params)
        service.throws = list(dict.fromkeys(service.throws))
        self._declare_exceptions(service.throws, service.ref_spans)
        self.component.services.append(service)

    def _request_field(self, service: Service, canonical: str, f: _Field, codel_params: list[CodelParam],
                       block: _Block) -> None:
        assert self.component is not None
        if canonical == "doc":
            service.doc = self._string(f)
        elif canonical in ("input", "output"):
            direction = "in" if canonical == "input" else "out"
            refs = self._refs(f)
            if len(refs) != 1:
                raise _FieldError(self.span_of(f.value), f"field '{f.name}' takes one 'name::sdi_field'")
            left, right = refs[0]
            if path_text(right) == "all":  # parser.y sdi_ref: ALL, the whole internal data
                typ = NamedType(str(self.component.properties.get("internal_data", "")), span=self.span_of(right))
                path = ""
            else:
                typ = self._ids_path(right)
                path = path_text(right)
            alias = path_text(left)
            param = Parameter(direction, alias, typ, source="ids", member=path, span=self.span_of(left))
            if direction == "in" and "input_info" in block.fields:
                self._input_info(param, block.fields["input_info"])
            service.parameters.append(param)
            codel_params.append(CodelParam(path, direction, "ids", alias, span=self.span_of(left)))
        elif canonical == "input_info":
            if "input" not in block.fields:
                raise _FieldError(self.span_of(f.name), "input_info without an input")
        elif canonical == "posters_input":
            self._posters_input(f)
        elif canonical == "interrupt_activity":
            for tok in self._names(f):
                if str(tok) == "none":
                    continue
                service.interrupts.append(str(tok))
                service.ref_spans[f"interrupts:{tok}"] = self.span_of(tok)
        elif canonical == "fail_reports":
            for tok in self._names(f):
                service.throws.append(str(tok))
                service.ref_spans[f"throws:{tok}"] = self.span_of(tok)
        elif canonical in ("resources", "rqst_num"):
            options = self.component.properties.setdefault("request_options", {}).setdefault(service.name, {})
            options[canonical] = self._int(f) if canonical == "rqst_num" else self._text(f)

    def _input_info(self, param: Parameter, f: _Field) -> None:
        """``input_info: default::"doc", ...``: defaults and docs of the input's scalar fields, in order."""
        infos: list[tuple[Any, str | None]] = []
        for item in self._items(f):
            if isinstance(item, Tree) and item.data == "pair":
                default_node, doc_node = item.children
                doc = self._string(f, doc_node)
            else:
                default_node, doc = item, None
            if isinstance(default_node, Tree) and default_node.data == "strings":
                default: Any = self._string(f, default_node)
            else:
                default = self._number(f, default_node)
            infos.append((default, doc))
        leaves = self._leaves(param.type, "")
        if not leaves or (len(leaves) == 1 and leaves[0] == ""):
            param.default, param.doc = infos[0]
            return
        defaults: dict[str, Any] = {}
        docs: dict[str, str] = {}
        for leaf, (default, doc) in zip(leaves, infos):
            node = defaults
            parts = leaf.split(".")
            for part in parts[:-1]:
                node = node.setdefault(part, {})
            node[parts[-1]] = default
            if doc:
                docs[leaf] = doc
        param.default = defaults
        param.member_docs.update(docs)

    def _leaves(self, typ: Type | None, prefix: str, depth: int = 0) -> list[str]:
        resolved = self.c.resolve(typ) if typ is not None else None
        if isinstance(resolved, StructType) and depth < 16:
            out = []
            for m in resolved.members:
                out.extend(self._leaves(m.type, f"{prefix}.{m.name}" if prefix else m.name, depth + 1))
            return out
        return [prefix]

    def _request_codels(self, service: Service, fs: dict[str, _Field], params: list[CodelParam]) -> None:
        control = self._codel_field(fs.get("codel_control"))
        if control:
            name, wcet, span = control
            service.validate = Codel(name, [], [], [p for p in params if p.direction == "in"], wcet=wcet, span=span)
        start = self._codel_field(fs.get("codel_start"))
        main = self._codel_field(fs.get("codel_main"))
        end = self._codel_field(fs.get("codel_end"))
        inter = self._codel_field(fs.get("codel_inter"))
        fail = self._codel_field(fs.get("codel_fail"))
        after_step = (["pause::exec"] if main else []) + (["pause::end"] if end else []) + ["ether"]
        if start:
            name, wcet, span = start
            service.codels.append(self._make_codel(name, ["start"], after_step, span, wcet, params))
        if main:
            name, wcet, span = main
            triggers = ["exec"] if start else ["start", "exec"]
            service.codels.append(self._make_codel(name, triggers, after_step, span, wcet, params))
        if end:
            name, wcet, span = end
            service.codels.append(self._make_codel(name, ["end"], ["ether"], span, wcet, params))
        if inter:
            name, wcet, span = inter
            service.codels.append(self._make_codel(name, ["stop"], ["ether"], span, wcet, params))
        if fail:
            name, wcet, span = fail
            service.codels.append(self._make_codel(name, ["fail"], ["ether"], span, wcet, params))

    # ------------------------------------------------------------------ finishing

    def _declare_exceptions(self, names: list[str], spans: dict[str, Span]) -> None:
        """GenoM2 fail reports are declared by use: each becomes a component exception."""
        assert self.component is not None
        for name in names:
            if name not in self.component.throws:
                self.component.throws.append(name)
            key = f"{self.component.name}::{name}"
            if key not in self.description.exceptions:
                self.description.exceptions[key] = ExceptionDecl(name, span=spans.get(f"throws:{name}", self.component.span))

    def _expand_all(self) -> None:
        """``interrupt_activity: all`` names every activity of the module; init requests interrupt all of them.

        GenoM2 (genom.c, resolveRequests) forces every init request to be
        incompatible with all requests, with a warning when the file says otherwise.
        """
        assert self.component is not None
        activities = [s.name for s in self.component.services if s.kind == "activity"]
        for init in self.init_requests:
            if init.interrupts and init.interrupts != ["all"]:
                self.reporter.warning(init.ref_spans.get(f"interrupts:{init.interrupts[0]}", init.span),
                                      f"init request '{init.name}' is made incompatible with all requests",
                                      "GenoM2 forces it whatever interrupt_activity says")
            for key in [k for k in init.ref_spans if k.startswith("interrupts:")]:
                del init.ref_spans[key]
            init.interrupts = ["all"]
            init.ref_spans["interrupts:all"] = init.span
        for service in self.component.services:
            if "all" in service.interrupts:
                span = service.ref_spans.pop("interrupts:all", service.span)
                expanded = []
                for n in service.interrupts:
                    for m in (activities if n == "all" else [n]):
                        if m not in expanded:
                            expanded.append(m)
                service.interrupts = expanded
                for m in activities:
                    service.ref_spans.setdefault(f"interrupts:{m}", span)


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
