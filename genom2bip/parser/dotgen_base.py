"""What every part of the dotgen reader shares: the IDL scope, its symbols, spans and errors."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from lark import Token, Tree

from genom2bip.ir import Component, Description
from genom2bip.parser import dotgen_consts as K
from genom2bip.parser.preprocess import Preprocessed
from runtime.diagnostics import NOWHERE, Reporter, Span

# kinds of names that open a scope; genom3 (scope.c, scope_push) reopens one of them by name
SCOPES = {"module", "interface", "component"}

TIME_UNITS = {"s": 1, "ms": 1_000, "us": 1_000_000}
SIZE_UNITS = {"k": 1024, "m": 1024 * 1024, "M": 1024 * 1024}

# which properties each kind of block accepts (the grammar accepts all of them everywhere)
COMPONENT_PROPS = {"doc", "version", "lang", "email", "require", "codels-require", "clock-rate", "provides",
                   "uses", "throws", "stack"}
ALLOWED = {
    "component": COMPONENT_PROPS,
    "interface": COMPONENT_PROPS | {"extends"},
    "task": {"doc", "period", "delay", "priority", "scheduling", "stack", "codel", "throws"},
    "port": {"doc"},
    "attribute": {"doc", "validate", "codel", "throws", "interrupts", "before", "after"},
    "function": {"doc", "validate", "codel", "throws", "interrupts", "before", "after", "local"},
    "activity": {"doc", "validate", "codel", "throws", "interrupts", "before", "after", "local", "task"},
}
ARTICLE = {"component": "a component", "interface": "an interface", "task": "a task", "port": "a port",
            "attribute": "an attribute", "function": "a function", "activity": "an activity"}


@dataclass
class Symbol:
    kind: str  # type, const, enumerator, exception, module, component, interface, forward
    span: Span
    value: Any = None


def unquote(s: str) -> str:
    return K.unescape(s[1:-1])


def prop_name(prop: Tree) -> str:
    return {"p_codels_require": "codels-require", "p_clock_rate": "clock-rate"}.get(prop.data, prop.data[2:])


def join_path(path: str, key: Any) -> str:
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else str(key)


class DotgenReader:
    """The state of one dotgen file being read: scope, symbols, the components it opened."""

    def __init__(self, source: Preprocessed, reporter: Reporter, description: Description, quiet_names: bool) -> None:
        self.src = source
        self.rep = reporter
        self.desc = description
        self.quiet_names = quiet_names  # after syntax errors, unknown names are likely consequences
        self.scope: list[str] = []
        self.symbols: dict[str, Symbol] = {}
        self.components: list[Component] = []
        self.extended: dict[str, list[str]] = {}  # interface -> the interfaces already merged into it

    def span(self, node: Any) -> Span:
        if isinstance(node, Token):
            if node.line is None:
                return NOWHERE
            return self.src.span(node.line, node.column, node.end_line, node.end_column)
        if isinstance(node, Tree):
            m = node.meta
            if getattr(m, "empty", True):
                return NOWHERE
            return self.src.span(m.line, m.column, m.end_line, m.end_column)
        return NOWHERE

    def text_of(self, first: Any, last: Any) -> str:
        """The preprocessed text from the start of ``first`` to the end of ``last``."""
        a = first.start_pos if isinstance(first, Token) else first.meta.start_pos
        b = last.end_pos if isinstance(last, Token) else last.meta.end_pos
        return self.src.text[a:b]

    def error(self, node_or_span: Any, message: str, hint: str | None = None) -> None:
        span = node_or_span if isinstance(node_or_span, Span) else self.span(node_or_span)
        self.rep.error(span, message, hint)

    def qualify(self, name: str) -> str:
        return "::".join(self.scope + [name])

    def declare(self, name: str, kind: str, node: Any, value: Any = None) -> str | None:
        """Register a name in the current scope; report a redefinition.  Returns the scoped name."""
        full = self.qualify(name)
        old = self.symbols.get(full)
        span = self.span(node)
        if old is not None and not (old.kind == "forward" and kind == "type"):
            self.error(span, f"'{full}' is already defined", hint=f"first defined at {old.span}")
            return None
        self.symbols[full] = Symbol(kind, span, value)
        return full

    def resolve(self, node: Tree, kinds: set[str]) -> str | None:
        """IDL name lookup: the innermost enclosing scope that defines the name wins."""
        parts = [str(t) for t in node.children]
        if node.data == "absolute_name":
            candidates = ["::".join(parts)]
        else:
            candidates = ["::".join(self.scope[:i] + parts) for i in range(len(self.scope), -1, -1)]
        for c in candidates:
            sym = self.symbols.get(c)
            if sym is not None and sym.kind in kinds:
                return c
        for c in candidates:  # names declared by files parsed earlier
            if c in self.desc.types or c in self.desc.exceptions:
                return c
        return None

    @staticmethod
    def written(node: Tree) -> str:
        name = "::".join(str(t) for t in node.children)
        return "::" + name if node.data == "absolute_name" else name
