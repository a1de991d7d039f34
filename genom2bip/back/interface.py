"""The services interface of a functional level as plain data, for the runtime (generated ``interface.py``).

The runtime never reads the description IR (it must not import genom2bip),
yet to call Python codels and to expose services it needs what the model
leaves out on purpose: ids members, ports, service parameters and the
arguments of every codel.  This back end writes them as dicts and lists of
strings, numbers and JSON-schema-like type dicts; docs/runtime.md describes
the shape.
"""
from __future__ import annotations

import keyword
import os
import re
from pathlib import Path, PurePosixPath
from typing import Any

from genom2bip import ir
from genom2bip.build.names import ident, joined

#: Ranges of the IDL integer types, for the schemas' minimum and maximum.
_INT_RANGES = ir.INTEGER_RANGES


class Schemas:
    """JSON-schema-like dicts for IDL types, resolving names through the description's types."""

    def __init__(self, description: ir.Description) -> None:
        self.types = description.types
        self.exceptions = description.exceptions
        self.named: dict[str, dict[str, Any]] = {}  # type name -> schema, referenced as {"$ref": name}

    def ref(self, name: str, t: ir.Type, seen: tuple[str, ...]) -> dict[str, Any]:
        """``{"$ref": name}``, the named type's schema going once into :attr:`named`."""
        if name not in self.named and name not in seen:
            self.named[name] = {}
            self.named[name] = self.of(t, seen + (name,))
        return {"$ref": name}

    def of(self, t: ir.Type | None, seen: tuple[str, ...] = ()) -> dict[str, Any]:
        if t is None:
            return {}
        if isinstance(t, ir.BaseType):
            return _base(t.name)
        if isinstance(t, ir.StringType):
            return {"type": "string"} | ({"maxLength": t.bound} if t.bound else {})
        if isinstance(t, ir.SequenceType):
            out = {"type": "array", "items": self.of(t.element, seen)}
            return out | ({"maxItems": t.bound} if t.bound else {})
        if isinstance(t, ir.ArrayType):
            if isinstance(t.element, ir.BaseType) and t.element.name == "char" and len(t.dims) == 1:
                return {"type": "string", "maxLength": max(t.dims[0] - 1, 0)}  # a C string
            out = self.of(t.element, seen)
            for n in reversed(t.dims):
                out = {"type": "array", "items": out, "minItems": n, "maxItems": n}
            return out
        if isinstance(t, ir.OptionalType):
            return {"anyOf": [self.of(t.element, seen), {"type": "null"}]}
        if isinstance(t, (ir.StructType, ir.UnionType, ir.EnumType)) and t.name not in seen:
            return self.ref(t.name, t, seen)
        if isinstance(t, ir.StructType):
            props = {m.name: self.of(m.type, seen) | ({"description": m.doc} if m.doc else {}) for m in t.members}
            return {"type": "object", "title": t.name, "properties": props, "required": list(props),
                    "additionalProperties": False}
        if isinstance(t, ir.UnionType):
            cases = {c.member.name: self.of(c.member.type, seen) for c in t.cases}
            return {"type": "object", "title": t.name, "properties": cases, "minProperties": 1, "maxProperties": 1,
                    "additionalProperties": False}
        if isinstance(t, ir.EnumType):
            return {"type": "string", "title": t.name, "enum": list(t.enumerators)}
        if isinstance(t, ir.FixedType):
            return {"type": "number"}
        if isinstance(t, ir.NativeType):
            return {"title": t.name, "description": "native type: opaque to GenoM, any value"}
        if isinstance(t, ir.NamedType):
            target = self.types.get(t.name)
            if isinstance(target, ir.Typedef):
                return self.ref(t.name, target.type, seen)
            if isinstance(target, (ir.StructType, ir.UnionType, ir.EnumType)):
                return self.ref(target.name, target, seen)
            return {"title": t.name, "description": "unknown type: any value"}
        return {}


def _base(name: str) -> dict[str, Any]:
    if name in _INT_RANGES:
        lo, hi = _INT_RANGES[name]
        return {"type": "integer", "minimum": lo, "maximum": hi}
    if name in ("float", "double", "long double"):
        return {"type": "number"}
    if name in ("boolean", "bool"):
        return {"type": "boolean"}
    if name in ("char", "wchar"):
        return {"type": "string", "maxLength": 1}
    if name in ("string", "wstring"):
        return {"type": "string"}
    if "int" in name or "long" in name or "short" in name:
        return {"type": "integer"}
    return {}  # any, pointers and other C types: any value


def zero(schema: dict[str, Any], named: dict[str, dict[str, Any]]) -> Any:
    """The value a variable of this type holds before anything is written (C's zero initialisation)."""
    while "$ref" in schema:
        schema = named.get(schema["$ref"], {})
    kind = schema.get("type")
    if "enum" in schema:
        return schema["enum"][0] if schema["enum"] else None
    if kind == "object" and "required" in schema and "maxProperties" not in schema:
        return {k: zero(v, named) for k, v in schema["properties"].items()}
    if kind == "array":
        return [zero(schema["items"], named) for _ in range(schema.get("minItems", 0))]
    return {"integer": 0, "number": 0.0, "boolean": False, "string": ""}.get(kind)


def json_value(value: Any) -> Any:
    """A description's constant (enumerators, nested initialisers) as JSON data."""
    if isinstance(value, ir.EnumValue):
        return value.name.split("::")[-1]
    if isinstance(value, dict):
        return {str(k): json_value(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_value(v) for v in value]
    return value


def _lookup(members: list[ir.Member], path: str) -> ir.Member | None:
    root = re.split(r"[.\[]", path, maxsplit=1)[0]
    return next((m for m in members if m.name == root), None)


def _member_type(schemas: Schemas, members: list[ir.Member], path: str) -> dict[str, Any]:
    """Schema of ``pos.x`` / ``a[2]`` below the ids members."""
    m = _lookup(members, path)
    if m is None:
        return {}
    schema = schemas.of(m.type)
    for part in re.findall(r"\.(\w+)|\[(\d+)\]", path[len(m.name):]):
        while "$ref" in schema:  # a named struct: its members are in the named schema
            schema = schemas.named.get(schema["$ref"], {})
        if part[0]:
            schema = schema.get("properties", {}).get(part[0], {})
        else:
            schema = schema.get("items", {})
    return schema


def _python_name(path: str) -> str:
    word = re.findall(r"[A-Za-z_]\w*", path)
    name = word[-1] if word else "arg"
    return name + "_" if keyword.iskeyword(name) else name


def codel_params(codel: ir.Codel, local_names: set[str], ids_inputs: set[str], validate: bool) -> list[dict]:
    """The arguments of one codel: where each comes from, its direction and its Python argument name.

    A parameter without a source names a service parameter or local when one
    has that name, else an ids member (GenoM's resolution order).  A validate
    codel reading an ids member that an ``in`` parameter sets sees the
    requested value (the ids is written only once the request is accepted).
    Names clash (``local in goal`` and ``ids out goal``): each clashing
    argument is then prefixed by its source (``local_goal``, ``ids_goal``).
    """
    out = []
    for p in codel.params:
        root = re.split(r"[.\[]", p.path, maxsplit=1)[0]
        source = str(p.source or ("local" if root in local_names else "ids"))
        if validate and source == "ids" and root in ids_inputs:
            source = "local"
        out.append({"arg": p.alias or _python_name(p.path), "source": source, "direction": str(p.direction or "in"),
                    "path": p.path})
    names = [a["arg"] for a in out]
    for a in out:
        if names.count(a["arg"]) > 1 and not any(q.alias == a["arg"] for q in codel.params):
            a["arg"] = f"{a['source']}_{a['arg']}"
    seen: dict[str, int] = {}
    for a in out:
        n = seen[a["arg"]] = seen.get(a["arg"], 0) + 1
        if n > 1:
            a["arg"] = f"{a['arg']}_{n}"
    return out


def _codels(m: str, codels: list[ir.Codel], locals_: set[str], ids_inputs: set[str],
            validate: ir.Codel | None = None) -> dict[str, dict]:
    out: dict[str, dict] = {}
    if validate is not None:
        out[joined(m, validate.name)] = {"codel": validate.name, "role": "validate",
                                         "params": codel_params(validate, locals_, ids_inputs, True)}
        if validate.wcet is not None:
            out[joined(m, validate.name)]["wcet_us"] = round(validate.wcet.seconds * 1e6)
    for c in codels:
        entry = out.setdefault(joined(m, c.name), {"codel": c.name, "role": "fsm",
                                                   "params": codel_params(c, locals_, ids_inputs, False)})
        if c.wcet is not None:  # the run-time watchdog's bound for this codel (runtime/controller/stuck.py)
            entry["wcet_us"] = round(c.wcet.seconds * 1e6)
    return out


def remote_entries(schemas: Schemas, description: ir.Description, c: ir.Component) -> dict[str, Any]:
    """The remote services ``c`` may call (every service of the interfaces it uses): interface and parameters."""
    out: dict[str, Any] = {}
    for name in dict.fromkeys(c.uses):
        iface = description.interfaces.get(name)
        for s in getattr(iface, "services", []):
            params = []
            for p in s.parameters:
                schema = schemas.of(p.type) if p.type is not None else _member_type(schemas, iface.ids,
                                                                                      p.member or p.name)
                params.append({"name": p.name, "direction": str(p.direction), "schema": schema})
            out.setdefault(s.name, {"interface": name, "parameters": params})
    return out


def component_interface(schemas: Schemas, c: ir.Component) -> dict[str, Any]:
    m = ident(c.name)
    ids = {}
    for member in c.ids:
        schema = schemas.of(member.type)
        initial = json_value(member.initializer) if member.initializer is not None else zero(schema, schemas.named)
        ids[member.name] = {"schema": schema, "initial": initial} | ({"doc": member.doc} if member.doc else {})
    ports = {p.name: {"direction": str(p.direction), "schema": schemas.of(p.type), "multiple": p.multiple}
             | ({"doc": p.doc} if p.doc else {}) for p in c.ports}
    tasks = {}
    taken = {ident(s.name) for s in c.services}
    for t in c.tasks:
        name = ident(t.name)  # the builder's instance name (genom2bip/build/functional.py)
        if name in taken:
            name += "_task"
        taken.add(name)
        tasks[t.name] = {"instance": f"{m}.{name}",
                         "period_us": round(t.period.seconds * 1e6) if t.period is not None else None,
                         "codels": _codels(m, t.codels, set(), set())}
    services = {}
    for s in c.services:
        params = []
        for p in s.parameters:
            if p.source == ir.Origin.IDS:
                schema = _member_type(schemas, c.ids, p.member or p.name) if p.type is None else schemas.of(p.type)
            else:
                schema = schemas.of(p.type)
            entry = {"name": p.name, "direction": str(p.direction), "schema": schema, "source": str(p.source)}
            if p.source == ir.Origin.IDS:
                entry["member"] = p.member if p.member is not None else p.name
            if p.default is not None:
                entry["default"] = json_value(p.default)
            if p.doc:
                entry["doc"] = p.doc
            params.append(entry)
        locals_ = {m_.name: {"schema": schemas.of(m_.type),
                             "initial": json_value(m_.initializer) if m_.initializer is not None
                             else zero(schemas.of(m_.type), schemas.named)} for m_ in s.locals}
        local_names = {p.name for p in s.parameters} | set(locals_)
        ids_inputs = {(p.member or p.name).split(".")[0] for p in s.parameters
                      if p.source == ir.Origin.IDS and p.direction in (ir.Direction.IN, ir.Direction.INOUT)}
        services[s.name] = {
            "instance": f"{m}.{ident(s.name)}",
            "kind": str(s.kind),
            "task": s.task if s.kind == ir.ServiceKind.ACTIVITY else None,
            "doc": s.doc,
            "parameters": params,
            "locals": locals_,
            "throws": list(dict.fromkeys(s.throws + c.throws)),
            "interrupts": list(s.interrupts),
            "after": list(s.after),
            "before": list(s.before),
            "codels": _codels(m, s.fsm_codels(), local_names, ids_inputs, s.validate),
        }
    exceptions = {}
    for name in dict.fromkeys(c.throws + [e for s in c.services for e in s.throws]):
        decl = schemas.exceptions.get(name) or schemas.exceptions.get(f"{c.name}::{name}")
        members = decl.members if decl is not None else []
        exceptions[name] = {"type": "object", "properties": {x.name: schemas.of(x.type) for x in members}}
    return {
        "instance": m, "doc": c.properties.get("doc"),
        "clock_rate_us": round(c.clock_rate.seconds * 1e6) if c.clock_rate is not None else None,
        "ids": ids, "ports": ports, "tasks": tasks, "services": services, "exceptions": exceptions,
    }


def interface_data(description: ir.Description, system: str, sources: str,
                   package_dir: Path | None = None) -> dict[str, Any]:
    """Everything the runtime needs about ``description``'s components, as plain data.

    ``codels`` is the descriptions' ``codels`` folder: relative to ``package_dir`` (where the package is
    written) when it is given, so that the package finds it from any working directory.
    """
    schemas = Schemas(description)
    first = PurePosixPath(sources.split()[0]) if sources.split() else PurePosixPath(".")
    folder = first.parent if first.suffix else first
    codels = str(folder / "codels")
    if package_dir is not None:
        codels = PurePosixPath(os.path.relpath(os.path.abspath(codels), os.path.abspath(package_dir))).as_posix()
    components = {c.name: component_interface(schemas, c) for c in description.components}
    for c in description.components:  # only where there are some: a level without interfaces is unchanged
        if c.provides:
            components[c.name]["provides"] = list(c.provides)
        called = remote_entries(schemas, description, c)
        if called:
            components[c.name]["remotes"] = called
    types = dict(sorted(schemas.named.items()))
    return {"system": system, "codels": codels, "types": types, "components": components}


def literal(value: Any, indent: int = 0, column: int = 0, width: int = 110) -> str:
    """``value`` (plain data) as a Python literal: one line when it fits, else one item per line."""
    flat = repr(value)
    if column + len(flat) <= width or not isinstance(value, (dict, list)) or not value:
        return flat
    pad = " " * (indent + 4)
    if isinstance(value, dict):
        items = []
        for k, v in value.items():
            head = f"{pad}{k!r}: "
            items.append(f"{head}{literal(v, indent + 4, len(head), width)},")
        return "{\n" + "\n".join(items) + "\n" + " " * indent + "}"
    items = [f"{pad}{literal(v, indent + 4, indent + 4, width)}," for v in value]
    return "[\n" + "\n".join(items) + "\n" + " " * indent + "]"
