"""Turns the lark parse tree of a BIP2 package into runtime.model objects, noting where each name was read."""
from __future__ import annotations

from dataclasses import dataclass

from lark import Token, Transformer, v_args

from runtime.bip2.literals import decode_string
from runtime.bip2.locator import Locator
from runtime.bip2.reserved import UNUSED_KEYWORDS
from runtime.bip2.timed_builder import TimedBuilder
from runtime.diagnostics import Reporter, Span
from runtime.model import (
    Annotation,
    Assign,
    AtomPriority,
    AtomType,
    Binary,
    Call,
    ComponentInstance,
    CompoundType,
    ConnectorExport,
    ConnectorInstance,
    ConnectorParam,
    ConnectorType,
    Const,
    Constant,
    DataDecl,
    DataParam,
    DefineGroup,
    DefinePort,
    ClockDecl,
    Do,
    ExportData,
    ExportPort,
    ExternFunction,
    If,
    InitialTransition,
    InteractionPattern,
    InteractionSpec,
    Package,
    Invariant,
    PortData,
    PortDecl,
    PortRef,
    PortType,
    Priority,
    Transition,
    Unary,
    Var,
)


@dataclass
class _Name:
    """A possibly dotted name as read, with its span."""

    text: str
    parts: list[Token]
    span: Span


@dataclass
class _Names:
    tokens: list[Token]


@dataclass
class _Action:
    stmts: list


@dataclass
class _Places:
    tokens: list[Token]


@dataclass
class _ExternType:
    name: str
    annotations: list[Annotation]
    span: Span


class Builder(TimedBuilder, Transformer):
    """Bottom-up construction of a :class:`Package`; structural problems go to ``reporter``."""

    def __init__(self, filename: str, text: str, reporter: Reporter, locator: Locator) -> None:
        super().__init__(visit_tokens=True)
        self.filename = filename
        self.text = text
        self.reporter = reporter
        self.locator = locator
        self.extern_type_spans: dict[str, list[Span]] = {}

    # ------------------------------------------------------------------ helpers
    def span(self, tok: Token, last: Token | None = None) -> Span:
        last = last or tok
        return Span(self.filename, tok.line, tok.column, last.end_line, last.end_column)

    def ID(self, tok: Token) -> Token:
        if tok.value in UNUSED_KEYWORDS:
            self.reporter.error(
                self.span(tok),
                f"'{tok.value}' is a reserved word of BIP2 and cannot be used as a name",
                hint="rename it: the Verimag compilers reserve it (timed or extended BIP2)",
            )
        return tok

    def _note_names(self, obj, key: str, tokens: list[Token]) -> list[str]:
        for i, tok in enumerate(tokens):
            self.locator.note(obj, self.span(tok), (key, i))
        return [t.value for t in tokens]

    @staticmethod
    def _present(items):
        return [x for x in items if x is not None]

    # ------------------------------------------------------------------ names, annotations
    def qname(self, parts):
        return _Name(".".join(p.value for p in parts), list(parts), self.span(parts[0], parts[-1]))

    def type_name(self, children):
        (c,) = children
        return c if isinstance(c, _Name) else _Name(c.value, [c], self.span(c))

    def id_list(self, tokens):
        return _Names(list(tokens))

    def annots(self, children):
        return list(children)

    def annotation(self, children):
        name, *params = children
        args = dict(p for p in params if p is not None)
        return Annotation(name.value, args, span=self.span(name))

    def ann_param(self, children):
        key, value = children
        if value is None:
            return key.value, ""
        return key.value, decode_string(value.value) if value.type == "STRING" else value.value

    # ------------------------------------------------------------------ package
    def start(self, children):
        annotations, name, *rest = children
        pkg = Package(name.text, annotations=annotations, span=name.span)
        for item in rest:
            if isinstance(item, _Name):
                pkg.uses.append(item.text)
            elif isinstance(item, list):
                pkg.constants.extend(item)
            elif isinstance(item, _ExternType):
                pkg.extern_types.append(item.name)
                if item.annotations:
                    pkg.extern_type_annotations[item.name] = item.annotations
                self.extern_type_spans.setdefault(item.name, []).append(item.span)
            elif isinstance(item, ExternFunction):
                pkg.extern_functions.append(item)
            elif isinstance(item, PortType):
                pkg.port_types.append(item)
            elif isinstance(item, AtomType):
                pkg.atom_types.append(item)
            elif isinstance(item, ConnectorType):
                pkg.connector_types.append(item)
            elif isinstance(item, CompoundType):
                pkg.compound_types.append(item)
        self.locator.note(pkg, name.span, "name")
        for name_, spans in self.extern_type_spans.items():
            for i, s in enumerate(spans):
                self.locator.note(pkg, s, ("extern_type", name_, i))
        return pkg

    def use_clause(self, children):
        return children[0]

    def const_decl(self, children):
        annotations, type_, *inits = children
        out = []
        for tok, value in inits:
            c = Constant(type_.text, tok.value, value, annotations=list(annotations), span=self.span(tok))
            self.locator.note(c, type_.span, "type")
            if value is None:
                self.reporter.error(self.span(tok), f"constant '{tok.value}' needs a value",
                                    hint=f"write: const data {type_.text} {tok.value} = ...")
            out.append(c)
        return out

    def var_init(self, children):
        tok, value = children
        return tok, value

    def extern_type(self, children):
        annotations, name = children
        return _ExternType(name.value, annotations, self.span(name))

    def extern_function(self, children):
        annotations, ret, name, *params = children
        params = self._present(params)
        f = ExternFunction(name.value, ret.text if ret else None, [t.text for _, t in params],
                           annotations=annotations, param_const=[c for c, _ in params], span=self.span(name))
        if ret:
            self.locator.note(f, ret.span, "return_type")
        for i, (_, t) in enumerate(params):
            self.locator.note(f, t.span, ("param_types", i))
        return f

    def proto_param(self, children):
        const, type_, _ = children  # parameter names document the prototype only
        return const is not None, type_

    def port_type(self, children):
        annotations, name, *params = children
        return PortType(name.value, self._present(params), annotations=annotations, span=self.span(name))

    def data_param(self, children):
        const, type_, name = children
        p = DataParam(type_.text, name.value, const=const is not None, span=self.span(name))
        self.locator.note(p, type_.span, "type")
        return p

    # ------------------------------------------------------------------ atoms
    def atom_type(self, children):
        annotations, name, *rest = children
        atom = AtomType(name.value, annotations=annotations, span=self.span(name))
        for item in self._present(rest):
            if isinstance(item, DataParam):
                atom.params.append(item)
            elif isinstance(item, list) and item and isinstance(item[0], DataDecl):
                atom.data.extend(item)
            elif isinstance(item, list) and item and isinstance(item[0], ClockDecl):
                atom.clocks.extend(item)
            elif isinstance(item, list):
                atom.ports.extend(item)
            elif isinstance(item, _Places):
                atom.places = self._note_names(atom, "places", item.tokens)
            elif isinstance(item, InitialTransition):
                atom.initial = item
            elif isinstance(item, Transition):
                atom.transitions.append(item)
            elif isinstance(item, AtomPriority):
                atom.priorities.append(item)
            elif isinstance(item, Invariant):
                atom.invariants.append(item)
        return atom

    def data_decl(self, children):
        annotations, export, const, type_, *inits = children
        return self._data(annotations, export is not None, const is not None, type_, inits)

    def conn_data(self, children):
        annotations, const, type_, *inits = children
        return self._data(annotations, False, const is not None, type_, inits)

    def _data(self, annotations, exported, const, type_, inits):
        out = []
        for tok, value in inits:
            d = DataDecl(type_.text, tok.value, value, const=const, exported=exported,
                         annotations=list(annotations), span=self.span(tok))
            self.locator.note(d, type_.span, "type")
            out.append(d)
        return out

    def port_decl(self, children):
        annotations, export, type_, *bindings, merged = children
        out = []
        for tok, data in bindings:
            p = PortDecl(type_.text, tok.value, [], exported=export is not None,
                         annotations=list(annotations), span=self.span(tok),
                         export_as=merged.value if merged is not None else None)
            if merged is not None:
                self.locator.note(p, self.span(merged), "export_as")
            p.data = self._note_names(p, "data", data)
            self.locator.note(p, type_.span, "type")
            out.append(p)
        return out

    def extern_port_decl(self, children):
        annotations, type_, *bindings, backend, policy = children
        out = self.port_decl([annotations, None, type_, *bindings, None])
        for p in out:
            p.extern = True
            p.backend = decode_string(backend.value) if backend is not None else None
            if policy is not None:
                p.policy = policy.value
                self.locator.note(p, self.span(policy), "policy")
        return out

    def port_binding(self, children):
        name, *data = children
        return name, self._present(data)

    def places(self, tokens):
        return _Places(list(tokens))

    def initial(self, children):
        keyword, targets, act, resume = children
        init = InitialTransition([], act.stmts if act else [], span=self.span(keyword), resume=resume)
        init.targets = self._note_names(init, "targets", targets.tokens)
        return init

    def transition(self, children):
        annotations, keyword, *rest = children
        port = None
        if keyword.type == "ON":
            port_tok, *rest = rest
            port = port_tok.value
        if port:
            sources, targets, guard, urgency, act, resume = rest
        else:
            (sources, targets, guard, act), urgency, resume = rest, None, None
        t = Transition(port, [], [], guard, act.stmts if act else [], annotations=annotations,
                       span=self.span(port_tok if port else keyword),
                       urgency=urgency.value if urgency else None, resume=resume)
        if port:
            self.locator.note(t, self.span(port_tok), "port")
        t.sources = self._note_names(t, "sources", sources.tokens)
        t.targets = self._note_names(t, "targets", targets.tokens)
        return t

    def atom_priority(self, children):
        name, low, _lt, high, guard = children
        p = AtomPriority(name.value, low.value, high.value, guard, span=self.span(name))
        self.locator.note(p, self.span(low), "low")
        self.locator.note(p, self.span(high), "high")
        return p

    # ------------------------------------------------------------------ connectors
    def connector_type(self, children):
        annotations, name, *rest = children
        conn = ConnectorType(name.value, annotations=annotations, span=self.span(name))
        for item in self._present(rest):
            if isinstance(item, ConnectorParam):
                conn.params.append(item)
            elif isinstance(item, list):
                conn.data.extend(item)
            elif isinstance(item, ConnectorExport):
                conn.export = item
            elif isinstance(item, DefineGroup):
                conn.define = item
            elif isinstance(item, InteractionSpec):
                conn.interactions.append(item)
        return conn

    def connector_param(self, children):
        type_, name = children
        p = ConnectorParam(type_.text, name.value, span=self.span(name))
        self.locator.note(p, type_.span, "port_type")
        return p

    def conn_export(self, children):
        annotations, type_, name, *data = children
        e = ConnectorExport(type_.text, name.value, [], annotations=annotations, span=self.span(name))
        e.data = self._note_names(e, "data", self._present(data))
        self.locator.note(e, type_.span, "port_type")
        return e

    def define_items(self, items):
        return DefineGroup(list(items))

    def define_port(self, children):
        name, quote = children
        d = DefinePort(name.value, trigger=quote is not None)
        self.locator.note(d, self.span(name))
        return d

    def define_group(self, children):
        group, quote = children
        group.trigger = quote is not None
        return group

    def interaction(self, children):
        annotations, keyword, *rest = children
        *ports, guard, up, down = rest
        spec = InteractionSpec([], guard, up.stmts if up else [], down.stmts if down else [],
                               annotations=annotations, span=self.span(keyword))
        spec.ports = self._note_names(spec, "ports", ports)
        return spec

    # ------------------------------------------------------------------ compounds
    def compound_type(self, children):
        annotations, name, *rest = children
        comp = CompoundType(name.value, annotations=annotations, span=self.span(name))
        for item in self._present(rest):
            if isinstance(item, DataParam):
                comp.params.append(item)
            elif isinstance(item, list) and item and isinstance(item[0], ComponentInstance):
                comp.components.extend(item)
            elif isinstance(item, list):
                comp.connectors.extend(item)
            elif isinstance(item, Priority):
                comp.priorities.append(item)
            elif isinstance(item, ExportPort):
                comp.ports.append(item)
            elif isinstance(item, ExportData):
                comp.data.append(item)
        return comp

    def component_decl(self, children):
        annotations, type_, *instances = children
        out = []
        for tok, args in instances:
            c = ComponentInstance(type_.text, tok.value, args, annotations=list(annotations), span=self.span(tok))
            self.locator.note(c, type_.span, "type")
            out.append(c)
        return out

    def instance(self, children):
        name, *args = children
        return name, self._present(args)

    def comment_above(self, line: int) -> str | None:
        """The ``//`` lines right above source line ``line`` (1-based), as one text: the writer prints
        ``comment`` fields that way, and reading them back keeps regenerated text identical."""
        lines = self.text.splitlines()
        found: list[str] = []
        i = line - 2
        while i >= 0 and lines[i].strip().startswith("//"):
            body = lines[i].strip()[2:]
            found.insert(0, body[1:] if body.startswith(" ") else body)
            i -= 1
        return "\n".join(found) if found else None

    @v_args(meta=True)
    def connector_decl(self, meta, children):
        annotations, type_, *instances = children
        comment = self.comment_above(meta.line)
        out = []
        for tok, refs in instances:
            c = ConnectorInstance(type_.text, tok.value, refs, annotations=list(annotations), comment=comment,
                                  span=self.span(tok))
            self.locator.note(c, type_.span, "type")
            out.append(c)
        return out

    def conn_instance(self, children):
        name, *refs = children
        return name, refs

    def port_ref(self, children):
        comp, port = children
        ref = PortRef(comp.value, port.value)
        self.locator.note(ref, self.span(comp, port))
        return ref

    @v_args(meta=True)
    def compound_priority(self, meta, children):
        name, low, _lt, high, guard = children
        return Priority(name.value, low, high, guard, comment=self.comment_above(meta.line), span=self.span(name))

    def pattern_all(self, children):
        name, star = children
        p = InteractionPattern(name.value, None)
        self.locator.note(p, self.span(name, star))
        return p

    def pattern_ports(self, children):
        name, *refs = children
        p = InteractionPattern(name.value, list(refs))
        self.locator.note(p, self.span(name))
        return p

    def pattern_any(self, children):
        first, last = children
        p = InteractionPattern("*", None)
        self.locator.note(p, self.span(first, last))
        return p

    def _is_keyword(self, tok: Token) -> bool:
        if tok.value != "is":
            self.reporter.error(self.span(tok), f"expected 'is' but found '{tok.value}'",
                                hint="write: export port c.p as name  (or the older form: export port T name is c.p)")
            return False
        return True

    def export_port_as(self, children):
        annotations, *refs, name = children
        return ExportPort("", name.value, refs, annotations=annotations, span=self.span(name))

    def export_port_is(self, children):
        annotations, type_, name, is_, *refs = children
        self._is_keyword(is_)
        e = ExportPort(type_.text, name.value, refs, annotations=annotations, span=self.span(name))
        self.locator.note(e, type_.span, "type")
        return e

    def export_data_as(self, children):
        annotations, ref, name = children
        return ExportData("", name.value, ref, annotations=annotations, span=self.span(name))

    def export_data_is(self, children):
        annotations, type_, name, is_, ref = children
        self._is_keyword(is_)
        e = ExportData(type_.text, name.value, ref, annotations=annotations, span=self.span(name))
        self.locator.note(e, type_.span, "type")
        return e

    # ------------------------------------------------------------------ actions
    def action(self, stmts):
        return _Action(list(stmts))

    def assign(self, children):
        target, value = children
        return Assign(self._reference(target), value)

    def do_call(self, children):
        return Do(children[0])

    def if_stmt(self, children):
        cond, then, orelse = children
        return If(cond, tuple(then), tuple(orelse or ()))

    def then_block(self, stmts):
        return list(stmts)

    else_block = then_block

    # ------------------------------------------------------------------ expressions
    def binary(self, children):
        left, op, right = children
        return Binary(op.value, left, right)

    def neg(self, children):
        minus, operand = children
        if isinstance(operand, Const) and not isinstance(operand.value, (bool, str)):
            rest = self.text[minus.end_pos:].lstrip()
            if rest[:1].isdigit() or rest[:1] == ".":
                return Const(-operand.value)  # "-5" is the literal -5; "-(5)" is a negation
        return Unary("-", operand)

    def unop(self, children):
        op, operand = children
        return Unary(op.value, operand)

    def ref(self, children):
        return self._reference(children[0])

    def _reference(self, name: _Name):
        if len(name.parts) == 1:
            node = Var(name.text)
        else:
            if len(name.parts) > 2:
                self.reporter.error(
                    name.span, f"'{name.text}': a data reference has at most one dot (port.data or component.data)"
                )
            node = PortData(name.parts[0].value, name.parts[-1].value)
        self.locator.note(node, name.span)
        return node

    def call(self, children):
        name, *args = children
        node = Call(name.text, tuple(self._present(args)))
        self.locator.note(node, name.span)
        return node

    def int_lit(self, children):
        return Const(int(children[0].value))

    def float_lit(self, children):
        return Const(float(children[0].value))

    def string_lit(self, children):
        return Const(decode_string(children[0].value))

    def true_lit(self, _children):
        return Const(True)

    def false_lit(self, _children):
        return Const(False)

