"""BIP2 text out: a runtime.model Package printed as Verimag BIP2 source (jinja2 templates).

The writer prints what it is given and refuses, with every problem named, a
model that BIP2 cannot express or that uses a reserved word as a name:
renaming is the generator's job (``bip_identifier``), done once and
consistently, not a silent fix here.  ``runtime.bip2.parse_text`` reads the
text back into an equal model.
"""
from __future__ import annotations

import math

import jinja2

from genom2bip.back.bip2_timed import resume_clause, timed_atom_problems
from runtime.bip2.literals import format_literal
from runtime.bip2.printer import action as print_action
from runtime.bip2.printer import expr as print_expr
from runtime.bip2.reserved import IDENTIFIER, RESERVED, is_identifier
from runtime.errors import Genom2bipError
from runtime.model import (
    BUILTIN_TYPES, Annotation, Assign, AtomType, Binary, Call, CompoundType, ConnectorType, Const, DefineGroup,
    DefinePort, Do, If, InteractionSpec, Package, PortData, Rate, Transition, Unary, Var,
)
from runtime.model.expressions import BINARY_PRECEDENCE

__all__ = ["RESERVED", "BipWriteError", "bip_identifier", "write_package"]

#: Operators of runtime.model that the Verimag BIP2 grammar has (it has no shifts and no unary '+').
UNARY_OPERATORS = ("-", "!", "~")
BINARY_OPERATORS = tuple(op for op in BINARY_PRECEDENCE if op not in ("<<", ">>"))
WIDTH = 100


class BipWriteError(Genom2bipError, ValueError):
    """The model cannot be written as BIP2; ``problems`` names each offending declaration."""

    def __init__(self, package: str, problems: list[str]) -> None:
        self.problems = problems
        lines = "\n".join(f"  - {p}" for p in problems)
        super().__init__(f"cannot write package {package} as BIP2 ({len(problems)} problem(s)):\n{lines}")


def bip_identifier(name: str) -> str:
    """A BIP2 identifier for ``name``: other characters become '_', a leading digit gets '_' before it,
    a reserved word gets '_' after it (``error`` -> ``error_``, ``pause::s`` -> ``pause__s``)."""
    out = "".join(ch if ch.isascii() and (ch.isalnum() or ch == "_") else "_" for ch in name) or "_"
    if out[0].isdigit():
        out = "_" + out
    return out + "_" if out in RESERVED else out


# ---------------------------------------------------------------------- what BIP2 can express
class _Problems:
    """Walks a package and collects every reason it cannot be printed as BIP2."""

    def __init__(self) -> None:
        self.items: list[str] = []

    def add(self, where: str, message: str) -> None:
        self.items.append(f"{where}: {message}")

    def name(self, where: str, what: str, name: str, dotted: bool = False) -> None:
        parts = name.split(".") if dotted else [name]
        for part in parts:
            if part in RESERVED:
                self.add(where, f"{what} '{name}' uses the reserved word '{part}'; rename it consistently "
                                f"(bip_identifier gives '{bip_identifier(part)}')")
                return
            if not IDENTIFIER.match(part):
                self.add(where, f"{what} '{name}' is not a BIP2 identifier (letters, digits, '_'); "
                                f"bip_identifier gives '{bip_identifier(name)}'")
                return

    def type_name(self, where: str, what: str, name: str) -> None:
        if name not in BUILTIN_TYPES:
            self.name(where, what, name, dotted=True)

    def annotations(self, where: str, annotations: list[Annotation]) -> None:
        for a in annotations:
            self.name(where, "annotation", a.name)
            for key in a.arguments:
                self.name(where, f"key of annotation @{a.name}", key)

    def expr(self, where: str, e) -> None:
        if isinstance(e, Const):
            v = e.value
            if not isinstance(v, (bool, int, float, str)):
                self.add(where, f"no BIP2 literal for {type(v).__name__} {v!r}")
            elif isinstance(v, float) and not math.isfinite(v):
                self.add(where, f"no BIP2 literal for the float {v!r}")
        elif isinstance(e, Var):
            self.name(where, "variable", e.name)
        elif isinstance(e, PortData):
            self.name(where, "port", e.port)
            self.name(where, "data", e.name)
        elif isinstance(e, Call):
            self.name(where, "function", e.function, dotted=True)
            for a in e.args:
                self.expr(where, a)
        elif isinstance(e, Unary):
            if e.op not in UNARY_OPERATORS:
                self.add(where, f"BIP2 has no unary operator '{e.op}'")
            self.expr(where, e.operand)
        elif isinstance(e, Binary):
            if e.op not in BINARY_OPERATORS:
                self.add(where, f"BIP2 has no binary operator '{e.op}'")
            self.expr(where, e.left)
            self.expr(where, e.right)
        else:
            self.add(where, f"not an expression: {e!r}")

    def stmts(self, where: str, stmts) -> None:
        for s in stmts:
            if isinstance(s, Assign):
                self.expr(where, s.target)
                self.expr(where, s.value)
            elif isinstance(s, Do):
                self.expr(where, s.call)
            elif isinstance(s, Rate):
                self.name(where, "clock", s.clock)
                self.expr(where, s.value)
            elif isinstance(s, If):
                self.expr(where, s.cond)
                if not s.then:
                    self.add(where, "an 'if' with an empty 'then' branch (BIP2 needs a statement there; negate "
                                    "the condition instead)")
                self.stmts(where, s.then)
                self.stmts(where, s.orelse)
            else:
                self.add(where, f"not a statement: {s!r}")

    def package(self, pkg: Package) -> list[str]:
        where = f"package {pkg.name}"
        self.name(where, "package name", pkg.name, dotted=True)
        self.annotations(where, pkg.annotations)
        for u in pkg.uses:
            self.name(where, "used package", u, dotted=True)
        for c in pkg.constants:
            w = f"constant {c.name}"
            self.name(w, "constant", c.name)
            self.type_name(w, "type", c.type)
            self.annotations(w, c.annotations)
            if c.value is None:
                self.add(w, "a package constant needs a value")
            else:
                self.expr(w, c.value)
        for t in pkg.extern_types:
            self.name(f"extern data type {t}", "type", t)
            self.annotations(f"extern data type {t}", pkg.extern_type_annotations.get(t, []))
        for f in pkg.extern_functions:
            w = f"extern function {f.name}"
            self.name(w, "function", f.name)
            for t in ([f.return_type] if f.return_type else []) + f.param_types:
                self.type_name(w, "type", t)
            if len(f.param_const) != len(f.param_types):
                self.add(w, f"{len(f.param_const)} const flag(s) for {len(f.param_types)} parameter(s)")
            self.annotations(w, f.annotations)
        for pt in pkg.port_types:
            w = f"port type {pt.name}"
            self.name(w, "port type", pt.name)
            self.annotations(w, pt.annotations)
            self.params(w, pt.params)
        for a in pkg.atom_types:
            self.atom(a)
        for c in pkg.connector_types:
            self.connector(c)
        for k in pkg.compound_types:
            self.compound(k)
        return self.items

    def params(self, where: str, params) -> None:
        for p in params:
            self.name(where, "parameter", p.name)
            self.type_name(where, "type", p.type)

    def data(self, where: str, decls) -> None:
        for d in decls:
            w = f"{where}, data {d.name}"
            self.name(w, "data", d.name)
            self.type_name(w, "type", d.type)
            self.annotations(w, d.annotations)
            if d.init is not None:
                self.expr(w, d.init)

    def atom(self, a: AtomType) -> None:
        where = f"atom type {a.name}"
        self.name(where, "atom type", a.name)
        self.annotations(where, a.annotations)
        self.params(where, a.params)
        self.data(where, a.data)
        for p in a.ports:
            w = f"{where}, port {p.name}"
            self.name(w, "port", p.name)
            self.type_name(w, "port type", p.type)
            self.annotations(w, p.annotations)
            for d in p.data:
                self.name(w, "data", d)
        if not a.places:
            self.add(where, "no place (BIP2 needs 'place ...')")
        for pl in a.places:
            self.name(where, "place", pl)
        if a.initial is None:
            self.add(where, "no initial transition (BIP2 needs 'initial to ...')")
        else:
            self.transition_places(f"{where}, initial", [], a.initial.targets, initial=True)
            self.stmts(f"{where}, initial", a.initial.action)
        for t in a.transitions:
            w = f"{where}, {_transition_label(t)}"
            if t.port is not None:
                self.name(w, "port", t.port)
            self.annotations(w, t.annotations)
            self.transition_places(w, t.sources, t.targets)
            if t.guard is not None:
                self.expr(w, t.guard)
            self.stmts(w, t.action)
        for pr in a.priorities:
            w = f"{where}, priority {pr.name}"
            self.name(w, "priority", pr.name)
            for port in (pr.low, pr.high):
                if port != "*":
                    self.name(w, "port", port)
            if pr.guard is not None:
                self.expr(w, pr.guard)
        timed_atom_problems(self, a, where)

    def transition_places(self, where: str, sources, targets, initial: bool = False) -> None:
        if not initial and not sources:
            self.add(where, "no source place")
        if not targets:
            self.add(where, "no target place")
        for pl in list(sources) + list(targets):
            self.name(where, "place", pl)

    def connector(self, c: ConnectorType) -> None:
        where = f"connector type {c.name}"
        self.name(where, "connector type", c.name)
        self.annotations(where, c.annotations)
        if not c.params:
            self.add(where, "no port parameter (BIP2 needs at least one)")
        for p in c.params:
            self.name(where, "port parameter", p.name)
            self.type_name(where, "port type", p.port_type)
        self.data(where, c.data)
        for d in c.data:
            if d.exported:
                self.add(f"{where}, data {d.name}", "connector data cannot be exported (export a port instead)")
        if c.export is not None:
            w = f"{where}, export port {c.export.name}"
            self.name(w, "port", c.export.name)
            self.type_name(w, "port type", c.export.port_type)
            self.annotations(w, c.export.annotations)
            for d in c.export.data:
                self.name(w, "data", d)
        if c.define.trigger:
            self.add(where, "the whole define expression cannot be a trigger; nest it: define (p q)'")
        self.define(where, c.define)
        for spec in c.interactions:
            w = f"{where}, on {' '.join(spec.ports)}"
            self.annotations(w, spec.annotations)
            if not spec.ports:
                self.add(where, "an interaction names no port")
            for p in spec.ports:
                self.name(w, "port", p)
            if spec.guard is not None:
                self.expr(w, spec.guard)
            self.stmts(w, spec.up)
            self.stmts(w, spec.down)

    def define(self, where: str, group: DefineGroup) -> None:
        if not group.items:
            self.add(where, "empty define expression or group")
        for item in group.items:
            if isinstance(item, DefinePort):
                self.name(where, "port in define", item.name)
            elif isinstance(item, DefineGroup):
                self.define(where, item)
            else:
                self.add(where, f"not a define item: {item!r}")

    def compound(self, k: CompoundType) -> None:
        where = f"compound type {k.name}"
        self.name(where, "compound type", k.name)
        self.annotations(where, k.annotations)
        self.params(where, k.params)
        if not k.components and not k.connectors:
            self.add(where, "no component and no connector (BIP2 needs at least one)")
        for c in k.components:
            w = f"{where}, component {c.name}"
            self.name(w, "component", c.name)
            self.type_name(w, "type", c.type)
            self.annotations(w, c.annotations)
            for a in c.args:
                self.expr(w, a)
        for c in k.connectors:
            w = f"{where}, connector {c.name}"
            self.name(w, "connector", c.name)
            self.type_name(w, "type", c.type)
            self.annotations(w, c.annotations)
            if c.args:
                self.add(w, "BIP2 connectors take no data arguments")
            if not c.ports:
                self.add(w, "no port")
            for r in c.ports:
                self.port_ref(w, r)
        for pr in k.priorities:
            w = f"{where}, priority {pr.name}"
            self.name(w, "priority", pr.name)
            for pattern in (pr.low, pr.high):
                if pattern.connector == "*":
                    if pattern.ports is not None:
                        self.add(w, "'*' (any connector) takes no port list: write *:*")
                else:
                    self.name(w, "connector", pattern.connector)
                    if pattern.ports is not None and not pattern.ports:
                        self.add(w, f"empty port list for connector {pattern.connector}: write {pattern.connector}:*")
                    for r in pattern.ports or []:
                        self.port_ref(w, r)
            if pr.guard is not None:
                self.expr(w, pr.guard)
        for e in k.ports:
            w = f"{where}, export port {e.name}"
            self.name(w, "exported port", e.name)
            self.annotations(w, e.annotations)
            if not e.targets:
                self.add(w, "names no port")
            for r in e.targets:
                self.port_ref(w, r)
        for e in k.data:
            w = f"{where}, export data {e.name}"
            self.name(w, "exported data", e.name)
            self.annotations(w, e.annotations)
            self.port_ref(w, e.target)

    def port_ref(self, where: str, ref) -> None:
        self.name(where, "component", ref.component)
        self.name(where, "port or data", ref.port)


def _transition_label(t: Transition) -> str:
    return "internal transition" if t.port is None else f"transition on {t.port}"


# ---------------------------------------------------------------------- jinja filters
def _annotation(a: Annotation) -> str:
    if not a.arguments:
        return f"@{a.name}"
    args = []
    for key, value in a.arguments.items():
        if value == "":
            args.append(key)
        elif is_identifier(value) or value in ("true", "false"):
            args.append(f"{key}={value}")
        else:
            args.append(f"{key}={print_expr(Const(value))}")
    return f"@{a.name}({', '.join(args)})"


def _annotations(annotations: list[Annotation], margin: str) -> str:
    """One line per annotation, each ending with a newline, ready to precede a declaration."""
    return "".join(f"{margin}{_annotation(a)}\n" for a in annotations)


def _comment(text: str | None, margin: str) -> str:
    if not text:
        return ""
    return "".join(f"{margin}// {line}".rstrip() + "\n" for line in text.splitlines())


def _define(group: DefineGroup) -> str:
    parts = []
    for item in group.items:
        text = f"({_define(item)})" if isinstance(item, DefineGroup) else item.name
        parts.append(text + ("'" if item.trigger else ""))
    return " ".join(parts)


def _clauses(head: str, clauses: list[tuple[str, str | None]], margin: str) -> str:
    """``head clause clause`` on one line when it fits, else each clause on its own line under ``head``."""
    inner = margin + "  "
    rendered = [kw if body is None else f"{kw} {print_action(body, inner) if isinstance(body, list) else body}"
                for kw, body in clauses]
    line = " ".join([head] + rendered)
    if len(margin) + len(line) <= WIDTH and "\n" not in line:
        return line
    return head + "".join(f"\n{inner}{r}" for r in rendered)


def _transition(t: Transition, margin: str) -> str:
    head = "internal" if t.port is None else f"on {t.port}"
    head += f" from {', '.join(t.sources)} to {', '.join(t.targets)}"
    clauses = []
    if t.guard is not None:
        clauses.append(("provided", f"({print_expr(t.guard)})"))
    if t.urgency is not None:
        clauses.append((t.urgency, None))
    if t.action:
        clauses.append(("do", t.action))
    clauses += resume_clause(t.resume)
    return _clauses(head, clauses, margin)


def _interaction(spec: InteractionSpec, margin: str) -> str:
    clauses = []
    if spec.guard is not None:
        clauses.append(("provided", f"({print_expr(spec.guard)})"))
    if spec.up:
        clauses.append(("up", spec.up))
    if spec.down:
        clauses.append(("down", spec.down))
    return _clauses(f"on {' '.join(spec.ports)}", clauses, margin)


def _pattern(p) -> str:
    if p.connector == "*":
        return "*:*"
    return f"{p.connector}:" + ("*" if p.ports is None else ", ".join(map(str, p.ports)))


def _port_decls(ports) -> list[tuple[object, str]]:
    """Atom ports as declaration lines: one per port, one per group merged with ``as`` (consecutive ports)."""
    out: list[tuple[object, str]] = []
    for p in ports:
        binding = f"{p.name}({', '.join(p.data)})"
        if p.export_as is not None and out and out[-1][0].export_as == p.export_as and out[-1][0].type == p.type:
            first, text = out[-1]
            out[-1] = (first, text[:-len(f" as {p.export_as}")] + f", {binding} as {p.export_as}")
            continue
        if p.extern:
            tail = (f" as {format_literal(p.backend)}" if p.backend is not None else "") + \
                (f" {p.policy}" if p.policy is not None else "")
            out.append((p, f"extern port {p.type} {binding}{tail}"))
            continue
        head = ("export " if p.exported else "") + f"port {p.type} {binding}"
        out.append((p, head + (f" as {p.export_as}" if p.export_as is not None else "")))
    return out


def _environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.PackageLoader("genom2bip", "templates/bip2"),
        trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True,
        undefined=jinja2.StrictUndefined, autoescape=False,
    )
    env.filters.update({
        "expr": print_expr, "action": print_action, "annotations": _annotations, "comment": _comment,
        "define": _define, "transition": _transition, "interaction": _interaction, "pattern": _pattern,
        "resume": lambda r: "".join(f" {kw}" if body is None else f" {kw} {body}" for kw, body in resume_clause(r)),
        "port_decls": _port_decls,
    })
    return env


_ENV: jinja2.Environment | None = None


def _tidy(text: str) -> str:
    """No trailing blanks, at most one empty line in a row, one newline at the end."""
    lines = [line.rstrip() for line in text.splitlines()]
    out: list[str] = []
    for line in lines:
        if line or (out and out[-1]):
            out.append(line)
    while out and not out[-1]:
        out.pop()
    return "\n".join(out) + "\n"


# ---------------------------------------------------------------------- API
def write_package(package: Package) -> str:
    """BIP2 source text of ``package``; raises BipWriteError naming every declaration BIP2 cannot express."""
    global _ENV
    problems = _Problems().package(package)
    if problems:
        raise BipWriteError(package.name, problems)
    if _ENV is None:
        _ENV = _environment()
    return _tidy(_ENV.get_template("package.bip.j2").render(package=package))

