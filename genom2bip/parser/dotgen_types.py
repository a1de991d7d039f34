"""The dotgen reader for IDL: modules' types, constants and exceptions, and constant expressions."""
from __future__ import annotations

from typing import Any

from lark import Tree

from genom2bip.ir import (
    ArrayType,
    BaseType,
    Constant,
    Duration,
    EnumType,
    EnumValue,
    ExceptionDecl,
    FixedType,
    Member,
    NamedType,
    NativeType,
    OptionalType,
    SequenceType,
    StringType,
    StructType,
    Type,
    Typedef,
    UnionCase,
    UnionType,
)
from genom2bip.parser import dotgen_consts as K
from genom2bip.parser.dotgen_base import TIME_UNITS, DotgenReader, Symbol, unquote
from genom2bip.parser.limits import MAX_DURATION, MIN_DURATION
from runtime.diagnostics import Span


class TypeReader(DotgenReader):
    """Types, constants and exceptions; constant expressions, sizes, durations and strings."""

    def st_const_dcl(self, node: Tree) -> None:
        type_node, name, expr = node.children
        ctype = self.type(type_node)
        value = self.const(expr)
        base = self.base_name(ctype)
        if value is not None:
            try:
                value = K.coerce(base, value, self.span(expr), f"constant '{name}'")
            except K.ConstError as exc:
                self.error(exc.span, exc.message)
                value = None
        full = self.declare(str(name), "const", name, value)
        if full:
            self.desc.constants[full] = Constant(full, ctype, value, span=self.span(name))

    def base_name(self, t: Type) -> str | None:
        """The base type behind a type (through typedefs), for constant checks."""
        seen = 0
        while isinstance(t, NamedType) and seen < 20:
            target = self.desc.types.get(t.name)
            if not isinstance(target, Typedef):
                return None
            t, seen = target.type, seen + 1
        if isinstance(t, BaseType):
            return t.name
        if isinstance(t, StringType):
            return "string"
        return None

    def st_typedef(self, node: Tree) -> None:
        type_node, decls = node.children
        base = self.type(type_node)
        for decl in decls.children:
            name, t = self.declarator(decl, base)
            full = self.declare(name, "type", decl)
            if full:
                self.desc.types[full] = Typedef(full, t, span=self.span(decl))

    def st_native(self, node: Tree) -> None:
        (name,) = node.children
        full = self.declare(str(name), "type", name)
        if full:
            self.desc.types[full] = NativeType(full, span=self.span(name))

    def st_forward(self, node: Tree) -> None:
        _kw, name = node.children
        full = self.qualify(str(name))
        if full not in self.symbols:
            self.symbols[full] = Symbol("forward", self.span(name))

    def st_exceptions(self, node: Tree) -> None:
        for dcl in node.children:
            name, *members = dcl.children
            full = self.declare(str(name), "exception", name)
            self.scope.append(str(name))
            fields = self.members(members, f"exception '{name}'")
            self.scope.pop()
            if full:
                self.desc.exceptions[full] = ExceptionDecl(full, fields, span=self.span(name))

    def st_struct_type(self, node: Tree) -> None:
        self.type(node)

    def type(self, node: Any) -> Type:
        kind = node.data
        span = self.span(node)
        if kind == "base_type":
            return BaseType(" ".join(str(t) for t in node.children), span=span)
        if kind == "named_type":
            (name,) = node.children
            full = self.resolve(name, {"type", "forward", "exception"})
            return NamedType(full or self.written(name).lstrip(":"), span=span)
        if kind == "sequence_type":
            elem = self.type(node.children[0])
            bound = self.size(node.children[1], "sequence bound") if len(node.children) > 1 else None
            return SequenceType(elem, bound, span=span)
        if kind == "optional_type":
            return OptionalType(self.type(node.children[0]), span=span)
        if kind == "string_type":
            exprs = [c for c in node.children if isinstance(c, Tree)]
            bound = self.size(exprs[0], "string bound") if exprs else None
            return StringType(bound, span=span)
        if kind == "fixed_type":
            if not node.children:
                return FixedType(span=span)
            digits = self.size(node.children[0], "fixed digits")
            scale = self.const_int(node.children[1], "fixed scale", minimum=0)
            return FixedType(digits, scale, span=span)
        if kind == "struct_type":
            return self.struct(node)
        if kind == "union_type":
            return self.union(node)
        if kind == "enum_type":
            return self.enum(node)
        raise AssertionError(f"unexpected type node {kind}")

    def declarator(self, decl: Tree, base: Type) -> tuple[str, Type]:
        name, *dims = decl.children
        if not dims:
            return str(name), base
        sizes = [self.size(d, "array size") or 1 for d in dims]
        return str(name), ArrayType(base, sizes, span=self.span(decl))

    def members(self, nodes: list[Tree], owner: str, known: dict[str, Member] | None = None) -> list[Member]:
        """Members of a struct, exception, ids or local block; duplicates are reported."""
        out: list[Member] = []
        seen = {} if known is None else known
        for member in nodes:
            type_node, decls = member.children
            base = self.type(type_node)
            for decl in decls.children:
                name, t = self.declarator(decl, base)
                m = Member(name, t, span=self.span(decl))
                if name in seen:
                    self.error(
                        decl, f"duplicate member '{name}' in {owner}", hint=f"first declared at {seen[name].span}"
                    )
                    continue
                seen[name] = m
                out.append(m)
        return out

    def struct(self, node: Tree) -> StructType:
        name, *members = node.children
        full = self.declare(str(name), "type", name) or self.qualify(str(name))
        self.scope.append(str(name))
        fields = self.members(members, f"struct '{name}'")
        self.scope.pop()
        t = StructType(full, fields, span=self.span(name))
        self.desc.types[full] = t
        return t

    def union(self, node: Tree) -> UnionType:
        name, disc_node, *cases = node.children
        full = self.declare(str(name), "type", name) or self.qualify(str(name))
        disc = self.type(disc_node)
        self.scope.append(str(name))
        out: list[UnionCase] = []
        names: dict[str, Span] = {}
        has_default = False
        for case in cases:
            *labels, type_node, decl = case.children
            values: list[Any] = []
            for label in labels:
                if label.data == "default_label":
                    if has_default:
                        self.error(label, f"union '{name}' has more than one default case")
                    has_default = True
                    values.append("default")
                else:
                    values.append(self.const(label.children[0]))
            mname, t = self.declarator(decl, self.type(type_node))
            if mname in names:
                self.error(
                    decl, f"duplicate member '{mname}' in union '{name}'", hint=f"first declared at {names[mname]}"
                )
            names[mname] = self.span(decl)
            out.append(UnionCase(values, Member(mname, t, span=self.span(decl)), span=self.span(case)))
        self.scope.pop()
        t = UnionType(full, disc, out, span=self.span(name))
        self.desc.types[full] = t
        return t

    def enum(self, node: Tree) -> EnumType:
        name, *enumerators = node.children
        full = self.declare(str(name), "type", name) or self.qualify(str(name))
        names = []
        for i, e in enumerate(enumerators):
            efull = self.qualify(str(e))
            if self.declare(str(e), "enumerator", e, EnumValue(i, efull)):
                names.append(str(e))
        t = EnumType(full, names, span=self.span(name))
        self.desc.types[full] = t
        return t

    def const(self, node: Any) -> Any:
        """Evaluate a constant expression; report and return None when it cannot be."""
        try:
            return self.eval(node)
        except K.ConstError as exc:
            if not (self.quiet_names and exc.message.startswith("unknown constant")):
                self.error(exc.span, exc.message)
            return None

    def eval(self, node: Any) -> Any:
        kind = node.data
        span = self.span(node)
        ch = node.children
        if kind == "int_lit":
            return K.int_literal(str(ch[0]), span)
        if kind == "float_lit":
            return K.float_literal(str(ch[0]), span)
        if kind == "char_lit":
            return unquote(str(ch[0]))
        if kind == "string_lit":
            return self.strings(ch[0])
        if kind == "true_lit":
            return True
        if kind == "false_lit":
            return False
        if kind == "const_ref":
            (name,) = ch
            full = self.resolve(name, {"const", "enumerator"})
            if full is None:
                if self.written(name).lstrip(":") in self.desc.constants:
                    return self.desc.constants[self.written(name).lstrip(":")].value
                raise K.ConstError(span, f"unknown constant '{self.written(name)}'")
            value = self.symbols[full].value
            if value is None:
                raise K.ConstError(span, f"constant '{full}' has no value (its definition has an error)")
            return value
        if kind in ("neg", "pos", "inv"):
            return K.checked(K.unary({"neg": "-", "pos": "+", "inv": "~"}[kind], self.eval(ch[0]), span), span)
        ops = {"bit_or": "|", "bit_xor": "^", "bit_and": "&", "shl": "<<", "shr": ">>", "add": "+", "sub": "-",
               "mul": "*", "div": "/", "mod": "%"}
        if kind in ops:
            return K.checked(K.binary(ops[kind], self.eval(ch[0]), self.eval(ch[1]), span), span)
        raise AssertionError(f"unexpected expression node {kind}")

    def const_int(self, node: Any, what: str, minimum: int = 1) -> int | None:
        value = self.const(node)
        if value is None:
            return None
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            need = "a positive integer" if minimum == 1 else f"an integer >= {minimum}"
            self.error(node, f"{what} must be {need}, not {value!r}")
            return None
        return int(value)

    def size(self, node: Any, what: str) -> int | None:
        return self.const_int(node, what, minimum=1)

    def number(self, node: Any, what: str) -> float | None:
        value = self.const(node)
        if value is None:
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.error(node, f"{what} must be a number, not {value!r}")
            return None
        return value

    def duration(self, expr: Tree, unit: Tree | None, what: str) -> Duration | None:
        value = self.number(expr, what)
        if value is None:
            return None
        if value < 0:
            self.error(expr, f"{what} must not be negative, not {value!r}")
            return None
        name = str(unit.children[0]) if unit is not None else "s"
        seconds = value / TIME_UNITS[name]
        text = self.text_of(expr, unit if unit is not None else expr).strip()
        if unit is None:
            text += " s"
        if seconds > MAX_DURATION or 0 < seconds < MIN_DURATION:
            self.error(expr, f"{what} must be between 1 us and 1 day, not {text}",
                       hint="durations are counted in whole microseconds")
            return None
        return Duration(float(seconds), text)

    def strings(self, node: Tree) -> str:
        """Adjacent string literals concatenate, as in C."""
        return "".join(unquote(str(t)) for t in node.children)

    st_union_type = st_struct_type
    st_enum_type = st_struct_type
