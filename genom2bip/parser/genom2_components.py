"""The GenoM2 reader for the module, its execution tasks and its posters."""
from __future__ import annotations

from typing import Any

from lark import Token, Tree

from genom2bip.ir import (
    Component,
    Duration,
    Member,
    NamedType,
    Port,
    StructType,
    Task,
    Type,
)
from genom2bip.parser.genom2_base import DEFAULT_CLOCK_RATE, Block, Field, FieldError, Genom2Reader
from genom2bip.parser.genom2_c import (
    path_text,
)


class ComponentReader(Genom2Reader):
    """``module`` fields, ``exec_task`` blocks (tasks with their period) and ``poster`` blocks (out ports)."""

    def _module(self, block: Block) -> Component:
        comp = Component(str(block.name), "genom2", file=str(self.source.file or ""), span=self.span_of(block.name))
        self.component = comp
        props = comp.properties
        for canonical, f in block.fields.items():
            try:
                self._module_field(comp, props, canonical, f)
            except FieldError as err:
                self.reporter.error(err.span, err.message, err.hint)
        rate = props.get("clkrate", DEFAULT_CLOCK_RATE)
        self.tick = 1.0 / rate
        comp.clock_rate = Duration(self.tick, f"{rate} Hz")
        return comp

    def _module_field(self, comp: Component, props: dict, canonical: str, f: Field) -> None:
        if canonical in ("number", "max_rqst_size", "max_reply_size"):
            props[canonical] = self._int(f)
        elif canonical == "uses_cxx":  # parser.y: deprecated, means lang "c++" whatever its value
            self._int(f)
            props["lang"] = "c++"
            self.reporter.warning(self.span_of(f.name), "usage of uses_cxx is deprecated", 'use lang: "c++";')
        elif canonical == "clkrate":
            value = self._number(f)
            if value <= 0:
                raise FieldError(self.span_of(f.value), "clkrate (ticks per second) must be positive")
            props["clkrate"] = value
        elif canonical in ("version", "email", "lang", "doc"):
            props[canonical] = self._string(f)
        elif canonical == "iface_version":
            node = self._one(f, "version")
            if isinstance(node, Tree) and node.data == "colon_list":
                props[canonical] = ":".join(str(self._number(f, c)) for c in node.children)
            else:
                props[canonical] = (
                    self._string(f, node)
                    if isinstance(node, Tree) and node.data == "strings"
                    else str(self._number(f, node))
                )
        elif canonical in ("codel_files", "requires", "codels_requires"):
            key = {"requires": "require", "codels_requires": "codels-require"}.get(canonical, canonical)
            props[key] = self._packages(f) if key != "codel_files" else self._text(f)
        elif canonical == "internal_data":
            typ = self._type(f, self._one(f, "type"))
            name = typ.name if isinstance(typ, NamedType) else None
            resolved = self.c.resolve(typ)
            if not isinstance(resolved, StructType):
                what = f"'{name}'" if name else "this type"
                raise FieldError(self.span_of(f.value), f"internal_data {what} is not a known struct type",
                                  "declare it with 'typedef struct { ... } NAME;' or #include its header")
            props["internal_data"] = name or resolved.name
            comp.ids = [Member(m.name, m.type, m.initializer, m.doc, span=m.span) for m in resolved.members]

    def _exec_task(self, block: Block) -> None:
        assert self.component is not None
        task = Task(str(block.name), span=self.span_of(block.name))
        fs = block.fields
        for canonical, f in fs.items():
            try:
                if canonical == "period":
                    task.period = self._ticks(f)
                    task.ref_spans["period"] = self.span_of(f.value)
                elif canonical == "delay":
                    task.delay = self._ticks(f)
                elif canonical == "priority":
                    task.priority = self._int(f)
                elif canonical == "stack_size":
                    task.stack = self._int(f)
                elif canonical == "doc":
                    task.doc = self._string(f)
                elif canonical == "fail_reports":
                    for tok in self._names(f):
                        task.throws.append(str(tok))
                        task.ref_spans[f"throws:{tok}"] = self.span_of(tok)
                elif canonical in ("posters_input",):
                    self._posters_input(f)
                elif canonical == "poster_client_from":
                    self._poster_client_from(f)
                elif canonical in ("cs_client_from", "resources"):
                    self.component.properties.setdefault(canonical, []).extend(self._text(f))
            except FieldError as err:
                self.reporter.error(err.span, err.message, err.hint)
        start = self._codel_field(fs.get("codel_task_start"))
        main = self._codel_field(fs.get("codel_task_main"))
        main2 = self._codel_field(fs.get("codel_task_main2"))
        end = self._codel_field(fs.get("codel_task_end"))
        wait = self._codel_field(fs.get("codel_task_wait"))
        if wait:  # genom >= 2.8: an aperiodic task calls it to wait for its next wake-up instead of events
            self.component.properties.setdefault("codel_task_wait", {})[task.name] = wait[0]
        if start:
            name, wcet, span = start
            yields = ["pause::main"] if main else ["ether"]
            task.codels.append(self._make_codel(name, ["start"], yields, span, wcet))
        if main:
            name, wcet, span = main
            task.codels.append(
                self._make_codel(name, ["main"] if start else ["start", "main"], ["pause::main"], span, wcet)
            )
        if main2:
            name, wcet, span = main2
            task.codels.append(self._make_codel(name, ["main2"], ["pause::main2"], span, wcet))
            self.reporter.warning(
                span, f"codel_task_main2 '{name}' has no GenoM3 equivalent: kept as state 'main2', never entered"
            )
        if end:
            name, wcet, span = end
            task.codels.append(self._make_codel(name, ["stop"], ["ether"], span, wcet))
        task.throws = list(dict.fromkeys(task.throws))
        self._declare_exceptions(task.throws, task.ref_spans)
        self.component.tasks.append(task)

    def _posters_input(self, f: Field) -> None:
        assert self.component is not None
        names = self.component.properties.setdefault("posters_input", [])
        for item in self._items(f):
            typ = self._type(f, item)
            text = typ.name if isinstance(typ, NamedType) else getattr(typ, "name", str(typ))
            if text not in names:
                names.append(text)

    def _poster_client_from(self, f: Field) -> None:
        assert self.component is not None
        for left, right in self._refs(f):
            module, poster = path_text(left), path_text(right)
            name = f"{module}_{poster}"
            if self.component.port(name) is None:
                self.component.ports.append(Port(name, "in", NamedType(f"{module}::{poster}", span=self.span_of(left)),
                                                 doc=f"poster {poster} of module {module}", span=self.span_of(left)))

    def _poster(self, block: Block) -> None:
        assert self.component is not None
        fs = block.fields
        name = str(block.name)
        update = "auto"
        if "update" in fs:
            tok = self._name(fs["update"])
            if str(tok) not in ("auto", "user"):
                raise FieldError(self.span_of(tok), f"poster update must be 'auto' or 'user', not '{tok}'")
            update = str(tok)
        doc = self._string(fs["doc"]) if "doc" in fs else None
        typ: Type | None = None
        if "data" in fs and "type" in fs:
            raise FieldError(self.span_of(fs["type"].name), f"poster '{name}' has both 'data' and 'type'; "
                              "give 'data' (contents copied from the internal data) or 'type' (written by codels)")
        if "data" in fs:
            members: list[Member] = []
            for left, right in self._refs(fs["data"]):
                mtype = self._ids_path(right)
                mname = path_text(left)
                if any(m.name == mname for m in members):
                    raise FieldError(self.span_of(left), f"duplicate data name '{mname}' in poster '{name}'")
                members.append(Member(mname, mtype if mtype is not None else NamedType("?"),
                                      doc=f"internal data {path_text(right)}", span=self.span_of(left)))
            typ = StructType(f"{self.component.name}_{name}_poster", members, span=self.span_of(block.name))
            self._register_poster_type(typ)
            typ = NamedType(typ.name, span=self.span_of(block.name))
        elif "type" in fs:
            named = self._poster_types(fs["type"])
            types = [t for _, t in named]
            if len(types) == 1 and named[0][0] is None:
                typ = types[0]
            else:
                members = [Member(n or f"data{i}", t, span=t.span) for i, (n, t) in enumerate(named)]
                struct = StructType(f"{self.component.name}_{name}_poster", members, span=self.span_of(block.name))
                self._register_poster_type(struct)
                typ = NamedType(struct.name, span=struct.span)
        else:
            raise FieldError(self.span_of(block.name), f"poster '{name}' needs 'data: name::sdi_field, ...;' "
                              "(update: auto) or 'type: TYPE;' (update: user)")
        port = Port(name, "out", typ, doc=doc, span=self.span_of(block.name))
        self.component.ports.append(port)
        props = self.component.properties.setdefault("posters", {})
        info: dict[str, Any] = {"update": update}
        if "exec_task" in fs:
            tok = self._name(fs["exec_task"])
            info["exec_task"] = str(tok)
            if self.component.task(str(tok)) is None:
                self.reporter.error(self.span_of(tok), f"poster '{name}': unknown exec_task '{tok}'",
                                    self._known("tasks", [t.name for t in self.component.tasks], str(tok)))
        if "codel_poster_create" in fs:
            info["create"] = str(self._name(fs["codel_poster_create"]))
        if "address" in fs:
            info["address"] = " ".join(str(t) for t in fs["address"].value.scan_values(lambda v: isinstance(v, Token)))
        props[name] = info

    def _poster_types(self, f: Field) -> list[tuple[str | None, Type]]:
        """``type: name::TYPE, ...`` (parser.y named_type); an unnamed ``TYPE`` is deprecated, as GenoM2 warns."""
        out: list[tuple[str | None, Type]] = []
        for item in self._items(f):
            if isinstance(item, Tree) and item.data == "pair":
                left, right = item.children
                out.append((str(self._name(f, left)), self._type(f, right)))
                continue
            typ = self._type(f, item)
            self.reporter.warning(self.span_of(item), "unnamed poster member is deprecated",
                                  f"write type: NAME::{getattr(typ, 'name', 'TYPE')};")
            out.append((None, typ))
        return out

    def _register_poster_type(self, struct: StructType) -> None:
        """The first poster of a name gets the type; a second one is a duplicate port, which the checks report."""
        if struct.name not in self.description.types:
            self.description.types[struct.name] = struct
