"""Static checks of a BIP2 package: every name resolves, arities and port types agree, nothing is declared twice.

Run by the reader after parsing (errors then point at file:line:column) and
usable on a model built in code (errors then name the declaration).
"""
from __future__ import annotations

from runtime.bip2.defines import allows, define_ports
from runtime.bip2.interfaces import data_offer, port_offer
from runtime.bip2.lint import lint
from runtime.bip2.locator import Locator
from runtime.bip2.timed_checks import check_atom_timing
from runtime.bip2.scope import ExpressionChecker, Scope, suggestion
from runtime.diagnostics import NOWHERE, Diagnostic, Reporter, Span
from runtime.model import BUILTIN_TYPES, AtomType, CompoundType, ConnectorType, Package, PortData, PortRef, PortType


def validate(package: Package, locator: Locator | None = None, reporter: Reporter | None = None) -> list[Diagnostic]:
    """Every problem found in ``package``; they are also added to ``reporter`` when one is given.

    Errors, then (on a model with none) the Verimag compiler's warnings (runtime.bip2.lint), severity "warning".
    """
    reporter = reporter if reporter is not None else Reporter()
    before = len(reporter.diagnostics)
    locator = locator or Locator()
    _Checker(package, locator, reporter).run()
    if not any(d.severity == "error" for d in reporter.diagnostics[before:]):
        lint(package, locator, reporter)
    return reporter.diagnostics[before:]


_KINDS = {PortType: "port type", AtomType: "atom type", ConnectorType: "connector type", CompoundType: "compound type"}


class _Checker:
    def __init__(self, pkg: Package, loc: Locator, rep: Reporter) -> None:
        self.pkg, self.loc, self.rep = pkg, loc, rep
        self.lenient = bool(pkg.uses)  # names may come from used packages, which we do not read
        self.functions: dict = {}
        for f in pkg.extern_functions:
            self.functions.setdefault(f.name, []).append(f)
        self.constants = {c.name: "constant" for c in pkg.constants}
        self.exprs = ExpressionChecker(self.functions, loc, rep, lenient_calls=self.lenient)

    def error(self, span: Span, message: str, hint: str | None = None) -> None:
        self.rep.error(span, message, hint)

    # ------------------------------------------------------------------ helpers
    def unique(self, items, what: str, where: str, name=lambda x: x.name) -> None:
        seen: dict[str, object] = {}
        for item in items:
            key = name(item)
            if key in seen:
                first = self.loc.at(seen[key])
                hint = f"first declared at {first}" if first is not NOWHERE else None
                self.error(self.loc.at(item), f"duplicate {what} '{key}' in {where}", hint)
            else:
                seen[key] = item

    def kind_of(self, name: str) -> str | None:
        for decls, kind in ((self.pkg.port_types, "port type"), (self.pkg.atom_types, "atom type"),
                            (self.pkg.connector_types, "connector type"), (self.pkg.compound_types, "compound type")):
            if any(d.name == name for d in decls):
                return kind
        return "extern data type" if name in self.pkg.extern_types else None

    def external(self, name: str) -> bool:
        """A qualified name from a used package: not ours to resolve."""
        return "." in name and self.lenient

    def data_type(self, name: str, span: Span) -> None:
        if name in BUILTIN_TYPES or name in self.pkg.extern_types or self.external(name):
            return
        kind = self.kind_of(name)
        if kind:
            self.error(span, f"'{name}' is a {kind}, not a data type")
        else:
            known = list(BUILTIN_TYPES) + self.pkg.extern_types
            self.error(span, f"unknown data type '{name}'",
                       hint=suggestion(name, known) or f"declare it: extern data type {name}")

    def _known_data_type(self, name: str) -> bool:
        return name in BUILTIN_TYPES or name in self.pkg.extern_types

    def _known_port_type(self, name: str | None) -> bool:
        return bool(name) and (self.pkg.port_type(name) is not None or self.external(name))

    def typed(self, obj, want: str, name: str, key: str = "type") -> object | None:
        """The declaration of type ``name`` that must be a ``want`` (e.g. "port type"), or None after an error."""
        if self.external(name):
            return None
        decl = {"port type": self.pkg.port_type, "connector type": self.pkg.connector_type,
                "component type": self.pkg.component_type}[want](name)
        if decl is not None:
            return decl
        span = self.loc.at(obj, key)
        kind = self.kind_of(name)
        if kind:
            self.error(span, f"'{name}' is a {kind}, not a {want}")
        else:
            pool = {"port type": self.pkg.port_types, "connector type": self.pkg.connector_types,
                    "component type": self.pkg.atom_types + self.pkg.compound_types}[want]
            word = "atom or compound type" if want == "component type" else want
            hint = (f"a qualified name needs: use {name.rpartition('.')[0]}" if "." in name
                    else suggestion(name, [d.name for d in pool]))
            self.error(span, f"unknown {word} '{name}'", hint=hint)
        return None

    # ------------------------------------------------------------------ package
    def run(self) -> None:
        pkg = self.pkg
        type_decls = [
            (n, ("extern_type", n, i)) for n in set(pkg.extern_types) for i in range(pkg.extern_types.count(n))
        ] + [(d.name, d) for d in pkg.port_types + pkg.atom_types + pkg.connector_types + pkg.compound_types]
        self._unique_types(type_decls)
        self.unique(pkg.constants, "constant", f"package {pkg.name}")
        self._constants()
        self._functions()
        for pt in pkg.port_types:
            self.unique(pt.params, "parameter", f"port type {pt.name}")
            for p in pt.params:
                self.data_type(p.type, self.loc.at(p, "type"))
        for atom in pkg.atom_types:
            self.atom(atom)
        for conn in pkg.connector_types:
            self.connector(conn)
        for comp in pkg.compound_types:
            self.compound(comp)
        self._recursion()

    def _unique_types(self, decls) -> None:
        seen: dict[str, Span] = {}
        for name, obj in decls:
            span = self.loc.at(self.pkg, obj) if isinstance(obj, tuple) else self.loc.at(obj)
            if name in seen:
                hint = f"first declared at {seen[name]}" if seen[name] is not NOWHERE else None
                self.error(span, f"duplicate type name '{name}' in package {self.pkg.name}", hint)
            else:
                seen[name] = span

    def _constants(self) -> None:
        visible: dict[str, str] = {}
        for c in self.pkg.constants:
            if c.type not in BUILTIN_TYPES:
                self.error(self.loc.at(c, "type"), f"constant '{c.name}' must have a native type "
                                                    f"({', '.join(BUILTIN_TYPES)}), not '{c.type}'")
            if c.value is not None:
                self.exprs.expr(c.value, Scope(f"constant {c.name}", dict(visible)), c.span)
            visible[c.name] = "constant"

    def _functions(self) -> None:
        seen = set()
        for f in self.pkg.extern_functions:
            key = (f.name, tuple(f.param_types))
            if key in seen:
                self.error(self.loc.at(f), f"extern function '{f.name}({', '.join(f.param_types)})' is declared twice")
            seen.add(key)
            if f.return_type:
                self.data_type(f.return_type, self.loc.at(f, "return_type"))
            for i, t in enumerate(f.param_types):
                self.data_type(t, self.loc.at(f, ("param_types", i)))

    def _recursion(self) -> None:
        reported: set[frozenset[str]] = set()

        def walk(comp: CompoundType, path: tuple[str, ...]) -> None:
            for inst in comp.components:
                inner = self.pkg.compound_type(inst.type)
                if inner is None:
                    continue
                if inner.name in path:
                    members = path[path.index(inner.name):]
                    if frozenset(members) in reported:
                        continue
                    reported.add(frozenset(members))
                    cycle = " -> ".join(members + (inner.name,))
                    self.error(self.loc.at(inst, "type"), f"compound type {inner.name} contains itself ({cycle})")
                    continue
                walk(inner, path + (inner.name,))
        for comp in self.pkg.compound_types:
            walk(comp, (comp.name,))

    def _params(self, params, where: str) -> dict[str, str]:
        self.unique(params, "parameter", where)
        for p in params:
            self.data_type(p.type, self.loc.at(p, "type"))
        return {p.name: "parameter" for p in params}

    def _data(self, decls, where: str, variables: dict[str, str], assignable: set[str]) -> None:
        """Data declarations in order: each initial value sees what is declared before it."""
        for d in decls:
            self.data_type(d.type, self.loc.at(d, "type"))
            if d.const and d.init is None:
                self.error(self.loc.at(d), f"const data '{d.name}' needs a value in {where}")
            if d.init is not None:
                self.exprs.expr(d.init, Scope(where, dict(variables)), self.loc.at(d))
            variables[d.name] = "const data" if d.const else "data"
            if not d.const:
                assignable.add(d.name)

    # ------------------------------------------------------------------ atoms
    def atom(self, a: AtomType) -> None:
        where = f"atom type {a.name}"
        variables = {**self.constants, **self._params(a.params, where)}
        self.unique(a.params + a.data + a.clocks, "variable", where)
        assignable: set[str] = set()
        self._data(a.data, where, variables, assignable)
        variables.update({c.name: "clock" for c in a.clocks})
        assignable.update(c.name for c in a.clocks)
        self.unique(a.ports, "port", where)
        for p in a.ports:
            self._atom_port(a, p, where, variables)
        self._merged_exports(a, where)
        if not a.places:
            self.error(a.span, f"{where} declares no place")
        for i, place in enumerate(a.places):
            if place in a.places[:i]:
                first = self.loc.at(a, ("places", a.places.index(place)))
                self.error(self.loc.at(a, ("places", i)), f"duplicate place '{place}' in {where}",
                           f"first declared at {first}" if first is not NOWHERE else None)
        scope = Scope(where, variables, assignable)
        if a.initial is None:
            self.error(a.span, f"{where} has no initial transition")
        else:
            self._places(a, a.initial, "targets", a.initial.targets)
            self.exprs.stmts(a.initial.action, scope, self.loc.at(a.initial))
        ports = {p.name for p in a.ports}
        for t in a.transitions:
            at = self.loc.at(t)
            if t.port is not None and t.port not in ports:
                self.error(
                    self.loc.at(t, "port"), f"unknown port '{t.port}' in {where}", hint=suggestion(t.port, ports)
                )
            self._places(a, t, "sources", t.sources)
            self._places(a, t, "targets", t.targets)
            if t.guard is not None:
                self.exprs.guard(t.guard, scope, at)
            self.exprs.stmts(t.action, scope, at)
        self.unique(a.priorities, "priority", where)
        for pr in a.priorities:
            for key in ("low", "high"):
                name = getattr(pr, key)
                if name != "*" and name not in ports:
                    self.error(self.loc.at(pr, key), f"unknown port '{name}' in priority {pr.name} of {where}",
                               hint=suggestion(name, ports))
            if pr.low == "*" and pr.high == "*":
                self.error(self.loc.at(pr), f"priority {pr.name} of {where} has '*' on both sides")
            if pr.guard is not None:
                self.exprs.guard(pr.guard, Scope(where, variables), self.loc.at(pr))
        check_atom_timing(self, a, where, scope)

    def _merged_exports(self, a: AtomType, where: str) -> None:
        """``export port T p(), q() as e``: needs ``export``; ``e`` names no other port of the atom."""
        for p in a.ports:
            if p.export_as is None:
                continue
            if p is not next(q for q in a.ports if q.export_as == p.export_as):
                continue  # one message per group
            at = self.loc.at(p, "export_as")
            if not p.exported:
                self.error(at, f"port '{p.name}' of {where} is merged as '{p.export_as}' but not exported",
                           hint=f"write export port {p.type} {p.name}(...) as {p.export_as}")
            other = next((q for q in a.ports if q.export_as != p.export_as and q.interface_name == p.export_as), None)
            if other is not None:
                self.error(at, f"exported port '{p.export_as}' of {where} has the name of port '{other.name}'")

    def _atom_port(self, a: AtomType, p, where: str, variables: dict[str, str]) -> None:
        decls = {d.name: d.type for d in a.params + a.data}
        for i, name in enumerate(p.data):
            if name not in decls:
                self.error(
                    self.loc.at(p, ("data", i)),
                    f"unknown variable '{name}' bound to port '{p.name}' in {where}",
                    hint=suggestion(name, decls),
                )
        ptype = self.typed(p, "port type", p.type)
        if ptype is None:
            return
        if len(ptype.params) != len(p.data):
            self.error(self.loc.at(p), f"port '{p.name}' of {where}: port type {ptype.name} carries "
                                       f"{len(ptype.params)} value(s), {len(p.data)} bound")
            return
        for i, (name, param) in enumerate(zip(p.data, ptype.params)):
            if name in decls and decls[name] != param.type and self._known_data_type(decls[name]):
                self.error(self.loc.at(p, ("data", i)), f"port '{p.name}' of {where}: '{name}' is {decls[name]} but "
                                                        f"port type {ptype.name} carries {param.type} {param.name}")

    def _places(self, a: AtomType, obj, key: str, names: list[str]) -> None:
        if not names:
            self.error(self.loc.at(obj), f"a transition of atom type {a.name} names no place in '{key}'")
        for i, name in enumerate(names):
            if name not in a.places:
                self.error(self.loc.at(obj, (key, i)), f"unknown place '{name}' in atom type {a.name}",
                           hint=suggestion(name, a.places) or f"places: {', '.join(a.places)}")

    # ------------------------------------------------------------------ connectors
    def connector(self, c: ConnectorType) -> None:
        where = f"connector type {c.name}"
        if not c.params:
            self.error(c.span, f"{where} has no port parameter")
        self.unique(c.params, "port parameter", where)
        params: dict[str, PortType | None] = {}
        for p in c.params:
            params[p.name] = self.typed(p, "port type", p.port_type, "port_type")
        self.unique(list(c.params) + list(c.data), "name", where)
        variables = dict(self.constants)
        assignable: set[str] = set()
        self._data(c.data, where, variables, assignable)
        self._connector_export(c, where)
        self._define(c, where)
        self.unique(c.interactions, "interaction", where, name=lambda s: " ".join(sorted(s.ports)))
        for spec in c.interactions:
            self._interaction(c, spec, where, params, variables, assignable)

    def _connector_export(self, c: ConnectorType, where: str) -> None:
        e = c.export
        if e is None:
            return
        data = {d.name: d.type for d in c.data}
        for i, name in enumerate(e.data):
            if name not in data:
                self.error(
                    self.loc.at(e, ("data", i)),
                    f"exported port '{e.name}' of {where} binds unknown data '{name}'",
                    hint=suggestion(name, data),
                )
        ptype = self.typed(e, "port type", e.port_type, "port_type")
        if ptype is not None and len(ptype.params) != len(e.data):
            self.error(self.loc.at(e), f"exported port '{e.name}' of {where}: port type {ptype.name} carries "
                                       f"{len(ptype.params)} value(s), {len(e.data)} bound")

    def _define(self, c: ConnectorType, where: str) -> None:
        names = {p.name for p in c.params}
        seen: set[str] = set()
        for d in define_ports(c.define):
            span = self.loc.at(d, default=c.span)
            if d.name not in names:
                self.error(span, f"'{d.name}' in define is not a port parameter of {where}",
                           hint=suggestion(d.name, names) or f"parameters: {', '.join(p.name for p in c.params)}")
            elif d.name in seen:
                self.error(span, f"port parameter '{d.name}' appears twice in the define of {where}")
            seen.add(d.name)
        for p in c.params:
            if p.name not in seen:
                self.error(self.loc.at(p), f"port parameter '{p.name}' of {where} does not appear in its define")

    def _interaction(self, c, spec, where, params, variables, assignable) -> None:
        at = self.loc.at(spec)
        text = " ".join(spec.ports)
        valid = True
        for i, name in enumerate(spec.ports):
            if name not in params:
                self.error(self.loc.at(spec, ("ports", i)), f"'{name}' is not a port parameter of {where}",
                           hint=suggestion(name, params))
                valid = False
        if len(set(spec.ports)) != len(spec.ports):
            self.error(at, f"a port appears twice in 'on {text}' of {where}")
        elif valid and spec.ports and not allows(c.define, set(spec.ports)):
            self.error(at, f"'on {text}' is not an interaction that the define of {where} allows")
        if not spec.ports:
            self.error(at, f"an interaction of {where} names no port")

        def port_data(ref: PortData) -> str | None:
            if ref.port not in params:
                return f"'{ref.port}.{ref.name}': '{ref.port}' is not a port parameter of {where}"
            if ref.port not in spec.ports:
                return f"'{ref.port}.{ref.name}': port '{ref.port}' does not take part in 'on {text}'"
            ptype = params[ref.port]
            if ptype is not None and all(p.name != ref.name for p in ptype.params):
                carried = ", ".join(p.name for p in ptype.params) or "nothing"
                return f"'{ref.port}.{ref.name}': port type {ptype.name} carries no '{ref.name}' (it carries {carried})"
            return None

        scope = Scope(f"{where}, on {text}", variables, assignable, port_data)
        if spec.guard is not None:
            self.exprs.guard(spec.guard, scope, at)
        self.exprs.stmts(spec.up, scope, at)
        self.exprs.stmts(spec.down, scope, at)

    # ------------------------------------------------------------------ compounds
    def compound(self, k: CompoundType) -> None:
        where = f"compound type {k.name}"
        variables = {**self.constants, **self._params(k.params, where)}
        if not k.components and not k.connectors:
            self.error(k.span, f"{where} has no component and no connector")
        self.unique(list(k.components) + list(k.connectors), "component or connector name", where)
        for inst in k.components:
            typ = self.typed(inst, "component type", inst.type)
            if typ is not None and len(typ.params) != len(inst.args):
                self.error(self.loc.at(inst), f"component '{inst.name}': {_KINDS[type(typ)]} {typ.name} takes "
                                              f"{len(typ.params)} parameter(s), {len(inst.args)} given")
            for arg in inst.args:
                self.exprs.expr(arg, Scope(where, variables), self.loc.at(inst))
        for conn in k.connectors:
            self._connector_instance(k, conn, where)
        self._binds_once(k, where)
        self._priorities(k, where, variables)
        self._exports(k, where)

    def _port_type(self, k: CompoundType, ref, default: Span) -> str | None:
        """The port type behind ``ref``; None after an error, or when that type is itself in error."""
        offer = port_offer(self.pkg, k, ref)
        if offer.problem:
            self.error(self.loc.at(ref, default=default), offer.problem)
        return offer.type if self._known_port_type(offer.type) else None

    def _connector_instance(self, k: CompoundType, conn, where: str) -> None:
        if conn.args:
            self.error(self.loc.at(conn), f"connector '{conn.name}' in {where}: BIP2 connectors take no data arguments")
        ctype = self.typed(conn, "connector type", conn.type)
        if ctype is not None and len(ctype.params) != len(conn.ports):
            self.error(self.loc.at(conn), f"connector '{conn.name}' in {where}: connector type {ctype.name} has "
                                          f"{len(ctype.params)} port parameter(s), {len(conn.ports)} port(s) given")
        seen = set()
        for i, ref in enumerate(conn.ports):
            key = (ref.component, ref.port)
            if key in seen:
                self.error(
                    self.loc.at(ref, default=self.loc.at(conn)), f"{ref} is given twice to connector '{conn.name}'"
                )
            seen.add(key)
            actual = self._port_type(k, ref, self.loc.at(conn))
            if ctype is None or i >= len(ctype.params) or actual is None:
                continue
            param = ctype.params[i]
            if actual != param.port_type:
                self.error(self.loc.at(ref, default=self.loc.at(conn)),
                           f"port type mismatch: parameter '{param.name}' of connector type {ctype.name} is "
                           f"{param.port_type}, but {ref} is {actual}")

    def _binds_once(self, k: CompoundType, where: str) -> None:
        """A connector that fires on its own reaches each component once, through sub-connectors too.

        Verimag's rule ``connectorDoesNotBindTheSameComponentMoreThanOnce``:
        only connectors without an exported port are checked, and a port
        reached through another connector's exported port counts for the
        components that connector binds.
        """
        components = {c.name for c in k.components}
        local = {c.name: c for c in k.connectors if c.name not in components}
        for conn in k.connectors:
            ctype = self.pkg.connector_type(conn.type)
            if ctype is None or ctype.export is not None:
                continue
            if len({(r.component, r.port) for r in conn.ports}) < len(conn.ports) or len(ctype.params) != len(
                conn.ports
            ):
                continue  # reported as a port given twice, or as a wrong port count
            seen: set[str] = set()
            twice: list[str] = []
            todo, visited = [conn], {conn.name}
            while todo:
                for ref in todo.pop().ports:
                    sub = local.get(ref.component)
                    if sub is not None:
                        if sub.name not in visited:
                            visited.add(sub.name)
                            todo.append(sub)
                    elif ref.component in seen:
                        twice.append(ref.component)
                    else:
                        seen.add(ref.component)
            if twice:
                self.error(self.loc.at(conn), f"connector '{conn.name}' in {where} binds component "
                                              f"'{twice[0]}' more than once (BIP2 lets a connector reach a component "
                                              f"through one port only)",
                           hint="join those ports in a connector inside the component and export its port")

    def _priorities(self, k: CompoundType, where: str, variables: dict[str, str]) -> None:
        self.unique(k.priorities, "priority", where)

        def port_data(ref: PortData) -> str | None:
            return data_offer(self.pkg, k, PortRef(ref.port, ref.name)).problem

        for pr in k.priorities:
            for pattern in (pr.low, pr.high):
                self._pattern(k, pr, pattern, where)
            if pr.low.connector == "*" and pr.high.connector == "*":
                self.error(self.loc.at(pr), f"priority {pr.name} of {where} has '*:*' on both sides")
            elif (pr.low.connector == pr.high.connector and pr.low.ports is not None and pr.high.ports is not None
                  and set(map(str, pr.high.ports)) < set(map(str, pr.low.ports))):
                self.error(self.loc.at(pr), f"priority {pr.name} of {where} contradicts maximal progress: "
                                            f"{pr.low} contains {pr.high}, so it already has priority over it",
                           hint="drop the rule, or swap its sides if the smaller interaction must win")
            if pr.guard is not None:
                self.exprs.guard(pr.guard, Scope(f"priority {pr.name} of {where}", variables, set(), port_data),
                                self.loc.at(pr))

    def _pattern(self, k: CompoundType, pr, pattern, where: str) -> None:
        span = self.loc.at(pattern, default=self.loc.at(pr))
        if pattern.connector == "*":
            if pattern.ports is not None:
                self.error(
                    span, f"priority {pr.name} of {where}: '*' stands for every connector and takes no port list"
                )
            return
        conn = k.connector(pattern.connector)
        if conn is None:
            self.error(span, f"unknown connector '{pattern.connector}' in priority {pr.name} of {where}",
                       hint=suggestion(pattern.connector, [c.name for c in k.connectors]))
            return
        user = next((c.name for c in k.connectors for r in c.ports if r.component == conn.name), None)
        if user is not None:
            self.error(span, f"priority {pr.name} of {where}: connector '{conn.name}' is not top-level (connector "
                             f"'{user}' uses its port); priorities apply to top-level connectors only")
        for ref in pattern.ports or []:
            if ref not in conn.ports:
                self.error(self.loc.at(ref, default=span), f"{ref} is not a port of connector '{conn.name}' "
                                                          f"(priority {pr.name} of {where})",
                           hint=f"its ports: {', '.join(map(str, conn.ports))}")

    def _exports(self, k: CompoundType, where: str) -> None:
        self.unique(k.ports, "exported port", where)
        for e in k.ports:
            if not e.targets:
                self.error(self.loc.at(e), f"exported port '{e.name}' of {where} names no port")
            types = [(ref, self._port_type(k, ref, self.loc.at(e))) for ref in e.targets]
            known = [(ref, t) for ref, t in types if t]
            if e.type:
                wrong = [(ref, t) for ref, t in known if t != e.type]
                self.typed(e, "port type", e.type)
            else:
                wrong = [(ref, t) for ref, t in known if t != known[0][1]] if known else []
            for ref, t in wrong:
                self.error(self.loc.at(ref, default=self.loc.at(e)),
                           f"exported port '{e.name}' of {where} is {e.type or known[0][1]}, but {ref} is {t}",
                           hint="ports merged into one exported port must have the same port type")
        self.unique(k.data, "exported data", where)
        for d in k.data:
            offer = data_offer(self.pkg, k, d.target)
            span = self.loc.at(d.target, default=self.loc.at(d))
            if offer.problem:
                self.error(span, offer.problem)
            elif offer.type and d.type and offer.type != d.type:
                self.error(span, f"exported data '{d.name}' of {where} is {d.type}, but {d.target} is {offer.type}")
