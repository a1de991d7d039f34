"""What every part of the GenoM2 reader shares: positions, field values, codel fields."""
from __future__ import annotations

import difflib
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

from lark import Lark, Token, Tree

from genom2bip.ir import (
    Codel,
    CodelParam,
    Component,
    Description,
    Duration,
    NamedType,
    Service,
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
from runtime import lalr
from runtime.diagnostics import Reporter, Span

GRAMMAR = Path(__file__).with_name("genom2.lark")

#: Ticks per second of the module clock when the module does not say (``clkrate:``).
DEFAULT_CLOCK_RATE = 100

WCET_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}


@lru_cache(maxsize=1)
def grammar_parser() -> Lark:
    return lalr.parser(GRAMMAR.read_text(encoding="utf-8"), start=["start", "expr"], propagate_positions=False,
                       maybe_placeholders=False)


@dataclass
class Field:
    name: Token
    canonical: str
    value: Tree


@dataclass
class Block:
    kind: str
    kind_token: Token
    name: Token
    fields: dict[str, Field] = field(default_factory=dict)

    def get(self, canonical: str) -> Field | None:
        return self.fields.get(canonical)


class FieldError(Exception):
    """A field value of the wrong shape; reported at ``span``."""

    def __init__(self, span: Span, message: str, hint: str | None = None) -> None:
        super().__init__(message)
        self.span, self.message, self.hint = span, message, hint


class Genom2Reader:
    """The state of one GenoM2 file being read.

    It also says how a field's value is read: names, numbers, strings, types, codels.
    """

    def __init__(self, source: Any, reporter: Reporter, description: Description) -> None:
        self.source = source
        self.reporter = reporter
        self.description = description
        self.symbols: dict[str, Any] = {}
        self.c = CDeclarations(description, reporter, self.span_of, self.symbols)
        self.blocks: list[Block] = []
        self.component: Component | None = None
        self.broken_module = False  # a module declaration with a syntax error (already reported)
        self.init_requests: list[Service] = []  # type: init requests, incompatible with all others
        self.tick = 1.0 / DEFAULT_CLOCK_RATE
        self.poster_tasks: dict[str, Token] = {}

    def span_of(self, node: Any) -> Span:
        tok = first_token(node) if not isinstance(node, Token) else node
        if tok is None or getattr(tok, "line", None) is None:
            return self.source.span(1, 1)
        return self.source.span(tok.line, tok.column, tok.end_line, tok.end_column)

    def _span_at(self, line: int, column: int) -> Span:
        return self.source.span(max(line, 1), max(column, 1))

    def _items(self, f: Field) -> list[Any]:
        return list(f.value.children)

    def _one(self, f: Field, what: str) -> Any:
        items = self._items(f)
        if len(items) != 1:
            raise FieldError(self.span_of(items[1]), f"field '{f.name}' takes one {what}, not a list")
        return items[0]

    def _name(self, f: Field, item: Any = None) -> Token:
        node = self._one(f, "name") if item is None else item
        if (
            isinstance(node, Tree)
            and node.data == "path"
            and len(node.children) == 1
            and isinstance(node.children[0], Token)
        ):
            return node.children[0]
        raise FieldError(self.span_of(node), f"field '{f.name}' expects a name here")

    def _names(self, f: Field) -> list[Token]:
        return [self._name(f, item) for item in self._items(f)]

    def _number(self, f: Field, item: Any = None) -> Any:
        node = self._one(f, "number") if item is None else item
        if isinstance(node, Tree) and node.data in ("strings", "value_type", "pair", "colon_list", "wcet"):
            raise FieldError(self.span_of(node), f"field '{f.name}' expects a number")
        try:
            return evaluate(node, self.symbols, self.span_of)
        except CError as err:
            raise FieldError(err.span, err.message, err.hint) from None

    def _int(self, f: Field) -> int:
        value = self._number(f)
        if not isinstance(value, int):
            raise FieldError(self.span_of(f.value), f"field '{f.name}' expects an integer, not {value!r}")
        return value

    def _string(self, f: Field, item: Any = None) -> str:
        node = self._one(f, "string") if item is None else item
        if isinstance(node, Tree) and node.data == "strings":
            return "".join(string_literal(str(t)) for t in node.children)
        raise FieldError(self.span_of(node), f"field '{f.name}' expects a quoted string")

    def _text(self, f: Field) -> list[str]:
        """Names or strings (``requires``, ``codel_files``...): their text."""
        out = []
        for item in self._items(f):
            if isinstance(item, Tree) and item.data == "strings":
                out.append(self._string(f, item))
            else:
                out.append(str(self._name(f, item)))
        return out

    def _packages(self, f: Field) -> list[str]:
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
                raise FieldError(self.span_of(item), f"field '{f.name}' expects package names or strings")
            out.append(name)
        return out

    def _type(self, f: Field, item: Any) -> Type:
        if isinstance(item, Tree) and item.data == "value_type":
            try:
                return self.c.type_spec_core(item.children[0], None)
            except CError as err:
                raise FieldError(err.span, err.message, err.hint) from None
        tok = self._name(f, item)
        return NamedType(str(tok), span=self.span_of(tok))

    def _codel(self, f: Field) -> tuple[Token, Duration | None]:
        node = self._one(f, "codel")
        if isinstance(node, Tree) and node.data == "wcet":
            name, _kw, amount, *unit = node.children
            seconds = self._wcet_seconds(f, amount, unit[0] if unit else None, name)
            return name, seconds
        return self._name(f, node), None

    def _wcet_seconds(self, f: Field, amount: Any, unit: Token | None, name: Token) -> Duration:
        if unit is None or str(unit) not in WCET_UNITS:
            where = unit if unit is not None else name
            raise FieldError(self.span_of(where), f"wcet of codel '{name}' needs a unit: "
                              + ", ".join(WCET_UNITS))
        try:
            value = evaluate(amount, self.symbols, self.span_of)
        except CError as err:
            raise FieldError(err.span, err.message) from None
        if value < 0:
            raise FieldError(self.span_of(amount), "a wcet cannot be negative")
        return Duration(value * WCET_UNITS[str(unit)], f"{value} {unit}")

    def _ticks(self, f: Field) -> Duration | None:
        node = self._one(f, "number of ticks")
        if (
            isinstance(node, Tree)
            and node.data == "path"
            and len(node.children) == 1
            and str(node.children[0]) == "none"
        ):
            return None
        value = self._number(f, node)
        if not isinstance(value, int):
            raise FieldError(self.span_of(node), f"field '{f.name}' counts clock ticks: an integer, not {value!r}")
        if value == 0:
            return None  # GenoM2: 0 (or none) means no period
        return Duration(value * self.tick, f"{value} tick{'s' if abs(value) != 1 else ''}")

    def _refs(self, f: Field) -> list[tuple[Tree, Tree]]:
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
                raise FieldError(self.span_of(item), f"field '{f.name}' expects 'name::sdi_field'")
            left, right = item.children
            for side in (left, right):
                if not (isinstance(side, Tree) and side.data == "path"):
                    raise FieldError(self.span_of(side), f"field '{f.name}' expects 'name::sdi_field'")
            out.append((left, right))
        return out

    def _codel_field(self, f: Field | None) -> tuple[str, Duration | None, Span] | None:
        if f is None:
            return None
        try:
            tok, wcet = self._codel(f)
        except FieldError as err:
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

    @staticmethod
    def _known(what: str, names: list[str], wrong: str) -> str:
        close = difflib.get_close_matches(wrong, names, n=1)
        if close:
            return f"did you mean '{close[0]}'?"
        return f"known {what}: {', '.join(names)}" if names else f"no {what} are declared"
