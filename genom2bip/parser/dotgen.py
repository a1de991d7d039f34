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

import copy
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from typing import Any

from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedInput

from genom2bip.ir import (
    ArrayType,
    BaseType,
    Codel,
    CodelParam,
    Component,
    Constant,
    Description,
    Duration,
    EnumType,
    EnumValue,
    ExceptionDecl,
    FixedType,
    Interface,
    Member,
    NamedType,
    NativeType,
    OptionalType,
    Parameter,
    Port,
    SequenceType,
    Service,
    StringType,
    StructType,
    Task,
    Type,
    Typedef,
    UnionCase,
    UnionType,
    Yield,
)
from genom2bip.parser import dotgen_consts as K
from genom2bip.parser.dotgen_errors import blank, enclosing_item, explain, terminal_words
from genom2bip.parser.preprocess import Preprocessed
from runtime.diagnostics import NOWHERE, Reporter, Span

MAX_SYNTAX_ERRORS = 20

# kinds of names that open a scope; genom3 (scope.c, scope_push) reopens one of them by name
_SCOPES = {"module", "interface", "component"}

_TIME_UNITS = {"s": 1, "ms": 1_000, "us": 1_000_000}
_SIZE_UNITS = {"k": 1024, "m": 1024 * 1024, "M": 1024 * 1024}

# which properties each kind of block accepts (the grammar accepts all of them everywhere)
_COMPONENT_PROPS = {"doc", "version", "lang", "email", "require", "codels-require", "clock-rate", "provides",
                    "uses", "throws", "stack"}
_ALLOWED = {
    "component": _COMPONENT_PROPS,
    "interface": _COMPONENT_PROPS | {"extends"},
    "task": {"doc", "period", "delay", "priority", "scheduling", "stack", "codel", "throws"},
    "port": {"doc"},
    "attribute": {"doc", "validate", "codel", "throws", "interrupts", "before", "after"},
    "function": {"doc", "validate", "codel", "throws", "interrupts", "before", "after", "local"},
    "activity": {"doc", "validate", "codel", "throws", "interrupts", "before", "after", "local", "task"},
}
_ARTICLE = {"component": "a component", "interface": "an interface", "task": "a task", "port": "a port",
            "attribute": "an attribute", "function": "a function", "activity": "an activity"}


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
    return Lark(text, parser="lalr", lexer="contextual", propagate_positions=True, maybe_placeholders=False,
                postlex=_WholeWords())


@lru_cache(maxsize=1)
def _words() -> dict[str, str]:
    return terminal_words(grammar().terminals)


def parse_dotgen(source: Preprocessed, reporter: Reporter, description: Description) -> None:
    """Parse one preprocessed GenoM3 file and add what it declares to ``description``."""
    tree, syntax_errors = _parse_recovering(source, reporter)
    if tree is None:
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


@dataclass
class _Symbol:
    kind: str  # type, const, enumerator, exception, module, component, interface, forward
    span: Span
    value: Any = None


def _strip(s: str) -> str:
    return K.unescape(s[1:-1])


class _Builder:
    """Walks a dotgen tree in source order and fills the description."""

    def __init__(self, source: Preprocessed, reporter: Reporter, description: Description, quiet_names: bool) -> None:
        self.src = source
        self.rep = reporter
        self.desc = description
        self.quiet_names = quiet_names  # after syntax errors, unknown names are likely consequences
        self.scope: list[str] = []
        self.symbols: dict[str, _Symbol] = {}
        self.components: list[Component] = []
        self.extended: dict[str, list[str]] = {}  # interface -> the interfaces already merged into it

    # ------------------------------------------------------------------ helpers

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
        self.symbols[full] = _Symbol(kind, span, value)
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

    # ------------------------------------------------------------------ statements

    def run(self, tree: Tree) -> None:
        for child in tree.children:
            self.statement(child)
        for pragma in self.src.pragmas:
            self.desc.pragmas.append(pragma)
        for comp in self.components:
            self.apply_pragmas(comp)
            self.merge_provided(comp)
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
            self.symbols[full] = _Symbol("module", self.span(name))
        elif sym.kind not in _SCOPES:  # scopes may be reopened (an IDL module and an interface share one)
            self.error(name, f"'{full}' is already defined", hint=f"first defined at {sym.span}")
        self.scope.append(str(name))
        for item in items:
            self.statement(item)
        self.scope.pop()

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
            self.symbols[full] = _Symbol("forward", self.span(name))

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

    st_union_type = st_struct_type
    st_enum_type = st_struct_type

    # ------------------------------------------------------------------ types

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
                    self.error(decl, f"duplicate member '{name}' in {owner}", hint=f"first declared at {seen[name].span}")
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
                self.error(decl, f"duplicate member '{mname}' in union '{name}'", hint=f"first declared at {names[mname]}")
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

    # ------------------------------------------------------------------ constants

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
            return K.float_literal(str(ch[0]))
        if kind == "char_lit":
            return _strip(str(ch[0]))
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
            return K.unary({"neg": "-", "pos": "+", "inv": "~"}[kind], self.eval(ch[0]), span)
        ops = {"bit_or": "|", "bit_xor": "^", "bit_and": "&", "shl": "<<", "shr": ">>", "add": "+", "sub": "-",
               "mul": "*", "div": "/", "mod": "%"}
        if kind in ops:
            return K.binary(ops[kind], self.eval(ch[0]), self.eval(ch[1]), span)
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
        seconds = value / _TIME_UNITS[name]
        text = self.text_of(expr, unit if unit is not None else expr).strip()
        if unit is None:
            text += " s"
        return Duration(float(seconds), text)

    def strings(self, node: Tree) -> str:
        """Adjacent string literals concatenate, as in C."""
        return "".join(_strip(str(t)) for t in node.children)

    # ------------------------------------------------------------------ components and interfaces

    def st_component(self, node: Tree) -> None:
        name, *body = node.children
        if not self.open_scope(name, "component", self.desc.interfaces):
            return
        comp = self.desc.component(str(name))
        if comp is None:  # else reopened, as genom3's comp_push does
            comp = Component(str(name), "genom3", file=self.span(name).file, span=self.span(name))
            self.desc.components.append(comp)
        if comp not in self.components:
            self.components.append(comp)
        self.body(comp, "component", body[0] if body else None)

    def st_interface(self, node: Tree) -> None:
        name, *body = node.children
        if not self.open_scope(name, "interface", {c.name: c for c in self.desc.components}):
            return
        iface = self.desc.interfaces.get(str(name))
        if iface is None:  # else reopened
            iface = Interface(str(name), span=self.span(name))
            self.desc.interfaces[str(name)] = iface
        self.body(iface, "interface", body[0] if body else None)
        merged = self.extended.setdefault(str(name), [])
        for base in iface.properties.get("extends", []):
            other = self.desc.interfaces.get(base)
            if other is None:
                self.error(iface.span, f"interface '{name}' extends unknown interface '{base}'")
                continue
            if base in merged:
                continue
            merged.append(base)
            self.merge_checked(iface, other, f"interface '{name}'", iface.span)

    def open_scope(self, name: Token, kind: str, others: dict) -> bool:
        """Register a component or interface scope; False (reported) when the name is the other kind's."""
        full = self.qualify(str(name))
        sym = self.symbols.get(full)
        if str(name) in others or (sym is not None and sym.kind not in _SCOPES):
            first = sym.span if sym is not None else others[str(name)].span
            self.error(name, f"conflicting declarations of '{full}': already declared as "
                             f"{sym.kind if sym is not None else 'another kind'}", hint=f"first declared at {first}")
            return False
        if sym is None or sym.kind == "module":
            self.symbols[full] = _Symbol(kind, self.span(name))
        return True

    def body(self, owner: Component | Interface, kind: str, body: Tree | None) -> None:
        """The items of a component or interface body, in order."""
        if body is None:
            return
        self.scope.append(owner.name)
        ids_seen: dict[str, Member] = {}
        for item in body.children:
            data = item.data
            if data == "ids":
                self.ids(owner, item, ids_seen)
            elif data == "task":
                task = self.task(item)
                self.add_unique(owner.tasks, task, "task", item.children[0])
            elif data == "port":
                port = self.port(item)
                name_tok = next(c for c in reversed(item.children) if isinstance(c, Token) and c.type == "IDENT")
                self.add_unique(owner.ports, port, "port", name_tok)
            elif data in ("attribute", "service"):
                service = self.service(item)
                self.add_unique(owner.services, service, "service", self.service_name_token(item))
            elif data.startswith("p_"):
                self.component_property(owner, kind, item)
            else:
                self.statement(item)
        self.scope.pop()

    def ids(self, owner: Component | Interface, node: Tree, seen: dict[str, Member]) -> None:
        """An ``ids`` block: a struct type named ``C::ids`` whose scope holds the types declared inside."""
        full = self.qualify("ids")
        if full not in self.desc.types:
            self.symbols[full] = _Symbol("type", self.span(node))
            # the members list is the component's own, so provided interfaces' members join the type too
            self.desc.types[full] = StructType(full, owner.ids, span=self.span(node))
        if not seen:
            seen.update((m.name, m) for m in owner.ids)
        self.scope.append("ids")
        owner.ids.extend(self.members(node.children, f"the ids of '{owner.name}'", seen))
        self.scope.pop()

    def add_unique(self, items: list, item: Any, what: str, node: Any) -> None:
        for old in items:
            if old.name == item.name:
                self.error(node, f"duplicate {what} '{item.name}'", hint=f"first declared at {old.span}")
                return
        items.append(item)

    def component_property(self, owner: Component | Interface, kind: str, prop: Tree) -> None:
        name = _prop_name(prop)
        if not self.allowed(prop, name, kind):
            return
        ch = prop.children
        if name in ("doc", "version", "lang", "email"):
            owner.properties[name] = self.strings(ch[0])
        elif name in ("require", "codels-require"):
            lst = ch[-1]
            owner.properties.setdefault(name, []).extend(self.strings(s) for s in lst.children)
        elif name == "clock-rate":
            d = self.duration(ch[1], ch[2] if len(ch) > 2 else None, "clock-rate")
            if isinstance(owner, Component):
                owner.clock_rate = d
            else:
                owner.properties["clock-rate"] = d
        elif name in ("provides", "uses"):
            names = [str(t) for t in ch[0].children]
            if isinstance(owner, Component):
                target = owner.provides if name == "provides" else owner.uses
                target.extend(n for n in names if n not in target)
                if name == "provides":
                    owner.ref_spans.update({f"provides:{t}": self.span(t) for t in ch[0].children})
            else:
                owner.properties.setdefault(name, []).extend(names)
        elif name == "extends":
            owner.properties.setdefault("extends", []).extend(str(t) for t in ch[0].children)
        elif name == "throws":
            self.extend_unique(owner.throws, self.throws(prop))
        elif name == "stack":
            owner.properties["stack"] = self.stack(prop)

    def allowed(self, prop: Tree, name: str, kind: str) -> bool:
        if name in _ALLOWED[kind]:
            return True
        allowed = ", ".join(sorted(_ALLOWED[kind]))
        self.error(prop, f"'{name}' is not a property of {_ARTICLE[kind]}", hint=f"allowed here: {allowed}")
        return False

    @staticmethod
    def extend_unique(target: list, values: list) -> None:
        target.extend(v for v in values if v not in target)

    def throws(self, prop: Tree, refs: dict[str, Span] | None = None) -> list[str]:
        """Exception names, scoped when declared; ``refs`` gets where each was written ("throws:NAME")."""
        out = []
        for name in prop.children[0].children:
            full = self.resolve(name, {"exception"}) or self.written(name).lstrip(":")
            out.append(full)
            if refs is not None:
                refs.setdefault(f"throws:{full}", self.span(name))
        return out

    def stack(self, prop: Tree) -> int | None:
        expr = prop.children[0]
        size = self.const_int(expr, "stack size")
        if size is None:
            return None
        unit = str(prop.children[1].children[0]) if len(prop.children) > 1 else None
        return size * _SIZE_UNITS.get(unit, 1) if unit else size

    # ------------------------------------------------------------------ tasks and ports

    def task(self, node: Tree) -> Task:
        name, *rest = node.children
        task = Task(str(name), span=self.span(name))
        for prop in self.block_items(rest):
            pname = _prop_name(prop)
            if not self.allowed(prop, pname, "task"):
                continue
            ch = prop.children
            if pname == "doc":
                task.doc = self.strings(ch[0])
            elif pname == "period":
                task.period = self.duration(ch[0], ch[1] if len(ch) > 1 else None, "period")
                task.ref_spans["period"] = self.span(ch[0])
                if task.period is not None and task.period.seconds == 0:
                    self.error(ch[0], "period must be positive", hint="leave the period out for an aperiodic task")
                    task.period = None
            elif pname == "delay":
                task.delay = self.duration(ch[0], ch[1] if len(ch) > 1 else None, "delay")
            elif pname == "priority":
                task.priority = self.const_int(ch[0], "priority", minimum=0)
            elif pname == "scheduling":
                task.scheduling = str(ch[0])
            elif pname == "stack":
                task.stack = self.stack(prop)
            elif pname == "codel":
                codel = self.codel(prop)
                if codel is not None:
                    if prop.children[-1].data == "simple_codel":
                        self.error(prop, f"codel '{codel.name}' of task '{name}' has no state",
                                   hint=f"write codel <start> {codel.name}(...) yield ...;")
                        continue
                    self.add_codel(task.codels, codel, f"task '{name}'")
            elif pname == "throws":
                self.extend_unique(task.throws, self.throws(prop, task.ref_spans))
        return task

    def block_items(self, rest: list) -> list[Tree]:
        """The properties of an optional block; ``task NAME;`` is handled by services only."""
        if not rest:
            return []
        out = []
        for item in rest[0].children:
            if item.data == "task_ref":
                out.append(Tree("p_task", item.children, item.meta))
            else:
                out.append(item)
        return out

    def port(self, node: Tree) -> Port:
        ch = list(node.children)
        multiple = isinstance(ch[0], Token) and ch[0].type == "MULTIPLE"
        if multiple:
            ch.pop(0)
        direction, type_node, name, *rest = ch
        port = Port(str(name), str(direction.children[0]), self.type(type_node), multiple, span=self.span(name))
        for prop in self.block_items(rest):
            pname = _prop_name(prop)
            if self.allowed(prop, pname, "port") and pname == "doc":
                port.doc = self.strings(prop.children[0])
        return port

    # ------------------------------------------------------------------ services

    @staticmethod
    def service_name_token(node: Tree) -> Token:
        return node.children[0] if node.data == "attribute" else node.children[1]

    def service(self, node: Tree) -> Service:
        if node.data == "attribute":
            kind = "attribute"
            name, *rest = node.children
        else:
            kind_node, name, *rest = node.children
            kind = str(kind_node.children[0])
        service = Service(str(name), kind, span=self.span(name))
        if rest and isinstance(rest[0], Tree) and rest[0].data == "parameters":
            service.parameters = self.parameters(rest.pop(0), service)
        for prop in self.block_items(rest):
            pname = _prop_name(prop)
            if pname == "task" and kind != "activity":
                self.error(prop, f"'task' is not a property of {_ARTICLE[kind]}",
                           hint=f"{kind}s run in the control task; only activities name an execution task")
                continue
            if not self.allowed(prop, pname, kind):
                continue
            ch = prop.children
            if pname == "doc":
                service.doc = self.strings(ch[0])
            elif pname == "task":
                if service.task is not None:
                    self.error(prop, f"activity '{name}' already runs in task '{service.task}'")
                service.task = str(ch[0])
                service.ref_spans["task"] = self.span(ch[0])
            elif pname == "validate":
                if service.validate is not None:
                    self.error(prop, f"service '{name}' already has a validate codel '{service.validate.name}'")
                service.validate = self.simple_codel(ch[0])
            elif pname == "codel":
                codel = self.codel(prop)
                if codel is None:
                    continue
                if kind == "activity" and prop.children[-1].data == "simple_codel":
                    self.error(prop, f"codel '{codel.name}' of activity '{name}' has no state",
                               hint=f"write codel <start> {codel.name}(...) yield ...;")
                    continue
                if kind == "attribute" and codel.triggers:  # genom3 service.c: no state machine codels
                    self.error(prop, f"attribute '{name}' cannot have state machine codels",
                               hint=f"write codel {codel.name}(...); or make it a function")
                    continue
                self.add_codel(service.codels, codel, f"service '{name}'")
            elif pname in ("interrupts", "before", "after"):
                self.extend_unique(getattr(service, pname), [str(t) for t in ch[0].children])
                for t in ch[0].children:
                    service.ref_spans.setdefault(f"{pname}:{t}", self.span(t))
            elif pname == "throws":
                self.extend_unique(service.throws, self.throws(prop, service.ref_spans))
            elif pname == "local":
                known = {m.name: m for m in service.locals}
                service.locals.extend(self.members([Tree("member", ch, prop.meta)], f"the locals of '{name}'", known))
        return service

    def add_codel(self, codels: list[Codel], codel: Codel, owner: str) -> None:
        """Add an FSM codel, refusing a state already handled by another codel of the same owner."""
        for other in codels:
            for t in codel.triggers:
                if t in other.triggers:
                    self.error(codel.span, f"state '{t}' of {owner} is already handled by codel '{other.name}'",
                               hint=f"see {other.span}")
                    return
        codels.append(codel)

    def parameters(self, node: Tree, service: Service) -> list[Parameter]:
        out: list[Parameter] = []
        for p in node.children:
            param = self.parameter(p, service.kind)
            if param is None:
                continue
            if any(q.name == param.name for q in out):
                self.error(p, f"duplicate parameter '{param.name}' in service '{service.name}'")
                continue
            out.append(param)
        return out

    def parameter(self, node: Tree, kind: str) -> Parameter | None:
        dir_node, body, *init = node.children
        direction = str(dir_node.children[0])
        span = self.span(node)
        form = body.data
        if form in ("typed", "typed_named"):
            type_node, decl = body.children
            base = self.type(Tree("named_type", [type_node], type_node.meta) if form == "typed_named" else type_node)
            name, t = self.declarator(decl, base)
            param = Parameter(direction, name, t, source="local", span=span)
        elif form == "ids_name":
            (scoped,) = body.children
            parts = [str(t) for t in scoped.children]
            if scoped.data == "absolute_name" and len(parts) == 1:
                param = Parameter(direction, parts[0], None, source="ids", member="", span=span)
            elif scoped.data == "relative_name" and len(parts) <= 2:
                param = Parameter(direction, parts[-1], None, source="ids", member=parts[0], span=span)
            else:
                self.error(body, f"bad parameter '{self.written(scoped)}'",
                           hint="write 'member', 'member::name', '::name' or a type and a name")
                return None
        else:  # ids_path: member.field[2]::name
            scoped, *rest = body.children
            if scoped.data != "relative_name" or len(scoped.children) != 1:
                self.error(body, f"bad parameter path starting with '{self.written(scoped)}'")
                return None
            path = str(scoped.children[0])
            last_name = path
            alias = None
            for suffix in rest:
                if isinstance(suffix, Token):
                    alias = str(suffix)
                elif suffix.data == "suffix_member":
                    last_name = str(suffix.children[0])
                    path += f".{last_name}"
                else:
                    index = self.const_int(suffix.children[0], "index", minimum=0)
                    path += f"[{index}]"
            param = Parameter(direction, alias or last_name, None, source="ids", member=path, span=span)
        if init:
            target = param.type if param.type is not None else self.ids_type(param.member or "")
            if target is not None and init[0].data != "init_only_doc":
                self.check_init(init[0].children[0], target, param.name)
            value, doc, docs = self.initializer(init[0], top=True)
            if value is not None and param.type is not None:
                try:
                    value = K.coerce(self.base_name(param.type), value, self.span(init[0]), f"parameter '{param.name}'")
                except K.ConstError as exc:
                    self.error(exc.span, exc.message)
                    value = None
            param.default, param.doc, param.member_docs = value, doc, docs
        return param

    # ------------------------------------------------------------------ initializers

    def ids_type(self, member: str) -> Type | None:
        """The declared type of an ids member named by a parameter (the whole ids for ''), if known here."""
        ids = self.desc.types.get(self.qualify("ids"))
        if not isinstance(ids, StructType):
            return None
        if not member:
            return ids
        head = member.replace("[", ".").split(".")[0]
        found = next((m for m in ids.members if m.name == head), None)
        return found.type if found is not None and head == member else None

    def resolved(self, t: Type) -> Type:
        """A type through named types and typedefs."""
        for _ in range(20):
            if not isinstance(t, NamedType):
                return t
            target = self.desc.types.get(t.name)
            if isinstance(target, Typedef):
                t = target.type
            elif isinstance(target, Type):
                return target
            else:
                return t
        return t

    def check_init(self, node: Tree, t: Type, what: str) -> None:
        """genom3's initializer.c: braces give no more elements than the type has, and only its members."""
        if node.data != "init_list":
            return
        t = self.resolved(t)
        items = node.children[0].children if node.children else []
        if isinstance(t, StructType):
            names = [m.name for m in t.members]
            index = 0
            for item in items:
                inner = item.children[0] if item.data != "init_only_doc" else None
                if inner is not None and inner.data == "init_field":
                    name = str(inner.children[0])
                    if name not in names:
                        self.error(inner, f"unknown member '{name}' in struct {t.name}",
                                   hint=f"its members: {', '.join(names)}")
                        continue
                    index = names.index(name) + 1
                    member = t.members[index - 1]
                    if len(inner.children) > 1:
                        self.check_init(inner.children[1], member.type, f"{what}.{name}")
                    continue
                if inner is not None and inner.data == "init_index":
                    self.error(inner, f"an index designator cannot initialize struct {t.name}")
                    continue
                if index >= len(names):
                    self.error(item, f"too many initializers for struct {t.name} in '{what}'",
                               hint=f"it has {len(names)} member{'s' if len(names) != 1 else ''}")
                    return
                if inner is not None:
                    self.check_init(inner, t.members[index].type, f"{what}.{names[index]}")
                index += 1
        elif isinstance(t, ArrayType) and len(t.dims) == 1:
            positional = [i for i in items if i.data == "init_only_doc" or i.children[0].data not in (
                "init_field", "init_index")]
            if len(positional) > t.dims[0]:
                self.error(positional[t.dims[0]], f"too many initializers for array '{what}'",
                           hint=f"it has {t.dims[0]} element{'s' if t.dims[0] != 1 else ''}")

    def initializer(self, node: Tree, top: bool = False, path: str = "") -> tuple[Any, str | None, dict[str, str]]:
        """(value, doc, docs of parts): ``{ .x = 1 : "doc" }`` gives ({'x': 1}, None, {'x': 'doc'})."""
        docs: dict[str, str] = {}
        doc = None
        if node.data == "init_only_doc":
            return None, self.strings(node.children[0]), docs
        value_node = node.children[0]
        if node.data == "init_doc":
            doc = self.strings(node.children[1])
        if value_node.data in ("init_index", "init_field") and top:
            self.error(value_node, "a designator ('.name =' or '[i] =') must be inside braces")
            return None, doc, docs
        value = self.init_value(value_node, path, docs)
        return value, doc, docs

    def init_value(self, node: Tree, path: str, docs: dict[str, str]) -> Any:
        """A default value: a constant, a list (positional braces) or a dict (designated braces)."""
        if node.data == "init_expr":
            return self.const(node.children[0])
        assert node.data == "init_list", node.data
        entries: list[tuple[Any, Any]] = []
        designated = False
        index = 0
        for item in node.children[0].children if node.children else []:
            doc = self.strings(item.children[-1]) if item.data in ("init_doc", "init_only_doc") else None
            inner = item.children[0] if item.data != "init_only_doc" else None
            value = None
            if inner is not None and inner.data in ("init_field", "init_index"):
                designated = True
                if inner.data == "init_field":
                    key: Any = str(inner.children[0])
                else:
                    key = self.const_int(inner.children[0], "index", minimum=0)
                    key = index if key is None else key
                    index = key + 1
                if len(inner.children) > 1:
                    value = self.init_value(inner.children[1], _join(path, key), docs)
            else:
                key = index
                index += 1
                if inner is not None:
                    value = self.init_value(inner, _join(path, key), docs)
            if doc is not None:
                docs[_join(path, key)] = doc
            entries.append((key, value))
        if not designated:
            return [v for _, v in entries]
        return {k: v for k, v in entries if v is not None}

    # ------------------------------------------------------------------ codels

    def codel(self, prop: Tree) -> Codel | None:
        ch = prop.children
        is_async = isinstance(ch[0], Token) and ch[0].type == "ASYNC"
        body = ch[-1]
        codel = self.simple_codel(body) if body.data == "simple_codel" else self.fsm_codel(body)
        codel.is_async = is_async
        return codel

    def simple_codel(self, node: Tree) -> Codel:
        name, *rest = node.children
        codel = Codel(str(name), span=self.span(name))
        self.codel_tail(codel, rest)
        return codel

    def fsm_codel(self, node: Tree) -> Codel:
        triggers, name, *rest = node.children
        codel = Codel(str(name), span=self.span(name))
        for ev in triggers.children:
            if ev.data == "pause_event":
                self.error(ev, f"codel '{name}' cannot be triggered by 'pause::{ev.children[0]}'",
                           hint="pause:: only qualifies the states a codel yields")
                continue
            state = str(ev.children[0])
            if state in codel.triggers:
                self.error(ev, f"state '{state}' is listed twice for codel '{name}'")
                continue
            codel.triggers.append(state)
        params = [r for r in rest if r.data == "codel_params"]
        others = [r for r in rest if r.data != "codel_params"]
        events = others[0]
        for ev in events.children:
            y = Yield(str(ev.children[0]), ev.data == "pause_event", span=self.span(ev))
            if any(str(o) == str(y) for o in codel.yields):
                self.error(ev, f"codel '{name}' yields '{y}' twice")
                continue
            codel.yields.append(y)
        self.codel_tail(codel, params + others[1:])
        return codel

    def codel_tail(self, codel: Codel, rest: list[Tree]) -> None:
        for r in rest:
            if r.data == "codel_params":
                codel.params = [self.codel_param(p) for p in r.children]
            elif r.data == "wcet":
                expr, *unit = r.children
                codel.wcet = self.duration(expr, unit[0] if unit else None, "wcet")

    def codel_param(self, node: Tree) -> CodelParam:
        ch = list(node.children)
        source = None
        if isinstance(ch[0], Tree) and ch[0].data == "param_source":
            source = str(ch.pop(0).children[0])
        direction = str(ch.pop(0).children[0])
        if node.data == "codel_param_whole":
            return CodelParam("", direction, source, str(ch[0]), span=self.span(node))
        path = self.param_path(ch[0])
        alias = str(ch[1]) if len(ch) > 1 else None
        return CodelParam(path, direction, source, alias, span=self.span(node))

    def param_path(self, node: Tree) -> str:
        if node.data == "param_path":
            return str(node.children[0])
        base = self.param_path(node.children[0])
        if node.data == "path_member":
            return f"{base}.{node.children[1]}"
        index = self.const_int(node.children[1], "index", minimum=0)
        return f"{base}[{index}]"

    # ------------------------------------------------------------------ pragmas and interfaces

    def apply_pragmas(self, comp: Component) -> None:
        """``#pragma requires`` and ``#pragma provides`` apply to every component of the file."""
        for pragma in self.src.pragmas:
            args = pragma.arguments.strip()
            if pragma.name in ("requires", "require"):
                value = _strip(args) if len(args) >= 2 and args[0] == args[-1] == '"' else args
                reqs = comp.properties.setdefault("require", [])
                if value not in reqs:
                    reqs.append(value)
            elif pragma.name == "provides":
                for name in args.replace(",", " ").split():
                    if name not in comp.provides:
                        comp.provides.append(name)
                        comp.ref_spans[f"provides:{name}"] = pragma.span

    def merge_provided(self, comp: Component) -> None:
        for name in comp.provides:
            where = comp.ref_spans.get(f"provides:{name}", comp.span)
            iface = self.desc.interfaces.get(name)
            if iface is None:
                self.error(where, f"component '{comp.name}' provides unknown interface '{name}'",
                           hint="declare or #include the interface before the component")
                continue
            self.merge_checked(comp, iface, f"component '{comp.name}'", where)

    def merge_checked(self, target: Component | Interface, iface: Interface, what: str, where: Span) -> None:
        """Merge ``iface`` into ``target``, refusing what genom3's prop_merge and comp_addids refuse.

        An ids member declared on both sides must have the same named type; a
        clock rate, a stack size or a language declared on both sides must agree.
        """
        mine = {m.name: m for m in target.ids}
        for m in iface.ids:
            old = mine.get(m.name)
            if old is not None and not (isinstance(old.type, NamedType) and old.type == m.type):
                self.error(where, f"{what} gets ids member '{m.name}' from interface '{iface.name}' but declares "
                                  f"it too", hint=f"the two declarations: {old.span} and {m.span}")
        for key in ("clock-rate", "stack", "lang"):
            ours = target.clock_rate if key == "clock-rate" and isinstance(target, Component) \
                else target.properties.get(key)
            theirs = iface.properties.get(key)
            if ours is not None and theirs is not None and ours != theirs:
                self.error(where, f"conflicting {key} for {what}: {ours}, and {theirs} from interface '{iface.name}'")
            elif theirs is not None and ours is None:
                if key == "clock-rate" and isinstance(target, Component):
                    target.clock_rate = theirs
                else:
                    target.properties[key] = theirs
        self.merge(target, iface)

    @staticmethod
    def merge(target: Component | Interface, iface: Interface) -> None:
        """Import an interface's ids, tasks, ports, services and throws; the target's own definitions win."""
        ids_names = {m.name for m in target.ids}
        target.ids[:0] = [copy.deepcopy(m) for m in iface.ids if m.name not in ids_names]
        for attr in ("tasks", "ports"):
            own = getattr(target, attr)
            names = {x.name for x in own}
            own[:0] = [copy.deepcopy(x) for x in getattr(iface, attr) if x.name not in names]
        own_services = {s.name: s for s in target.services}
        inherited = []
        for s in iface.services:
            mine = own_services.get(s.name)
            if mine is None:
                inherited.append(copy.deepcopy(s))
                continue
            if mine.doc is None:
                mine.doc = s.doc
            if not mine.parameters:
                mine.parameters = copy.deepcopy(s.parameters)
            mine.throws[:0] = [t for t in s.throws if t not in mine.throws]
        target.services[:0] = inherited
        target.throws[:0] = [t for t in iface.throws if t not in target.throws]
        for key in ("require", "codels-require"):
            if key in iface.properties:
                reqs = target.properties.setdefault(key, [])
                reqs.extend(r for r in iface.properties[key] if r not in reqs)


def _prop_name(prop: Tree) -> str:
    return {"p_codels_require": "codels-require", "p_clock_rate": "clock-rate"}.get(prop.data, prop.data[2:])


def _join(path: str, key: Any) -> str:
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else str(key)
