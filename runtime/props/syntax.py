"""Reading property files: the lark grammar (mcl.lark) into untyped trees with positions, and syntax errors.

The grammar does not know state formulas from action or regular ones (they
share ``true``, ``not``, ``and``, ``or`` and parentheses); :mod:`runtime.props.typing`
decides from where each piece stands.  Errors are :class:`~runtime.diagnostics.Diagnostic`
objects naming ``file:line:column``, gathered into one ``DiagnosticError``.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

from lark import Lark, Token, Transformer, Tree, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from runtime import lalr
from runtime.diagnostics import Diagnostic, DiagnosticError, SourceCache, Span
from runtime.nesting import MAX_DEPTH, too_deep

GRAMMAR = Path(__file__).with_name("mcl.lark")


@dataclass(frozen=True)
class Raw:
    """An untyped formula node: ``op`` names the construct, ``args`` its parts (Raw nodes or plain values)."""

    op: str
    args: tuple[Any, ...]
    span: Span


@dataclass(frozen=True)
class RawProperty:
    """One property of a file, before typing: its name (given or ``property N``), body and position."""

    name: str
    body: Raw
    span: Span
    text: str = ""


#: What a user reads for each terminal of the grammar in "expected ..." messages.
TERMINALS = {
    "NAME": "a name", "STRING": 'a label in double quotes ("M.S:port")',
    "REGEX": "a regular expression in quotes ('...')",
    "TRUE": "true", "FALSE": "false", "INT": "a number", "SIGNED_INT": "a number", "CMP": "a comparison",
    "MU": "mu", "NU": "nu", "LPAR": "'('", "RPAR": "')'", "LSQB": "'['", "RSQB": "']'", "LESSTHAN": "'<'",
    "MORETHAN": "'>'", "LBRACE": "'{'", "RBRACE": "'}'", "DOT": "'.'", "VBAR": "'|'", "STAR": "'*'", "PLUS": "'+'",
    "SEMICOLON": "';'", "COLON": "':'", "AT": "'@'", "$END": "the end of the file", "NOT": "not", "AND": "and",
    "OR": "or", "IMPLIES": "implies", "NEVER": "never", "PRECEDES": "precedes", "LEADS": "leads", "TO": "to",
    "WITHIN": "within", "STEPS": "steps", "ONLY": "only", "WHILE": "while", "RUNS": "runs",
    "INVARIANT": "invariant", "DEADLOCK": "deadlock", "FREE": "free",
}


@lru_cache(maxsize=1)
def parser() -> Lark:
    return lalr.parser(GRAMMAR.read_text(encoding="utf-8"), propagate_positions=True, maybe_placeholders=False)


def _span(file: str, meta_or_token) -> Span:
    m = meta_or_token
    if isinstance(m, Token):
        return Span(file, m.line, m.column, m.end_line, m.end_column)
    return Span(file, m.line, m.column, getattr(m, "end_line", None), getattr(m, "end_column", None))


class _Build(Transformer):
    """lark tree -> Raw nodes; every node keeps the position of its text."""

    def __init__(self, file: str) -> None:
        super().__init__()
        self.file = file

    def _raw(self, op: str, meta, *args) -> Raw:
        return Raw(op, tuple(args), _span(self.file, meta))

    @v_args(meta=True)
    def start(self, meta, items):
        return items

    @v_args(meta=True)
    def property(self, meta, items):
        if len(items) == 2:
            name, body = items
            return RawProperty(str(name), body, _span(self.file, name))
        return RawProperty("", items[0], body_span(items[0]))

    def _unary_rule(op):  # noqa: N805 - a factory used in the class body
        @v_args(meta=True)
        def rule(self, meta, items):
            return self._raw(op, meta, *[_value(i) for i in items])
        return rule

    formula = _unary_rule("formula")
    never = _unary_rule("never")
    precedes = _unary_rule("precedes")
    leads_to = _unary_rule("leads_to")
    only_while = _unary_rule("only_while")
    invariant = _unary_rule("invariant")
    deadlock_free = _unary_rule("deadlock_free")
    implies = _unary_rule("implies")
    choice = _unary_rule("choice")
    concat = _unary_rule("concat")
    star = _unary_rule("star")
    plus = _unary_rule("plus")
    or_ = _unary_rule("or")
    and_ = _unary_rule("and")
    not_ = _unary_rule("not")
    diamond = _unary_rule("diamond")
    box = _unary_rule("box")
    state = _unary_rule("state")
    p_or = _unary_rule("p_or")
    p_and = _unary_rule("p_and")
    p_not = _unary_rule("p_not")
    p_at = _unary_rule("p_at")
    p_cmp = _unary_rule("p_cmp")
    p_var = _unary_rule("p_var")
    p_true = _unary_rule("true")
    p_false = _unary_rule("false")
    true = _unary_rule("true")
    false = _unary_rule("false")
    var = _unary_rule("var")
    label = _unary_rule("label")
    regex = _unary_rule("regex")
    optional = _unary_rule("optional")

    @v_args(meta=True)
    def fix(self, meta, items):
        sign, name, body = items
        return self._raw("mu" if str(sign) == "mu" else "nu", meta, str(name), body, _span(self.file, name))

    @v_args(meta=True)
    def path(self, meta, items):
        return self._raw("path", meta, ".".join(str(i) for i in items))

    @v_args(meta=True)
    def v_int(self, meta, items):
        return self._raw("value", meta, int(items[0]))

    @v_args(meta=True)
    def v_true(self, meta, items):
        return self._raw("value", meta, True)

    @v_args(meta=True)
    def v_false(self, meta, items):
        return self._raw("value", meta, False)


def _value(item):
    """Tokens become their text (strings keep their quotes off); Raw nodes pass through."""
    if isinstance(item, Token):
        if item.type in ("STRING", "REGEX"):
            return _unquote(str(item)[1:-1])
        if item.type == "INT":
            return int(item)
        return str(item)
    return item


def _unquote(text: str) -> str:
    out = []
    i = 0
    while i < len(text):
        ch = text[i]
        if ch == "\\" and i + 1 < len(text):
            nxt = text[i + 1]
            out.append({"n": "\n", "t": "\t"}.get(nxt, nxt if nxt in "\"'\\" else "\\" + nxt))
            i += 2
            continue
        out.append(ch)
        i += 1
    return "".join(out)


def body_span(raw: Raw) -> Span:
    return raw.span


def _expected(names) -> str:
    words = sorted({TERMINALS.get(n, n.lower()) for n in names})
    if not words:
        return ""
    if len(words) == 1:
        return words[0]
    return ", ".join(words[:-1]) + " or " + words[-1]


def syntax_error(file: str, err: UnexpectedInput) -> Diagnostic:
    """A worded diagnostic for a lark error: what was found, what could come there."""
    if isinstance(err, UnexpectedEOF):
        return Diagnostic(Span(file, err.line if err.line > 0 else 1, max(err.column, 1)),
                          f"unexpected end of the file; expected {_expected(err.expected)}")
    if isinstance(err, UnexpectedToken):
        tok = err.token
        found = "the end of the file" if tok.type == "$END" else f"'{tok}'"
        line, col = (tok.line, tok.column) if tok.type != "$END" else (err.line, err.column)
        if line is None or line < 1:
            line, col = _end_position(err)
        return Diagnostic(Span(file, line, col), f"unexpected {found}; expected {_expected(err.expected)}")
    if isinstance(err, UnexpectedCharacters):
        allowed = _expected(err.allowed or ())
        return Diagnostic(Span(file, err.line, err.column),
                          f"unexpected character {err.char!r}" + (f"; expected {allowed}" if allowed else ""))
    return Diagnostic(Span(file, getattr(err, "line", 1), getattr(err, "column", 1)), str(err))


def _end_position(err) -> tuple[int, int]:
    text = getattr(err, "_text", None) or ""
    lines = text.splitlines() or [""]
    return len(lines), len(lines[-1]) + 1


def parse_properties(text: str, file: str = "<properties>") -> list[RawProperty]:
    """The properties of a file, untyped; raises DiagnosticError on a syntax error."""
    sources = SourceCache()
    sources.add(file, text)
    if not text.strip() or not _has_content(text):
        raise DiagnosticError([Diagnostic(Span(file, 1, 1), "no property in this file")], sources)
    try:
        tree: Tree = parser().parse(text)
    except UnexpectedInput as err:
        opened = _unclosed_comment(text)
        if opened is not None:
            diag = Diagnostic(Span(file, *opened, opened[0], opened[1] + 2),
                              "unterminated comment: this '(*' is never closed by '*)'",
                              hint="close it with '*)'; until then the rest of the file is a comment")
        elif isinstance(err, UnexpectedToken) and err.token.type == "$END":
            lines = text.rstrip().splitlines() or [""]
            diag = Diagnostic(Span(file, len(lines), len(lines[-1]) + 1),
                              f"unexpected end of the file; expected {_expected(err.expected)}")
        else:
            diag = syntax_error(file, err)
        raise DiagnosticError([diag], sources) from None
    deep = too_deep(tree)
    if deep is not None:
        raise DiagnosticError(
            [
                Diagnostic(
                    _span(file, deep.meta),
                    f"the formula is nested more than {MAX_DEPTH} operators deep here",
                    hint="split it into several properties",
                )
            ],
            sources,
        )
    wide = next(tree.scan_values(lambda t: isinstance(t, Token) and t.type in ("INT", "SIGNED_INT")
                                 and not _INT_MIN <= _bounded_int(t) <= _INT_MAX), None)
    if wide is not None:
        shown = wide if len(wide) <= 24 else wide[:20] + "..."
        raise DiagnosticError([Diagnostic(Span(file, wide.line, wide.column, wide.end_line, wide.end_column),
                                          f"{shown} is out of range: a number has 64 bits at most "
                                          "(from -2**63 to 2**63 - 1)")], sources)
    props = _Build(file).transform(tree)
    out = []
    for k, p in enumerate(props, 1):
        out.append(RawProperty(p.name or f"property {k}", p.body, p.span, _slice(text, p.body.span)))
    return out


#: Numbers of a property are compared with model data held in 64 bits (the C explorer's int64_t).
_INT_MIN, _INT_MAX = -(2 ** 63), 2 ** 63 - 1


def _bounded_int(token: Token) -> int:
    """The token's integer, or one out of range for more digits than any int64 has (int() refuses 4300)."""
    return int(token) if len(token.lstrip("-0")) <= 19 else _INT_MAX + 1


def _unclosed_comment(text: str) -> tuple[int, int] | None:
    """Line and column of a ``(*`` that no ``*)`` closes (outside strings and ``--`` comments), or None."""
    i = 0
    while i < len(text):
        if text.startswith("(*", i):
            end = text.find("*)", i + 2)
            if end < 0:
                return text.count("\n", 0, i) + 1, i - text.rfind("\n", 0, i)
            i = end + 2
        elif text.startswith("--", i):
            end = text.find("\n", i)
            i = len(text) if end < 0 else end
        elif text[i] in "\"'":
            quote, i = text[i], i + 1
            while i < len(text) and text[i] not in (quote, "\n"):
                i += 2 if text[i] == "\\" else 1
            i += 1
        else:
            i += 1
    return None


def _slice(text: str, span: Span) -> str:
    """The source text of a span, on one line (for reports)."""
    if not span.end_line or not span.end_column:
        return ""
    lines = text.splitlines(keepends=True)
    start = sum(len(x) for x in lines[: span.line - 1]) + span.column - 1
    end = sum(len(x) for x in lines[: span.end_line - 1]) + span.end_column - 1
    import re
    part = re.sub(r"\(\*[^*]*\*+(?:[^)*][^*]*\*+)*\)", " ", text[start:end])
    part = re.sub(r"--[^\n]*", " ", part)
    return " ".join(part.split())


def _has_content(text: str) -> bool:
    import re
    stripped = re.sub(r"\(\*[^*]*\*+(?:[^)*][^*]*\*+)*\)", "", text)
    stripped = re.sub(r"--[^\n]*", "", stripped)
    return bool(stripped.strip())
