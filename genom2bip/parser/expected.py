"""The "expected …" wording of syntax errors, for both dialects, and error recovery for dotgen.

Turns lark's ``UnexpectedToken``/``UnexpectedCharacters`` into "expected ';' or
'yield' after codel parameters, found 'task'" at the original position (dotgen,
:func:`explain`) or "expected ';', '}' or a name" (GenoM2,
:func:`expected_genom2`), and finds the dotgen declaration around an error so
that the parser can skip it and go on to report the next error in the same file.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

from lark import Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken
from lark.lexer import PatternStr

from genom2bip.parser.genom2_base import grammar_parser

_CATEGORY = {
    "IDENT": "identifier",
    "INT": "integer",
    "FLOAT_LIT": "number",
    "STRING": "string",
    "CHAR_LIT": "character",
    "CODELS_REQUIRE": "codels-require",
    "CLOCK_RATE": "clock-rate",
    "REAL_TIME": "real-time",
    "$END": "end of file",
}
_UNQUOTED = {"identifier", "integer", "number", "string", "character", "end of file"}

_TYPE_WORDS = {"long", "short", "unsigned", "float", "double", "char", "wchar", "boolean", "octet", "any",
               "string", "wstring", "sequence", "optional", "fixed", "struct", "union", "enum"}
_IDL_WORDS = {"module", "const", "typedef", "native", "exception", "struct", "union", "enum"}
_PROPERTY_WORDS = {"doc", "version", "lang", "email", "require", "codels-require", "clock-rate", "provide",
                   "use", "extend", "period", "delay", "priority", "scheduling", "stack", "interrupt", "before",
                   "after", "validate", "local", "async", "codel", "throw"}
_PLURALS = {"requires": "require", "throws": "throw", "interrupts": "interrupt", "provides": "provide",
            "uses": "use", "extends": "extend", "yields": "yield", "codels-requires": "codels-require"}
_OPERATORS = {"|", "^", "&", "<<", ">>", "+", "-", "*", "/", "%"}
_VALUE_STARTS = {"integer", "number", "character", "string", "TRUE", "FALSE", "(", "~"}
_COMPONENT_ITEMS = {"ids", "task", "port", "attribute", "function", "activity"}
_OPENERS = {"codel": "codel", "validate": "codel", "function": "service", "activity": "service",
            "attribute": "service", "task": "task", "port": "port", "ids": "ids", "struct": "struct",
            "union": "union", "enum": "enum", "component": "component", "interface": "interface",
            "module": "module", "typedef": "typedef", "const": "constant", "exception": "exception"}


def terminal_words(terminals) -> dict[str, str]:
    """Map terminal names to what a user reads: the keyword or punctuation itself, or a category."""
    words = {}
    for t in terminals:
        if t.name in _CATEGORY:
            words[t.name] = _CATEGORY[t.name]
        elif isinstance(t.pattern, PatternStr):
            words[t.name] = t.pattern.value
        else:
            words[t.name] = t.name.lower()
    words["$END"] = "end of file"
    return words


def describe_expected(names: set[str], words: dict[str, str]) -> str:
    """"';' or 'yield'", collapsing long lists into categories such as 'a type' or 'a property'."""
    raw = {_PLURALS.get(w, w) for w in (words.get(n, n) for n in names)}
    groups: list[str] = []
    if {"component", "interface"} <= raw:
        raw -= {"component", "interface"} | _IDL_WORDS
        groups.append("a declaration (component, interface, module, const, typedef, struct, enum, ...)")
    if len(raw & _COMPONENT_ITEMS) >= 3:
        raw -= _COMPONENT_ITEMS | _PROPERTY_WORDS | _IDL_WORDS
        groups.append("a declaration (ids, task, port, attribute, function, activity, a property or an IDL type)")
    if len(raw & _TYPE_WORDS) >= 4:
        raw -= _TYPE_WORDS | {"identifier", "::"}
        groups.append("a type")
    if len(raw & _PROPERTY_WORDS) >= 4:
        raw -= _PROPERTY_WORDS
        groups.append("a property (doc, codel, throws, ...)")
    if len(raw & _OPERATORS) >= 4:
        raw -= _OPERATORS
        groups.append("an operator")
    if len(raw & _VALUE_STARTS) >= 4:
        raw -= _VALUE_STARTS | {"-", "+", "identifier", "::"}
        groups.append("a value")
    quoted = sorted(f"'{w}'" for w in raw if w not in _UNQUOTED)
    items = quoted + sorted(w for w in raw if w in _UNQUOTED) + groups
    if not items:
        return "something else"
    if len(items) > 8:
        items = items[:7] + ["..."]
    if len(items) == 1:
        return items[0]
    return ", ".join(items[:-1]) + " or " + items[-1]


def _last_token(node) -> Token | None:
    if isinstance(node, Token):
        return node
    if isinstance(node, Tree):
        for child in reversed(node.children):
            tok = _last_token(child)
            if tok is not None:
                return tok
    return None


_TREE_WORDS = {"named_type": "the type", "base_type": "the type", "sequence_type": "the type",
               "string_type": "the type", "optional_type": "the type", "events": "the state list",
               "codel_params": "codel parameters", "parameters": "service parameters",
               "strings": "the string", "declarators": "the declarator", "declarator": "the declarator"}


def context(stack: list) -> tuple[str | None, Token | None]:
    """Describe what was read just before an error ("codel parameters", "'x'") and return that token."""
    if not stack:
        return None, None
    top = stack[-1]
    last = _last_token(top)
    opener = None
    for item in reversed(stack):
        if isinstance(item, Token) and item.value in _OPENERS:
            opener = _OPENERS[item.value]
            break
    if isinstance(top, Token):
        if top.value == ")" and opener == "codel":
            return "codel parameters", last
        if top.value == ")" and opener == "service":
            return "service parameters", last
        if top.type == "$END":
            return None, last
        return f"'{top.value}'", last
    if isinstance(top, Tree):
        if top.data in _TREE_WORDS:
            return _TREE_WORDS[top.data], last
    return (f"'{last.value}'" if last is not None else None), last


@dataclass
class SyntaxProblem:
    """One syntax error, positioned in the parsed (preprocessed) text."""

    line: int
    column: int
    end_line: int | None
    end_column: int | None
    offset: int  # character offset in the text, -1 at end of file
    message: str
    hint: str | None = None
    hint_line: int | None = None  # output line the hint talks about (mapped by the caller)


def explain(e: UnexpectedInput, text: str, words: dict[str, str]) -> SyntaxProblem:
    """Word a lark error for a user."""
    stack = []
    ip = getattr(e, "interactive_parser", None)
    if ip is not None:
        stack = list(ip.parser_state.value_stack)
    after, last = context(stack)
    if isinstance(e, UnexpectedToken):
        tok = e.token
        try:
            expected = e.accepts or e.expected
        except Exception:  # noqa: BLE001 - computing accepts replays the parser; never fail the report
            expected = e.expected
        exp = describe_expected(set(expected), words)
        if tok.type == "$END":
            found = "end of file"
            line, column = (last.end_line, last.end_column) if last is not None else (1, 1)
            end_line = end_column = None
            offset = -1
        else:
            if tok.value == "/" and text.startswith("/*", tok.start_pos):  # cpp passes an unclosed comment through
                return SyntaxProblem(tok.line, tok.column, tok.line, tok.column + 2, tok.start_pos,
                                     "unterminated comment", "a comment opened with '/*' must be closed with '*/'")
            found = _found(tok)
            line, column, end_line, end_column = tok.line, tok.column, tok.end_line, tok.end_column
            offset = tok.start_pos
        where = f" after {after}" if after else ""
        problem = SyntaxProblem(line, column, end_line, end_column, offset, f"expected {exp}{where}, found {found}")
        expected_words = {words.get(n, n) for n in expected}
        if ">" in expected_words and _has_shift(stack[-3:]):
            problem.hint = "'>>' is a shift operator here: write '> >' to close two template argument lists"
        elif ";" in expected_words and last is not None and tok.type != "$END" and tok.line > last.end_line:
            problem.hint = f"is a ';' missing after '{last.value}'?"
            problem.hint_line = last.end_line
        return problem
    if not isinstance(e, UnexpectedCharacters):  # UnexpectedEOF: not raised by LALR, but be safe
        line = text.count("\n") + 1
        column = len(text) - (text.rfind("\n") + 1) + 1
        exp = describe_expected(set(getattr(e, "expected", ()) or ()), words)
        return SyntaxProblem(line, column, None, None, -1, f"expected {exp}, found end of file")
    ch = e.char
    msg = f"unexpected character '{ch}'" if ch.isprintable() else f"unexpected character {ch!r}"
    if ch == '"':
        msg = "unterminated string"
    if text.startswith("/*", e.pos_in_stream):  # the preprocessor passes an unclosed comment through
        return SyntaxProblem(e.line, e.column, e.line, e.column + 2, e.pos_in_stream, "unterminated comment",
                             "a comment opened with '/*' must be closed with '*/'")
    allowed = None
    if ip is not None:
        try:
            allowed = ip.accepts()  # what the parser wants, not what the lexer tried
        except Exception:  # noqa: BLE001 - a description of the error must never fail
            allowed = None
    if not allowed:
        allowed = set(getattr(e, "allowed", None) or ()) - {"IDENT"}
    if allowed:
        msg += f"; expected {describe_expected(set(allowed), words)}"
        if after:
            msg += f" after {after}"
    return SyntaxProblem(e.line, e.column, e.line, e.column + 1, e.pos_in_stream, msg)


def _has_shift(items: list) -> bool:
    """Whether a '>>' was just read (as a token, or already reduced into a shift expression)."""
    for item in items:
        if isinstance(item, Token) and item.value == ">>":
            return True
        if isinstance(item, Tree) and (item.data == "shr" or _has_shift(item.children[-1:])):
            return True
    return False


def _found(tok: Token) -> str:
    if tok.type == "STRING":
        return f"string {tok.value}"
    return f"'{tok.value}'"


# ---------------------------------------------------------------------- recovery

_STRUCTURE = re.compile(r'"[^"\\\n]*(?:\\.[^"\\\n]*)*"|\'[^\'\\\n]*(?:\\.[^\'\\\n]*)*\'|[;{}]')


def _marks(text: str) -> list[tuple[int, str]]:
    return [(m.start(), m.group()) for m in _STRUCTURE.finditer(text) if m.group() in (";", "{", "}")]


def enclosing_item(text: str, offset: int, widen: int = 0) -> tuple[int, int] | None:
    """The character range of the declaration around ``offset`` (``widen`` levels further out).

    A declaration runs from just after the previous ';', '{' or '}' at the same
    brace depth to its terminating ';' (or to just before the '}' that closes
    the enclosing block), so that blanking it out leaves balanced braces.
    """
    marks = _marks(text)
    before = [m for m in marks if m[0] < offset]
    after = [m for m in marks if m[0] >= offset]
    # walk back to the start of the item, climbing `widen` blocks
    depth = 0
    level = widen
    start = 0
    i = len(before) - 1
    while i >= 0:
        pos, ch = before[i]
        if ch == "}":
            depth += 1
        elif ch == "{":
            if depth == 0:
                if level == 0:
                    start = pos + 1
                    break
                level -= 1  # climb: this block's header belongs to the item we blank out
            else:
                depth -= 1
        elif ch == ";" and depth == 0 and level == 0:
            start = pos + 1
            break
        i -= 1
    else:
        if widen and level > 0:
            return None
    # walk forward to the end of the item
    depth = widen  # the blocks we climbed out of must be closed again
    end = len(text)
    for pos, ch in after:
        if ch == "{":
            depth += 1
        elif ch == "}":
            if depth == 0:
                end = pos
                break
            depth -= 1
        elif ch == ";" and depth == 0:
            end = pos + 1
            break
    if end <= start:
        return None
    return start, end


def blank(text: str, start: int, end: int) -> str:
    """Replace a range by spaces, keeping newlines so that later positions do not move."""
    middle = "".join(c if c == "\n" else " " for c in text[start:end])
    return text[:start] + middle + text[end:]


# --------------------------------------------------------------------------- GenoM2

_GENOM2_TERMINALS = {
    "NAME": "a name", "STRING": "a string", "INT_NUMBER": "a number", "FLOAT_NUMBER": "a number",
    "CHAR_LIT": "a character", "BASE_WORD": "a C type", "QUALIFIER": "'const'", "STORAGE": "'extern'",
    "STRUCT": "'struct'", "UNION": "'union'", "ENUM": "'enum'", "TYPEDEF": "'typedef'", "WCET": "'wcet'",
    "STAR": "'*'", "ELLIPSIS": "'...'", "OROR": "'||'", "ANDAND": "'&&'", "BAR": "'|'", "CARET": "'^'",
    "AMP": "'&'", "EQOP": "'=='", "RELOP": "'<'", "SHIFTOP": "'<<'", "ADDOP": "'+'", "MULOP": "'/'",
    "UNOP": "'!'", "$END": "end of input",
}


def _genom2_terminal(name: str) -> str:
    if name in _GENOM2_TERMINALS:
        return _GENOM2_TERMINALS[name]
    try:
        pattern = grammar_parser().get_terminal(name).pattern
    except KeyError:
        return name
    if pattern.type == "str":
        return f"'{pattern.value}'"
    return name.lower()


_GENOM2_OPERATORS = {"OROR", "ANDAND", "BAR", "CARET", "AMP", "EQOP", "RELOP", "SHIFTOP", "ADDOP", "MULOP", "UNOP",
              "STAR", "QMARK", "DOT", "LSQB", "LPAR", "COLON"}
_GENOM2_FIRST = ["';'", "'}'", "'{'", "':'", "','", "a name"]


def expected_genom2(names: set[str]) -> str:
    """The expected terminals in words: punctuation that ends things first.

    Operators are dropped when other choices exist.
    """
    if names & {"SEMICOLON", "COMMA", "RBRACE"}:
        names = names - _GENOM2_OPERATORS
    texts = sorted({_genom2_terminal(n) for n in names})
    if "ADDOP" in names and "INT_NUMBER" in names:
        texts = [t for t in texts if t not in ("'+'", "'!'", "'('")] + ["an expression"]
    texts = [t for t in _GENOM2_FIRST if t in texts] + [t for t in texts if t not in _GENOM2_FIRST]
    if len(texts) > 8:
        texts = texts[:8] + ["..."]
    if len(texts) == 1:
        return texts[0]
    return ", ".join(texts[:-1]) + " or " + texts[-1]
