"""The BIP2 parser (lark, LALR) and the translation of its errors into plain-words diagnostics."""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken
from lark.lexer import PatternStr

from runtime import lalr
from runtime.bip2.reserved import KEYWORDS
from runtime.diagnostics import Diagnostic, Span

GRAMMAR = Path(__file__).with_name("bip2.lark")

_WORDS = {"ID": "a name", "INT": "an integer", "FLOAT": "a number", "STRING": "a string", "$END": "the end of the file"}
_EXPRESSION_START = {"ID", "INT", "FLOAT", "STRING", "TRUE", "FALSE", "LPAR", "MINUS", "NOT", "BNOT"}
_OPERATORS = {"OROR", "ANDAND", "BOR", "BXOR", "BAND", "EQ", "NE", "LT", "GT", "LE", "GE",
              "PLUS", "MINUS", "STAR", "SLASH", "PERCENT"}
_COMPARISONS = {"EQ", "NE", "LT", "GT", "LE", "GE"}
_ORDER_WORDS = {"data", "port", "place", "initial", "on", "internal", "priority", "component", "connector",
                "export", "define", "clock", "invariant"}
_ORDER_HINT = ("the order is fixed: in an atom, data, clocks and ports, then place, then initial, then "
               "on/internal transitions, then priorities and invariants; in a connector, data, then export port, "
               "then define, then on; in a compound, components and connectors, then priorities, then exports")


@lru_cache(maxsize=1)
def parser() -> Lark:
    """The LALR parser for bip2.lark, built once."""
    return lalr.parser(GRAMMAR.read_text(encoding="utf-8"), lexer="basic", propagate_positions=True,
                       maybe_placeholders=True)


def parse_tree(text: str, filename: str) -> Tree | Diagnostic:
    """The parse tree of ``text``, or the diagnostic of its first syntax error."""
    try:
        return parser().parse(text)
    except UnexpectedInput as err:
        return syntax_diagnostic(err, text, filename)


def _acceptable(err: UnexpectedToken) -> set[str]:
    """The tokens that could really come next (LALR tables alone also list tokens of merged states)."""
    try:
        accepted = set(err.interactive_parser.accepts())
    except Exception:  # the exact set is a nicety; the table's set is still right, only longer
        accepted = set()
    return accepted or set(err.expected)


def _terminal_words(names: set[str]) -> list[str]:
    names = set(names)
    generic = []
    if {"INT", "STRING", "TRUE"} <= names:
        names -= _EXPRESSION_START
        generic.append("an expression")
    ops = names & _OPERATORS
    if len(ops) >= 4:
        names -= ops
        generic.append("an operator")
    words = set()
    for name in names:
        words.add(_describe_terminal(name))
    return generic + sorted(words, key=lambda w: (not w.startswith("a"), w))


def _describe_terminal(name: str) -> str:
    if name in _WORDS:
        return _WORDS[name]
    try:
        pattern = parser().get_terminal(name).pattern
    except KeyError:
        return name.lower()
    if isinstance(pattern, PatternStr):
        return f"'{pattern.value}'"
    return name.lower()


def _describe_token(tok: Token) -> str:
    if tok.type == "$END":
        return "the end of the file"
    if tok.type == "ID":
        return f"the name '{tok.value}'"
    if tok.type in ("INT", "FLOAT"):
        return f"the number {tok.value}"
    if tok.type == "STRING":
        return f"the string {tok.value}"
    return f"'{tok.value}'"


def _join(words: list[str]) -> str:
    if len(words) <= 1:
        return "".join(words) or "nothing"
    return ", ".join(words[:-1]) + " or " + words[-1]


def _end_of_text(text: str) -> tuple[int, int]:
    stripped = text.rstrip()
    line = stripped.count("\n") + 1
    column = len(stripped) - (stripped.rfind("\n") + 1) + 1
    return line, column


def syntax_diagnostic(err: UnexpectedInput, text: str, filename: str) -> Diagnostic:
    """Say, in words, what the parser expected and what it found, at file:line:column."""
    if isinstance(err, UnexpectedCharacters):
        span = Span(filename, err.line, err.column, err.line, err.column + 1)
        rest = text[err.pos_in_stream:]
        if rest.startswith('"'):
            return Diagnostic(
                span, "unterminated string", hint='close it with "; write \\" for a quote inside a string'
            )
        if rest.startswith("/*"):
            return Diagnostic(span, "unterminated comment: '/*' without '*/'")
        return Diagnostic(span, f"unexpected character '{err.char}'")
    assert isinstance(err, UnexpectedToken)
    tok = err.token
    expected = _acceptable(err)
    if tok.type == "SLASH" and text.startswith("/*", tok.start_pos):
        return Diagnostic(Span(filename, tok.line, tok.column, tok.line, tok.column + 2),
                          "unterminated comment: '/*' without '*/'")
    if tok.type == "$END":
        line, column = _end_of_text(text)
        span = Span(filename, line, column)
    else:
        span = Span(filename, tok.line, tok.column, tok.end_line, tok.end_column)
    message = f"expected {_join(_terminal_words(expected))}, found {_describe_token(tok)}"
    hint = None
    if tok.value == "provided" and "ID" in expected:
        hint = "a priority's provided (...) comes after the rule: priority name low < high provided (guard)"
    elif "ID" in expected and tok.value in KEYWORDS and tok.type != "ID":
        hint = f"'{tok.value}' is a reserved word of BIP2 and cannot be used as a name; rename it"
    elif text.startswith(("<<", ">>"), max(tok.start_pos - 1, 0)):
        hint = "BIP2 has no shift operators; use an extern function"
    elif tok.type in _COMPARISONS:
        hint = "comparisons do not chain in BIP2: add parentheses, e.g. (a < b) == c"
    elif tok.value in _ORDER_WORDS and tok.type != "ID":
        hint = _ORDER_HINT
    elif tok.type == "SEMICOLON" and text[:tok.start_pos].rstrip().endswith(("fi", "}")):
        hint = "no ';' after 'fi' or '}'"
    return Diagnostic(span, message, hint=hint)
