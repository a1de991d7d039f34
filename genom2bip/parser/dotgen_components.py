"""The dotgen reader for components and interfaces: properties, ids, tasks, ports, provided interfaces."""
from __future__ import annotations

import copy
from typing import Any

from lark import Token, Tree

from genom2bip.ir import (
    Component,
    Direction,
    Interface,
    Member,
    NamedType,
    Port,
    StructType,
    Task,
)
from genom2bip.parser.dotgen_base import ALLOWED, ARTICLE, SCOPES, SIZE_UNITS, DotgenReader, Symbol, prop_name, unquote
from runtime.diagnostics import Span


class ComponentReader(DotgenReader):
    """Components and interfaces, their properties, ids, tasks and ports; merging provided interfaces."""

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
        if iface is not None and iface.span == self.span(name):
            # the same declaration again: a file that two descriptions of one level include (a provider's and
            # a user's .gen), read once
            return
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
        if str(name) in others or (sym is not None and sym.kind not in SCOPES):
            first = sym.span if sym is not None else others[str(name)].span
            self.error(name, f"conflicting declarations of '{full}': already declared as "
                             f"{sym.kind if sym is not None else 'another kind'}", hint=f"first declared at {first}")
            return False
        if sym is None or sym.kind == "module":
            self.symbols[full] = Symbol(kind, self.span(name))
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
            self.symbols[full] = Symbol("type", self.span(node))
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
        name = prop_name(prop)
        if not self.allowed(prop, name, kind):
            return
        ch = prop.children
        if name in ("doc", "version", "lang", "email"):
            owner.properties[name] = self.strings(ch[0])
        elif name in ("require", "codels-require"):
            lst = ch[-1]
            values = [self.strings(s) for s in lst.children]
            owner.properties.setdefault(name, []).extend(values)
            if name == "codels-require":  # where each package was named: a missing one is reported there
                for value, s in zip(values, lst.children):
                    owner.ref_spans.setdefault(f"codels-require:{value}", self.span(s))
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
        if name in ALLOWED[kind]:
            return True
        allowed = ", ".join(sorted(ALLOWED[kind]))
        self.error(prop, f"'{name}' is not a property of {ARTICLE[kind]}", hint=f"allowed here: {allowed}")
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
        return size * SIZE_UNITS.get(unit, 1) if unit else size

    def task(self, node: Tree) -> Task:
        name, *rest = node.children
        task = Task(str(name), span=self.span(name))
        for prop in self.block_items(rest):
            pname = prop_name(prop)
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
            pname = prop_name(prop)
            if self.allowed(prop, pname, "port") and pname == "doc":
                port.doc = self.strings(prop.children[0])
        return port

    def apply_pragmas(self, comp: Component) -> None:
        """``#pragma requires`` and ``#pragma provides`` apply to every component of the file."""
        for pragma in self.src.pragmas:
            args = pragma.arguments.strip()
            if pragma.name in ("requires", "require"):
                value = unquote(args) if len(args) >= 2 and args[0] == args[-1] == '"' else args
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

    def merge_used(self, comp: Component) -> None:
        """A used interface's ports become the component's, turned round: its ``port out`` is read (GenoM3)."""
        for name in comp.uses:
            iface = self.desc.interfaces.get(name)
            if iface is None:
                continue
            mine = {p.name for p in comp.ports}
            turned = []
            for p in iface.ports:
                if p.name not in mine:
                    port = copy.deepcopy(p)
                    port.direction = Direction.IN if p.direction == Direction.OUT else Direction.OUT
                    turned.append(port)
            comp.ports[:0] = turned

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
        for key, span in iface.ref_spans.items():
            if key.startswith("codels-require:"):
                target.ref_spans.setdefault(key, span)
