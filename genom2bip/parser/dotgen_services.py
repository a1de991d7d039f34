"""The dotgen reader for services and codels: parameters and their initialisers, codels and their arguments."""
from __future__ import annotations

from typing import Any

from lark import Token, Tree

from genom2bip.ir import (
    ArrayType,
    Codel,
    CodelParam,
    NamedType,
    Parameter,
    Service,
    StructType,
    Type,
    Typedef,
    Yield,
)
from genom2bip.parser import dotgen_consts as K
from genom2bip.parser.dotgen_base import ARTICLE, DotgenReader, join_path, prop_name


class ServiceReader(DotgenReader):
    """Services, their parameters and defaults, codels (simple and FSM) and codel arguments."""

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
            pname = prop_name(prop)
            if pname == "task" and kind != "activity":
                self.error(prop, f"'task' is not a property of {ARTICLE[kind]}",
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
                    value = self.init_value(inner.children[1], join_path(path, key), docs)
            else:
                key = index
                index += 1
                if inner is not None:
                    value = self.init_value(inner, join_path(path, key), docs)
            if doc is not None:
                docs[join_path(path, key)] = doc
            entries.append((key, value))
        if not designated:
            return [v for _, v in entries]
        return {k: v for k, v in entries if v is not None}

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
