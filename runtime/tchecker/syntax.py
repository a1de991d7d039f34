"""TChecker's text format read into declarations, each with its position (doc/file-format.md of TChecker).

A file is a sequence of declarations, one a line (``kind:field:...``), with
``{key:value:...}`` attributes that may span lines and ``#`` comments.  The
values of ``provided``, ``invariant`` and ``do`` are expressions and
statements, parsed here by a small grammar (runtime/tchecker/expressions.lark)
into :class:`Node` trees.  Every problem is a located error (file:line:column).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

from runtime.diagnostics import Diagnostic, DiagnosticError, SourceCache, Span

KINDS = ("system", "process", "event", "clock", "int", "location", "edge", "sync")
_ID = re.compile(r"[A-Za-z_][A-Za-z0-9_.]*")
_INT = re.compile(r"-?[0-9]+")


@dataclass
class Field:
    text: str
    span: Span


@dataclass
class Attribute:
    key: str
    value: str
    span: Span  # of the key
    value_span: Span  # where the value's text starts
    offset: int  # of the value's first character in the file


@dataclass
class Declaration:
    kind: str
    fields: list[Field]
    attributes: list[Attribute]
    span: Span


@dataclass
class Node:
    """An expression or statement: ``op`` is "int", "var", "!", "neg", a binary operator, "=" or "nop"."""

    op: str
    args: list = field(default_factory=list)
    span: Span | None = None
    name: str = ""
    value: int = 0

    def __str__(self) -> str:
        if self.op == "int":
            return str(self.value)
        if self.op == "var":
            return self.name + (f"[{self.args[0]}]" if self.args else "")
        if self.op == "!":
            return f"!{self.args[0]}"
        if self.op == "neg":
            return f"-{self.args[0]}"
        if self.op == "nop":
            return "nop"
        return f"({self.args[0]} {self.op} {self.args[1]})"


class Source:
    """The text of one file, to turn offsets into spans and raise located errors."""

    def __init__(self, file: str, text: str) -> None:
        self.file, self.text = file, text
        self.starts = [0] + [m.end() for m in re.finditer("\n", text)]
        self.sources = SourceCache()
        self.sources.add(file, text)

    def span(self, offset: int, end: int | None = None) -> Span:
        import bisect

        line = bisect.bisect_right(self.starts, offset)
        col = offset - self.starts[line - 1] + 1
        end_col = None
        if end is not None and bisect.bisect_right(self.starts, max(end - 1, offset)) == line:
            end_col = end - self.starts[line - 1] + 1
        return Span(self.file, line, col, line if end_col else None, end_col)

    def error(self, span: Span, message: str, hint: str | None = None) -> DiagnosticError:
        return DiagnosticError([Diagnostic(span, message, hint=hint)], self.sources)


def read(path: str | Path) -> tuple[Source, list[Declaration]]:
    """The declarations of a TChecker file (a DiagnosticError when it cannot be read or is malformed)."""
    from runtime.textfile import read_text

    file = str(path)
    return scan(file, read_text(path, "TChecker file"))


def scan(file: str, text: str) -> tuple[Source, list[Declaration]]:
    """Declarations of ``text``: fields split on ``:``, attributes in braces, comments dropped."""
    src = Source(file, text)
    out: list[Declaration] = []
    i, n = 0, len(text)
    fields: list[Field] = []
    attrs: list[Attribute] | None = None
    brace_at = 0

    def end_declaration() -> None:
        nonlocal fields, attrs
        if fields:
            head = fields[0]
            if head.text not in KINDS:
                raise src.error(head.span, f"unknown declaration '{head.text}'",
                                hint="a declaration starts with one of " + ", ".join(KINDS))
            out.append(Declaration(head.text, fields[1:], attrs or [], head.span))
        elif attrs is not None:
            raise src.error(src.span(brace_at), "attributes without a declaration")
        fields, attrs = [], None

    expect_field = True
    while i < n:
        c = text[i]
        if c == "#":
            j = text.find("\n", i)
            i = n if j < 0 else j
            continue
        if c == "\n":
            end_declaration()
            expect_field = True
            i += 1
            continue
        if c in " \t\r":
            i += 1
            continue
        if attrs is not None:
            raise src.error(src.span(i), f"unexpected '{c}' after the attributes",
                            hint="a declaration ends with its attributes '{...}'")
        if c == ":":
            if expect_field:
                raise src.error(src.span(i), "empty field", hint="two ':' in a row, or a ':' first")
            expect_field = True
            i += 1
            continue
        if c == "{":
            brace_at = i
            attrs, i = _attributes(src, i)
            continue
        if c in "@?":
            fields.append(Field(c, src.span(i, i + 1)))
            expect_field = c == "@"
            i += 1
            continue
        m = _ID.match(text, i) or _INT.match(text, i)
        if not m:
            raise src.error(src.span(i), f"unexpected character '{c}'",
                            hint="identifiers are letters, digits, '_' and '.', starting with a letter or '_'")
        if not expect_field:
            raise src.error(src.span(i), f"expected ':' before '{m.group()}'")
        fields.append(Field(m.group(), src.span(i, m.end())))
        expect_field = False
        i = m.end()
    end_declaration()
    return src, out


def _attributes(src: Source, i: int) -> tuple[list[Attribute], int]:
    """``{key:value:key:value}`` from the ``{`` at ``i``: the pairs and the offset after ``}``."""
    text = src.text
    close = text.find("}", i)
    if close < 0:
        raise src.error(src.span(i), "'{' is never closed", hint="attributes end with '}'")
    inner = text[i + 1:close]
    if "{" in inner:
        raise src.error(src.span(i + 1 + inner.index("{")), "'{' inside attributes")
    parts, start = [], i + 1
    for piece in inner.split(":"):
        parts.append((piece, start))
        start += len(piece) + 1
    if parts == [("", i + 1)] or all(not p.strip() for p, _ in parts) and len(parts) == 1:
        return [], close + 1
    if len(parts) % 2:
        at = parts[-1][1]
        raise src.error(src.span(at), "an attribute without its value",
                        hint="attributes are key:value pairs separated by ':' (an empty value is 'key:')")
    out = []
    for (key, k_at), (value, v_at) in zip(parts[0::2], parts[1::2]):
        stripped = key.strip()
        k_off = k_at + len(key) - len(key.lstrip())
        if not _ID.fullmatch(stripped):
            raise src.error(src.span(k_off), f"'{stripped}' is not an attribute name")
        v_off = v_at + len(value) - len(value.lstrip())
        out.append(Attribute(stripped, value.strip(), src.span(k_off, k_off + len(stripped)), src.span(v_off),
                             v_off))
    return out, close + 1


@lru_cache(maxsize=1)
def _parser():
    from runtime import lalr

    grammar = (Path(__file__).parent / "expressions.lark").read_text(encoding="utf-8")
    # tables from the cache: building them took about as long as a small model's whole search
    return lalr.parser(grammar, propagate_positions=True, start=["expression", "statements"])


_UNSUPPORTED_WORDS = re.compile(r"\b(if|while|local|then|else|end)\b")


def parse_expression(src: Source, attr: Attribute) -> Node:
    return _parse(src, attr, "expression")


def parse_statements(src: Source, attr: Attribute) -> list[Node]:
    return _parse(src, attr, "statements")


def _parse(src: Source, attr: Attribute, start: str):
    from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

    m = _UNSUPPORTED_WORDS.search(attr.value)
    if m:
        at = attr.offset + m.start()
        what = "conditional terms ('if ... then ... else')" if start == "expression" else \
            f"'{m.group()}' statements (only assignments and 'nop' are read)"
        raise src.error(src.span(at, at + len(m.group())), f"unsupported: {what}")
    if not attr.value:
        raise src.error(attr.value_span, f"'{attr.key}' needs a value")
    try:
        tree = _parser().parse(attr.value, start=start)
    except UnexpectedInput as e:
        if isinstance(e, UnexpectedEOF) or (isinstance(e, UnexpectedToken) and e.token.type == "$END"):
            at, what = attr.offset + len(attr.value), "the end of the value"
        elif isinstance(e, UnexpectedToken):
            at, what = attr.offset + e.token.start_pos, f"'{e.token}'"
        elif isinstance(e, UnexpectedCharacters):
            at, what = attr.offset + e.pos_in_stream, f"'{attr.value[e.pos_in_stream]}'"
        else:  # pragma: no cover - lark's other errors carry a position too
            at, what = attr.offset, "this"
        kind = "an expression" if start == "expression" else "statements"
        raise src.error(src.span(at), f"bad {attr.key}: unexpected {what}", hint=f"'{attr.key}' takes {kind}")
    return _Build(src, attr.offset).build(tree)


class _Build:
    """Lark's tree to :class:`Node`, with spans in the file."""

    def __init__(self, src: Source, offset: int) -> None:
        self.src, self.offset = src, offset

    def span(self, t) -> Span:
        meta = t.meta
        return self.src.span(self.offset + meta.start_pos, self.offset + meta.end_pos)

    def build(self, t):
        from lark import Token

        if isinstance(t, Token):
            at = self.src.span(self.offset + t.start_pos, self.offset + t.end_pos)
            if t.type == "INT":
                return Node("int", span=at, value=int(t))
            raise AssertionError(t.type)  # pragma: no cover - the grammar keeps no other token
        kind = t.data
        if kind == "statements":
            return [self.build(c) for c in t.children]
        if kind == "nop":
            return Node("nop", span=self.span(t))
        if kind == "assign":
            return Node("=", [self.build(t.children[0]), self.build(t.children[1])], self.span(t))
        if kind == "lvalue":
            name = t.children[0]
            args = [self.build(t.children[1])] if len(t.children) > 1 else []
            return Node("var", args, self.span(t), name=str(name))
        if kind == "not":
            return Node("!", [self.build(t.children[0])], self.span(t))
        if kind == "neg":
            return Node("neg", [self.build(t.children[0])], self.span(t))
        if kind == "expression":
            return self.build(t.children[0])
        if kind == "conj":
            node = self.build(t.children[0])
            for kid in t.children[1:]:
                node = Node("&&", [node, self.build(kid)], self.span(t))
            return node
        if kind in ("cmp", "sum", "product"):
            kids = t.children
            node = self.build(kids[0])
            for k in range(1, len(kids), 2):
                node = Node(str(kids[k]), [node, self.build(kids[k + 1])], self.span(t))
            return node
        raise AssertionError(kind)  # pragma: no cover
