"""The GenoM2 reader for constants and data: #define macros, internal data paths, fail reports."""
from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Iterator

from lark import Token, Tree
from lark.exceptions import UnexpectedInput

from genom2bip.ir import (
    ArrayType,
    BaseType,
    Constant,
    ExceptionDecl,
    SequenceType,
    StringType,
    StructType,
    Type,
)
from genom2bip.parser.genom2_base import FieldError, Genom2Reader, grammar_parser
from genom2bip.parser.genom2_c import (
    CError,
    evaluate,
    path_text,
    string_literal,
)
from runtime.diagnostics import Span


class TypeReader(Genom2Reader):
    """Constants harvested from #define, internal data (ids) paths, and fail reports declared by use."""

    _DEFINE = re.compile(r"^[ \t]*#[ \t]*define[ \t]+([A-Za-z_]\w*)(?![\w(])[ \t]+(.*?)[ \t]*$", re.M)

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
        if re.fullmatch(r'"[^"\\]*(?:\\.[^"\\]*)*"', text):
            return string_literal(text)
        try:
            tree = grammar_parser().parse(text, start="expr")
            return evaluate(tree, self.symbols, lambda _n: Span("", 0, 0))
        except (UnexpectedInput, CError, ArithmeticError, ValueError, TypeError, RecursionError):
            return None

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
                        raise FieldError(self.span_of(part), f"'{path_text(path)}': '{path.children[i - 1]}' "
                                          "is not a struct")
                    member = next((m for m in resolved.members if m.name == str(part)), None)
                    where = resolved.name
                if member is None:
                    raise FieldError(self.span_of(part), f"'{part}' is not a field of {where}")
                typ = member.type
            else:
                resolved = self.c.resolve(typ)
                if isinstance(resolved, ArrayType):
                    typ = (
                        resolved.element if len(resolved.dims) == 1 else ArrayType(resolved.element, resolved.dims[1:])
                    )
                elif isinstance(resolved, SequenceType):
                    typ = resolved.element
                else:
                    raise FieldError(self.span_of(part), f"'{path_text(path)}' indexes something that is not an array")
        return typ

    def _declare_exceptions(self, names: list[str], spans: dict[str, Span]) -> None:
        """GenoM2 fail reports are declared by use: each becomes a component exception."""
        assert self.component is not None
        for name in names:
            if name not in self.component.throws:
                self.component.throws.append(name)
            key = f"{self.component.name}::{name}"
            if key not in self.description.exceptions:
                self.description.exceptions[key] = ExceptionDecl(
                    name, span=spans.get(f"throws:{name}", self.component.span)
                )
