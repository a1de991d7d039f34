"""The GenoM2 reader for requests: services with their inputs, outputs and codel automaton."""
from __future__ import annotations

from typing import Any

from lark import Tree

from genom2bip.ir import (
    Codel,
    CodelParam,
    NamedType,
    Parameter,
    Service,
    StructType,
    Type,
)
from genom2bip.parser.genom2_base import Block, Field, FieldError, Genom2Reader
from genom2bip.parser.genom2_c import (
    path_text,
)


class RequestReader(Genom2Reader):
    """``request`` blocks desugared into services: parameters, codels as an FSM, interruptions."""

    def _request(self, block: Block) -> None:
        assert self.component is not None
        fs = block.fields
        name = str(block.name)
        if "type" not in fs:
            raise FieldError(self.span_of(block.name), f"request '{name}' has no 'type:' (control, exec or init)")
        type_tok = self._name(fs["type"])
        rtype = str(type_tok)
        if rtype not in ("control", "exec", "init"):
            raise FieldError(self.span_of(type_tok), f"request type must be control, exec or init, not '{rtype}'")
        kind = "function" if rtype == "control" else "activity"
        service = Service(name, kind, span=self.span_of(block.name))
        if rtype == "init":
            # GenoM2 (genom.c) does not limit init requests; the first one is the module's init service
            if "init_service" in self.component.properties:
                self.reporter.warning(self.span_of(type_tok), f"second init request '{name}' (the first is "
                                      f"'{self.component.properties['init_service']}')",
                                      "GenoM2 accepts it; a module usually has one")
            else:
                self.component.properties["init_service"] = name
            self.init_requests.append(service)
        codel_params: list[CodelParam] = []
        for canonical, f in fs.items():
            try:
                self._request_field(service, canonical, f, codel_params, block)
            except FieldError as err:
                self.reporter.error(err.span, err.message, err.hint)
        if "exec_task" in fs:
            try:
                tok = self._name(fs["exec_task"])
                if kind == "activity":
                    service.task = str(tok)
                    service.ref_spans["task"] = self.span_of(tok)
                else:
                    self.reporter.warning(self.span_of(fs["exec_task"].name),
                                          f"control request '{name}' runs in the control task: exec_task ignored")
            except FieldError as err:
                self.reporter.error(err.span, err.message, err.hint)
        self._request_codels(service, fs, codel_params)
        service.throws = list(dict.fromkeys(service.throws))
        self._declare_exceptions(service.throws, service.ref_spans)
        self.component.services.append(service)

    def _request_field(self, service: Service, canonical: str, f: Field, codel_params: list[CodelParam],
                       block: Block) -> None:
        assert self.component is not None
        if canonical == "doc":
            service.doc = self._string(f)
        elif canonical in ("input", "output"):
            direction = "in" if canonical == "input" else "out"
            refs = self._refs(f)
            if len(refs) != 1:
                raise FieldError(self.span_of(f.value), f"field '{f.name}' takes one 'name::sdi_field'")
            left, right = refs[0]
            if path_text(right) == "all":  # parser.y sdi_ref: ALL, the whole internal data
                typ = NamedType(str(self.component.properties.get("internal_data", "")), span=self.span_of(right))
                path = ""
            else:
                typ = self._ids_path(right)
                path = path_text(right)
            alias = path_text(left)
            param = Parameter(direction, alias, typ, source="ids", member=path, span=self.span_of(left))
            if direction == "in" and "input_info" in block.fields:
                self._input_info(param, block.fields["input_info"])
            service.parameters.append(param)
            codel_params.append(CodelParam(path, direction, "ids", alias, span=self.span_of(left)))
        elif canonical == "input_info":
            if "input" not in block.fields:
                raise FieldError(self.span_of(f.name), "input_info without an input")
        elif canonical == "posters_input":
            self._posters_input(f)
        elif canonical == "interrupt_activity":
            for tok in self._names(f):
                if str(tok) == "none":
                    continue
                service.interrupts.append(str(tok))
                service.ref_spans[f"interrupts:{tok}"] = self.span_of(tok)
        elif canonical == "fail_reports":
            for tok in self._names(f):
                service.throws.append(str(tok))
                service.ref_spans[f"throws:{tok}"] = self.span_of(tok)
        elif canonical in ("resources", "rqst_num"):
            options = self.component.properties.setdefault("request_options", {}).setdefault(service.name, {})
            options[canonical] = self._int(f) if canonical == "rqst_num" else self._text(f)

    def _input_info(self, param: Parameter, f: Field) -> None:
        """``input_info: default::"doc", ...``: defaults and docs of the input's scalar fields, in order."""
        infos: list[tuple[Any, str | None]] = []
        for item in self._items(f):
            if isinstance(item, Tree) and item.data == "pair":
                default_node, doc_node = item.children
                doc = self._string(f, doc_node)
            else:
                default_node, doc = item, None
            if isinstance(default_node, Tree) and default_node.data == "strings":
                default: Any = self._string(f, default_node)
            else:
                default = self._number(f, default_node)
            infos.append((default, doc))
        leaves = self._leaves(param.type, "")
        if not leaves or (len(leaves) == 1 and leaves[0] == ""):
            param.default, param.doc = infos[0]
            return
        defaults: dict[str, Any] = {}
        docs: dict[str, str] = {}
        for leaf, (default, doc) in zip(leaves, infos):
            node = defaults
            parts = leaf.split(".")
            for part in parts[:-1]:
                node = node.setdefault(part, {})
            node[parts[-1]] = default
            if doc:
                docs[leaf] = doc
        param.default = defaults
        param.member_docs.update(docs)

    def _leaves(self, typ: Type | None, prefix: str, depth: int = 0) -> list[str]:
        resolved = self.c.resolve(typ) if typ is not None else None
        if isinstance(resolved, StructType) and depth < 16:
            out = []
            for m in resolved.members:
                out.extend(self._leaves(m.type, f"{prefix}.{m.name}" if prefix else m.name, depth + 1))
            return out
        return [prefix]

    def _request_codels(self, service: Service, fs: dict[str, Field], params: list[CodelParam]) -> None:
        control = self._codel_field(fs.get("codel_control"))
        if control:
            name, wcet, span = control
            service.validate = Codel(name, [], [], [p for p in params if p.direction == "in"], wcet=wcet, span=span)
        start = self._codel_field(fs.get("codel_start"))
        main = self._codel_field(fs.get("codel_main"))
        end = self._codel_field(fs.get("codel_end"))
        inter = self._codel_field(fs.get("codel_inter"))
        fail = self._codel_field(fs.get("codel_fail"))
        after_step = (["pause::exec"] if main else []) + (["pause::end"] if end else []) + ["ether"]
        if start:
            name, wcet, span = start
            service.codels.append(self._make_codel(name, ["start"], after_step, span, wcet, params))
        if main:
            name, wcet, span = main
            triggers = ["exec"] if start else ["start", "exec"]
            service.codels.append(self._make_codel(name, triggers, after_step, span, wcet, params))
        if end:
            name, wcet, span = end
            service.codels.append(self._make_codel(name, ["end"], ["ether"], span, wcet, params))
        if inter:
            name, wcet, span = inter
            service.codels.append(self._make_codel(name, ["stop"], ["ether"], span, wcet, params))
        if fail:
            name, wcet, span = fail
            service.codels.append(self._make_codel(name, ["fail"], ["ether"], span, wcet, params))

    def _expand_all(self) -> None:
        """``interrupt_activity: all`` names every activity of the module; init requests interrupt all of them.

        GenoM2 (genom.c, resolveRequests) forces every init request to be
        incompatible with all requests, with a warning when the file says otherwise.
        """
        assert self.component is not None
        activities = [s.name for s in self.component.services if s.kind == "activity"]
        for init in self.init_requests:
            if init.interrupts and init.interrupts != ["all"]:
                self.reporter.warning(init.ref_spans.get(f"interrupts:{init.interrupts[0]}", init.span),
                                      f"init request '{init.name}' is made incompatible with all requests",
                                      "GenoM2 forces it whatever interrupt_activity says")
            for key in [k for k in init.ref_spans if k.startswith("interrupts:")]:
                del init.ref_spans[key]
            init.interrupts = ["all"]
            init.ref_spans["interrupts:all"] = init.span
        for service in self.component.services:
            if "all" in service.interrupts:
                span = service.ref_spans.pop("interrupts:all", service.span)
                expanded = []
                for n in service.interrupts:
                    for m in (activities if n == "all" else [n]):
                        if m not in expanded:
                            expanded.append(m)
                service.interrupts = expanded
                for m in activities:
                    service.ref_spans.setdefault(f"interrupts:{m}", span)
