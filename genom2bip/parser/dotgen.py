"""The GenoM3 dotgen front end: preprocessed text → lark tree → description IR.

The grammar lives in ``dotgen.lark``.  This module walks the tree in order,
keeping the IDL scope (modules, components, interfaces) so that names are
registered and resolved as IDL does, evaluates constant expressions, checks
which properties are allowed where, merges provided interfaces into their
components, and reports everything it can know at parse time through the
:class:`Reporter`.  Cross-references (unknown tasks, services, states) are
left to ``genom2bip.checks``.
"""
from __future__ import annotations

from functools import lru_cache
from importlib import resources

from lark import Lark, Tree
from lark.exceptions import UnexpectedInput

from genom2bip.ir import (
    Description,
    StructType,
)
from genom2bip.parser.dotgen_base import SCOPES, Symbol
from genom2bip.parser.dotgen_components import ComponentReader
from genom2bip.parser.dotgen_services import ServiceReader
from genom2bip.parser.dotgen_types import TypeReader
from genom2bip.parser.expected import blank, enclosing_item, explain, terminal_words
from genom2bip.parser.limits import TOO_DEEP, TOO_DEEP_HINT, deep_place
from genom2bip.parser.preprocess import Preprocessed
from runtime import lalr
from runtime.diagnostics import Reporter

MAX_SYNTAX_ERRORS = 20

class _WholeWords:
    """A pass-through postlexer whose only job is to put IDENT in the lexer of every parser state.

    Without it, a state that accepts the keyword ``codel`` but no identifier
    would lex ``codels`` as ``codel`` followed by ``s``.
    """

    always_accept = ("IDENT",)

    def process(self, stream):
        return stream


@lru_cache(maxsize=1)
def grammar() -> Lark:
    """The dotgen LALR parser (built once per process)."""
    text = resources.files("genom2bip.parser").joinpath("dotgen.lark").read_text(encoding="utf-8")
    return lalr.parser(text, lexer="contextual", propagate_positions=True, maybe_placeholders=False,
                       postlex=_WholeWords())


@lru_cache(maxsize=1)
def _words() -> dict[str, str]:
    return terminal_words(grammar().terminals)


def parse_dotgen(source: Preprocessed, reporter: Reporter, description: Description) -> None:
    """Parse one preprocessed GenoM3 file and add what it declares to ``description``."""
    tree, syntax_errors = _parse_recovering(source, reporter)
    if tree is None:
        return
    deep = deep_place(tree)
    if deep is not None:
        reporter.error(source.span(*deep), TOO_DEEP, TOO_DEEP_HINT)
        return
    _Builder(source, reporter, description, quiet_names=syntax_errors > 0).run(tree)


def _parse_recovering(source: Preprocessed, reporter: Reporter) -> tuple[Tree | None, int]:
    """Parse, and after a syntax error blank out the declaration around it and parse again.

    Returns the last tree (of the text without the broken declarations) and the
    number of syntax errors reported.  An error that reappears at the same place
    after blanking widens the blanked range instead of being reported twice.
    """
    text = source.text
    parser = grammar()
    reported = 0
    last_range: tuple[int, int] | None = None
    widen = 0
    for _attempt in range(4 * MAX_SYNTAX_ERRORS):
        try:
            return parser.parse(text), reported
        except UnexpectedInput as e:
            problem = explain(e, text, _words())
            offset = problem.offset
            # an error right after the blanked declaration is usually caused by the blanking
            cascade = last_range is not None and (
                offset < 0 or offset <= last_range[1] or not text[last_range[1]:offset].strip())
            if not cascade:
                span = source.span(problem.line, problem.column, problem.end_line, problem.end_column)
                hint = problem.hint
                if problem.hint_line is not None:
                    file, line, _ = source.origin(problem.hint_line, 1)
                    hint = f"{hint} (line {line})" if file == span.file else f"{hint} ({file}:{line})"
                reporter.error(span, problem.message, hint)
                reported += 1
                widen = 0
            else:
                widen += 1
            if offset < 0 or reported >= MAX_SYNTAX_ERRORS:
                return None, reported
            where = offset if not cascade or last_range is None else min(offset, last_range[0])
            found = enclosing_item(text, where, widen)
            if found is None:
                return None, reported
            start, end = found
            if last_range is not None and cascade:
                start, end = min(start, last_range[0]), max(end, last_range[1])
            text = blank(text, start, end)
            last_range = (start, end)
    return None, reported


# ====================================================================== the tree walker


class _Builder(TypeReader, ComponentReader, ServiceReader):
    """Walks a dotgen tree in source order and fills the description; each ``st_<rule>`` reads one statement.

    The statements of each topic live in their own reader: types and constants
    (:mod:`.dotgen_types`), components, interfaces, tasks and ports
    (:mod:`.dotgen_components`), services and codels (:mod:`.dotgen_services`).
    """

    def run(self, tree: Tree) -> None:
        for child in tree.children:
            self.statement(child)
        for pragma in self.src.pragmas:
            self.desc.pragmas.append(pragma)
        for comp in self.components:
            self.apply_pragmas(comp)
            self.merge_provided(comp)
            self.merge_used(comp)
            if comp.ids and f"{comp.name}::ids" not in self.desc.types:  # ids only from provided interfaces
                self.desc.types[f"{comp.name}::ids"] = StructType(f"{comp.name}::ids", comp.ids, span=comp.span)
        if self.src.file and self.src.file not in self.desc.files:
            self.desc.files.append(self.src.file)

    def statement(self, node: Tree) -> None:
        handler = getattr(self, f"st_{node.data}", None)
        if handler is None:
            raise AssertionError(f"no handler for {node.data}")
        handler(node)

    def st_module(self, node: Tree) -> None:
        name, *items = node.children
        full = self.qualify(str(name))
        sym = self.symbols.get(full)
        if sym is None:
            self.symbols[full] = Symbol("module", self.span(name))
        elif sym.kind not in SCOPES:  # scopes may be reopened (an IDL module and an interface share one)
            self.error(name, f"'{full}' is already defined", hint=f"first defined at {sym.span}")
        self.scope.append(str(name))
        for item in items:
            self.statement(item)
        self.scope.pop()
