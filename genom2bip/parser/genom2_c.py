"""The C part of GenoM2 files: typedef/struct/union/enum declarations and constant expressions.

GenoM2 modules describe their internal data and poster contents with plain C
declarations (in the ``.gen`` file, in ``#include``d headers after cpp, or in
``import from`` blocks).  This module turns the lark trees of those
declarations into IR types registered in :class:`Description.types`, and
evaluates the C constant expressions found in array bounds, enumerators and
GenoM2 fields.  C integer types are mapped to their IDL names (docs/genom2.md).
"""
from __future__ import annotations

from typing import Any, Callable

from lark import Token, Tree

from genom2bip.ir import (
    ArrayType,
    BaseType,
    Constant,
    Description,
    EnumType,
    EnumValue,
    Member,
    NamedType,
    SequenceType,
    StringType,
    StructType,
    Type,
    Typedef,
    UnionCase,
    UnionType,
)
from genom2bip.parser.limits import INT_MAX, literal_too_long, number_problem
from runtime.diagnostics import Reporter, Span


class CError(Exception):
    """A problem in a C declaration or expression, reported at ``span``."""

    def __init__(self, span: Span, message: str, hint: str | None = None) -> None:
        super().__init__(message)
        self.span = span
        self.message = message
        self.hint = hint


SpanOf = Callable[[Any], Span]


def first_token(node: Any) -> Token | None:
    """The first token of a tree (for positions); None for an empty tree."""
    stack = [node]
    while stack:
        node = stack.pop()
        if isinstance(node, Token):
            return node
        if isinstance(node, Tree):
            stack.extend(reversed(node.children))
    return None


# --------------------------------------------------------------------------- literals


def int_literal(text: str) -> int:
    """An integer literal as GenoM2's lexer reads it: hex after ``0x``, else decimal (parser.l uses atoi).

    GenoM2 has no octal: ``010`` is ten and ``09001`` is 9001.  Suffixes u/l are ignored.
    """
    digits = text.rstrip("uUlL")
    digits, base = (digits[2:], 16) if digits.lower().startswith("0x") else (digits, 10)
    return int(digits, base) if not literal_too_long(digits, base) else INT_MAX + 1  # out of range: reported


def string_literal(text: str) -> str:
    """Decode one C string literal token (with its quotes)."""
    body = text[1:-1]
    out: list[str] = []
    escapes = {
        "n": "\n",
        "t": "\t",
        "r": "\r",
        "0": "\0",
        "\\": "\\",
        '"': '"',
        "'": "'",
        "a": "\a",
        "b": "\b",
        "f": "\f",
        "v": "\v",
    }
    i = 0
    while i < len(body):
        ch = body[i]
        if ch == "\\" and i + 1 < len(body):
            out.append(escapes.get(body[i + 1], body[i + 1]))
            i += 2
        else:
            out.append(ch)
            i += 1
    return "".join(out)


def char_literal(text: str) -> int:
    decoded = string_literal(text)
    return ord(decoded[0]) if decoded else 0


# --------------------------------------------------------------------------- expressions


def _c_div(a: Any, b: Any) -> Any:
    if isinstance(a, int) and isinstance(b, int):
        q = abs(a) // abs(b)
        return q if (a >= 0) == (b >= 0) else -q
    return a / b


def _c_mod(a: int, b: int) -> int:
    return a - _c_div(a, b) * b


_BINARY = {
    "||": lambda a, b: int(bool(a) or bool(b)),
    "&&": lambda a, b: int(bool(a) and bool(b)),
    "|": lambda a, b: a | b,
    "^": lambda a, b: a ^ b,
    "&": lambda a, b: a & b,
    "==": lambda a, b: int(a == b),
    "!=": lambda a, b: int(a != b),
    "<": lambda a, b: int(a < b),
    ">": lambda a, b: int(a > b),
    "<=": lambda a, b: int(a <= b),
    ">=": lambda a, b: int(a >= b),
    "<<": lambda a, b: a << b,
    ">>": lambda a, b: a >> b,
    "+": lambda a, b: a + b,
    "-": lambda a, b: a - b,
    "*": lambda a, b: a * b,
    "/": _c_div,
    "%": _c_mod,
}


def evaluate(tree: Any, symbols: dict[str, Any], span_of: SpanOf) -> Any:
    """Evaluate a constant expression tree; names are looked up in ``symbols``."""
    try:
        return _evaluate(tree, symbols, span_of)
    except RecursionError:
        raise CError(span_of(first_token(tree)), "constant expression nested too deeply") from None


def _evaluate(tree: Any, symbols: dict[str, Any], span_of: SpanOf) -> Any:
    """One node's value, a number within what a description may hold (64-bit integers, finite floats)."""
    value = _value(tree, symbols, span_of)
    literal = getattr(tree, "data", None) in ("int_lit", "float_lit")
    problem = number_problem(value, str(tree.children[0]) if literal else None)
    if problem:
        raise CError(span_of(first_token(tree)), problem)
    return value


def _value(tree: Any, symbols: dict[str, Any], span_of: SpanOf) -> Any:
    if isinstance(tree, Token):
        raise CError(span_of(tree), f"expected a constant expression, found '{tree}'")
    kind = tree.data
    ch = tree.children
    if kind == "int_lit":
        return int_literal(str(ch[0]))
    if kind == "float_lit":
        return float(str(ch[0]).rstrip("fFlL"))
    if kind == "char_lit":
        return char_literal(str(ch[0]))
    if kind == "path":
        if len(ch) != 1:
            raise CError(span_of(ch[0]), f"'{path_text(tree)}' is not a constant")
        name = str(ch[0])
        if name not in symbols:
            raise CError(span_of(ch[0]), f"unknown constant '{name}'",
                         "constants are #define'd macros, enumerators or const declarations seen before")
        return symbols[name]
    if kind == "unop":
        op, operand = str(ch[0]), _evaluate(ch[1], symbols, span_of)
        if op == "-":
            return -operand
        if op == "+":
            return operand
        if op == "!":
            return int(not operand)
        if not isinstance(operand, int):
            raise CError(span_of(ch[0]), "'~' needs an integer operand")
        return ~operand
    if kind == "binop":
        left = _evaluate(ch[0], symbols, span_of)
        op = str(ch[1])
        right = _evaluate(ch[2], symbols, span_of)
        if op in ("/", "%") and right == 0:
            raise CError(span_of(ch[1]), "division by zero in a constant expression")
        if op in ("|", "^", "&", "<<", ">>", "%") and not (isinstance(left, int) and isinstance(right, int)):
            raise CError(span_of(ch[1]), f"'{op}' needs integer operands")
        if op in ("<<", ">>") and not 0 <= right < 64:
            raise CError(span_of(ch[1]), f"shift count {right} out of range (0 to 63)")
        return _BINARY[op](left, right)
    if kind == "ternary":
        cond = _evaluate(ch[0], symbols, span_of)
        return _evaluate(ch[1] if cond else ch[2], symbols, span_of)
    raise CError(span_of(first_token(tree)), "expected a constant expression")


def path_text(tree: Tree) -> str:
    """Render a ``path`` tree (``a.b[2]``) as text."""
    out = ""
    for child in tree.children:
        if isinstance(child, Token):
            out += ("." if out else "") + str(child)
        else:
            out += "[...]" if not (isinstance(child, Tree) and child.data == "int_lit") else f"[{child.children[0]}]"
    return out


# --------------------------------------------------------------------------- types


def base_type(words: list[str]) -> str | None:
    """The IDL name of a C base type written as ``words`` (None if the combination is invalid)."""
    unsigned = words.count("unsigned")
    signed = words.count("signed")
    longs = words.count("long")
    rest = [w for w in words if w not in ("unsigned", "signed", "long")]
    if unsigned + signed > 1 or longs > 2:
        return None
    prefix = "unsigned " if unsigned else ""
    if rest == ["void"] and not (unsigned or signed or longs):
        return "void"
    if rest == ["float"] and not (unsigned or signed or longs):
        return "float"
    if rest == ["double"] and not (unsigned or signed) and longs <= 1:
        return "long double" if longs else "double"
    if rest == ["char"] and not longs:
        return "octet" if unsigned else "char"
    if rest in (["short"], ["short", "int"], ["int", "short"]) and not longs:
        return prefix + "short"
    if rest in ([], ["int"]):
        if longs == 2:
            return prefix + "long long"
        return prefix + "long"  # C int and long are 32-bit IDL longs on GenoM2's targets
    return None


class CDeclarations:
    """Registers the C declarations of one GenoM2 file into a description."""

    def __init__(self, description: Description, reporter: Reporter, span_of: SpanOf, symbols: dict[str, Any]) -> None:
        self.description = description
        self.reporter = reporter
        self.span_of = span_of
        self.symbols = symbols
        self._anonymous = 0

    # ------------------------------------------------------------------ registration

    def register(self, name: str, node: Any, span: Span) -> None:
        """Add a named type; the same definition twice (a header seen by two modules) is fine."""
        known = self.description.types.get(name)
        if known is None:
            self.description.types[name] = node
        elif known != node:
            where = getattr(known, "span", None)
            where_text = f" (first defined at {where})" if where is not None and where.line > 0 else ""
            self.reporter.error(span, f"duplicate type '{name}': already defined differently{where_text}")

    def evaluate(self, tree: Any) -> Any:
        return evaluate(tree, self.symbols, self.span_of)

    def dimension(self, tree: Any) -> int:
        value = self.evaluate(tree)
        if not isinstance(value, int) or value <= 0:
            raise CError(self.span_of(first_token(tree)), f"array size must be a positive integer, not {value!r}")
        return value

    # ------------------------------------------------------------------ declarations

    def declare(self, tree: Tree) -> None:
        """Handle one top-level ``c_decl`` tree; errors are reported, never raised."""
        try:
            self._declare(tree)
        except CError as err:
            self.reporter.error(err.span, err.message, err.hint)

    def _declare(self, tree: Tree) -> None:
        kind = tree.data
        if kind == "typedef":
            _kw, spec, decls = tree.children
            hint = self._first_declarator_name(decls)
            base = self.type_spec(spec, hint)
            for name_tok, typ, is_function in self.declarators(decls, base):
                if name_tok is None or is_function:
                    continue
                self._register_typedef(str(name_tok), typ, self.span_of(name_tok))
        elif kind == "tag_decl":
            spec = tree.children[0]
            base = self.type_spec_core(spec, None)
            if len(tree.children) > 1:
                self.declarators(tree.children[1], base)  # variables: evaluate bounds, keep nothing
        elif kind in ("var_decl", "named_var_decl"):
            base = self.type_spec_core(tree.children[0], None)
            self.declarators(tree.children[1], base)
        elif kind == "storage_decl":
            words = [c for c in tree.children if isinstance(c, Token) and c.type in ("STORAGE", "QUALIFIER")]
            rest = [c for c in tree.children if not (isinstance(c, Token) and c.type in ("STORAGE", "QUALIFIER"))]
            if not rest:
                return
            core = rest[0]
            base = self.type_spec_core(core, None)
            if len(rest) > 1 and isinstance(rest[-1], Tree) and rest[-1].data == "declarators":
                is_const = any(str(w) == "const" for w in words) or any(
                    isinstance(c, Token) and str(c) == "const" for c in tree.children)
                for name_tok, typ, is_function, init in self.declarators(rest[-1], base, with_init=True):
                    if is_const and name_tok is not None and not is_function and init is not None:
                        self._declare_constant(name_tok, typ, init)

    def _declare_constant(self, name_tok: Token, typ: Type, init: Any) -> None:
        if isinstance(init, Tree) and init.data == "init_list":
            return
        value = self.evaluate(init)
        name = str(name_tok)
        self.symbols[name] = value
        self.description.constants.setdefault(name, Constant(name, typ, value, span=self.span_of(name_tok)))

    def _register_typedef(self, name: str, typ: Type, span: Span) -> None:
        if isinstance(typ, (StructType, UnionType, EnumType)) and typ.name == name:
            self.register(name, typ, span)  # typedef of an anonymous struct: the struct takes the name
            return
        if isinstance(typ, NamedType) and typ.name == name:
            return  # typedef struct X X;
        self.register(name, Typedef(name, typ, span=span), span)

    @staticmethod
    def _first_declarator_name(decls: Tree) -> str | None:
        for tok in decls.scan_values(lambda v: isinstance(v, Token) and v.type == "NAME"):
            return str(tok)
        return None

    # ------------------------------------------------------------------ declarators

    def declarators(self, decls: Tree, base: Type, with_init: bool = False) -> list:
        """Apply each declarator of ``decls`` to ``base``: (name token, type, is_function[, initializer])."""
        out = []
        for init_decl in decls.children:
            declarator = init_decl.children[0]
            init = None
            for extra in init_decl.children[1:]:
                if not (isinstance(extra, Tree) and extra.data == "bitfield"):
                    init = extra
            name_tok, typ, is_function = self.apply(declarator, base)
            out.append((name_tok, typ, is_function, init) if with_init else (name_tok, typ, is_function))
        return out

    def apply(self, declarator: Tree, base: Type) -> tuple[Token | None, Type, bool]:
        stars = [c for c in declarator.children if isinstance(c, Token) and c.type == "STAR"]
        direct = declarator.children[-1]
        typ = base
        for _ in stars:
            typ = self.pointer(typ)
        return self._apply_direct(direct, typ)

    def _apply_direct(self, node: Any, typ: Type) -> tuple[Token | None, Type, bool]:
        kind = node.data
        if kind == "decl_name":
            return node.children[0], typ, False
        if kind == "decl_paren":
            return self.apply(node.children[0], typ)
        if kind == "decl_array":
            inner = node.children[0]
            if len(node.children) > 1 and node.children[1] is not None:
                dim = self.dimension(node.children[1])
                if isinstance(typ, ArrayType):
                    wrapped: Type = ArrayType(typ.element, [dim] + list(typ.dims), span=typ.span)
                else:
                    wrapped = ArrayType(typ, [dim], span=self.span_of(first_token(node)))
            else:
                wrapped = SequenceType(typ, span=self.span_of(first_token(node)))
            return self._apply_direct(inner, wrapped)
        if kind == "decl_function":
            name_tok, _typ, _ = self._apply_direct(node.children[0], BaseType("function"))
            return name_tok, BaseType("function"), True
        raise CError(self.span_of(first_token(node)), "unsupported declarator")

    @staticmethod
    def pointer(typ: Type) -> Type:
        """C pointers have no IDL equivalent: ``char *`` is a string, other pointers unbounded sequences."""
        if isinstance(typ, BaseType) and typ.name == "char":
            return StringType(span=typ.span)
        if isinstance(typ, BaseType) and typ.name in ("void", "function"):
            return BaseType("pointer", span=typ.span)
        return SequenceType(typ, span=typ.span)

    # ------------------------------------------------------------------ type specifiers

    def type_spec(self, spec: Tree, hint: str | None) -> Type:
        """A ``type_spec`` tree (qualifiers ignored) as an IR type."""
        cores = [c for c in spec.children if not (isinstance(c, Token) and c.type == "QUALIFIER")]
        return self.type_spec_core(cores[0], hint)

    def type_spec_core(self, core: Any, hint: str | None) -> Type:
        if isinstance(core, Token):  # a typedef name
            return NamedType(str(core), span=self.span_of(core))
        kind = core.data
        if kind == "type_spec":
            return self.type_spec(core, hint)
        if kind == "base_type":
            words = [str(w) for w in core.children]
            name = base_type(words)
            if name is None:
                raise CError(self.span_of(core.children[0]), f"invalid C type '{' '.join(words)}'")
            return BaseType(name, span=self.span_of(core.children[0]))
        if kind == "tagged_ref":
            return NamedType(str(core.children[1]), span=self.span_of(core.children[1]))
        if kind in ("struct_spec", "union_spec"):
            return self._struct(core, hint)
        if kind == "enum_spec":
            return self._enum(core, hint)
        raise CError(self.span_of(first_token(core)), "unsupported type specifier")

    def _tag(self, node: Tree, hint: str | None) -> tuple[str, Span, bool]:
        """Name of a struct/union/enum: its tag, else the typedef name, else a generated one."""
        names = [c for c in node.children[1:] if isinstance(c, Token) and c.type == "NAME"]
        if names and names[0] is node.children[1]:
            return str(names[0]), self.span_of(names[0]), True
        self._anonymous += 1
        return hint or f"anonymous_{self._anonymous}", self.span_of(node.children[0]), False

    def _struct(self, node: Tree, hint: str | None) -> Type:
        name, span, tagged = self._tag(node, hint)
        members: list[Member] = []
        seen: dict[str, Member] = {}
        for member in (c for c in node.children if isinstance(c, Tree) and c.data == "member"):
            spec = member.children[0]
            member_hint = (
                f"{name}_{self._first_declarator_name(member.children[1])}" if len(member.children) > 1 else None
            )
            base = self.type_spec(spec, member_hint)
            if len(member.children) < 2:
                continue  # anonymous member or bare declaration: nothing to name
            for name_tok, typ, is_function in self.declarators(member.children[1], base):
                if name_tok is None or is_function:
                    continue
                mname = str(name_tok)
                if mname in seen:
                    self.reporter.error(
                        self.span_of(name_tok), f"duplicate member '{mname}' in {node.children[0]} {name}"
                    )
                    continue
                seen[mname] = Member(mname, typ, span=self.span_of(name_tok))
                members.append(seen[mname])
        if node.data == "union_spec":
            cases = [UnionCase([], m, span=m.span) for m in members]
            result: Type = UnionType(name, BaseType("long"), cases, span=span)
        else:
            result = StructType(name, members, span=span)
        if tagged:
            self.register(name, result, span)
            return NamedType(name, span=span)
        return result

    def _enum(self, node: Tree, hint: str | None) -> Type:
        name, span, tagged = self._tag(node, hint)
        enumerators: list[str] = []
        value = 0
        for item in (c for c in node.children if isinstance(c, Tree) and c.data == "enumerator"):
            tok = item.children[0]
            if len(item.children) > 1:
                value = self.evaluate(item.children[1])
            if str(tok) in enumerators:
                self.reporter.error(self.span_of(tok), f"duplicate enumerator '{tok}' in enum {name}")
            enumerators.append(str(tok))
            self.symbols[str(tok)] = value
            if isinstance(value, int):
                self.description.constants.setdefault(
                    str(tok), Constant(str(tok), NamedType(name, span=span), EnumValue(value, str(tok)),
                                       span=self.span_of(tok)))
            value = value + 1 if isinstance(value, int) else value
        result = EnumType(name, enumerators, span=span)
        if tagged:
            self.register(name, result, span)
            return NamedType(name, span=span)
        return result

    # ------------------------------------------------------------------ lookups

    def resolve(self, typ: Type | None) -> Type | None:
        """Follow named types and typedefs to a structural type (None when unknown)."""
        seen: set[str] = set()
        while isinstance(typ, NamedType):
            if typ.name in seen:
                return None
            seen.add(typ.name)
            node = self.description.types.get(typ.name)
            if node is None:
                return None
            typ = node.type if isinstance(node, Typedef) else node
        return typ
