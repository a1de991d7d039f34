"""``<comp>_c_types.h``: the C mapping of a component's IDL types, ports, events, exceptions and codel signatures.

The header is what a GenoM3 component's C or C++ codels compile against, written from our description IR by
the mapping rules of GenoM3's C mapping (docs/codels.md lists them and where our output may differ): ``::``
becomes ``_``; unbounded sequences are ``{_maximum, _length, _buffer, _release}``, bounded ones hold an array;
``string<N>`` is ``char[N]``; ``optional<T>`` is ``{_present, _value}``; unions are ``{_d, _u}``; enums are
``uint32_t`` with one constant per enumerator; exceptions are an ``_id`` string, a ``_detail`` struct and a
raising function; ports are structs of function pointers; a codel returns ``genom_event`` and takes
``genom_context self`` last.  Every definition sits in its own ``#ifndef _<name>_c_type`` guard, so that the
headers of several components can be included together.
"""
from __future__ import annotations

import re

from genom2bip import ir

BASE = {"boolean": "bool", "unsigned short": "uint16_t", "short": "int16_t", "unsigned long": "uint32_t",
        "unsigned long long": "uint64_t", "long": "int32_t", "long long": "int64_t", "float": "float",
        "double": "double", "char": "int8_t", "octet": "uint8_t", "wchar": "int16_t"}

#: Kinds whose ``in`` arguments go by const pointer (the others by value, strings and arrays as C does).
BY_POINTER = (ir.SequenceType, ir.OptionalType, ir.StructType, ir.UnionType)


class CMappingError(Exception):
    """A type the C mapping cannot express (``any``, ``fixed``), named with where it was written."""


def cname(scoped: str) -> str:
    """The C global name of an IDL scoped name: ``::a::b`` → ``a_b``."""
    return re.sub(r"::| ", "_", scoped.removeprefix("::")).translate({ord("+"): "x"})


def cdecl(declarator: str, name: str) -> str:
    """``declarator`` applied to ``name``: ``int32_t[4]`` and ``x`` give ``int32_t x[4]``."""
    b = declarator.find("[")
    pre, post = (declarator, "") if b < 0 else (declarator[:b], declarator[b:])
    if b >= 0 and name.startswith("*"):
        name = f"({name})"
    return f"{pre}{name}{post}" if pre.endswith("*") else f"{pre} {name}{post}"


def guard(text: str, name: str) -> str:
    return f"\n#ifndef _{name}_c_type\n# define _{name}_c_type{text}\n#endif /* _{name}_c_type */\n"


class CMapping:
    """The mapping of one description, for one component's header (types are emitted once each, on demand)."""

    def __init__(self, description: ir.Description) -> None:
        self.d = description
        self.done: set[str] = set()
        self.parts: list[str] = []

    # -- types ----------------------------------------------------------------------------------------------
    def resolve(self, t: ir.Type) -> ir.Type:
        """A named type's final type, through typedefs."""
        seen = 0
        while isinstance(t, ir.NamedType) and seen < 64:
            target = self.d.types.get(t.name)
            if isinstance(target, ir.Typedef):
                t = target.type
            elif target is not None:
                t = target
            else:
                return t
            seen += 1
        return t

    def scoped(self, t: ir.Type) -> str | None:
        """The scoped name of a named type, None for an anonymous one."""
        if isinstance(t, ir.NamedType | ir.NativeType):
            return t.name
        if isinstance(t, ir.StructType | ir.UnionType | ir.EnumType):
            return t.name
        return None

    def declarator(self, t: ir.Type) -> str:
        if isinstance(t, _PortRef):
            return cname(t.name)
        if isinstance(t, ir.BaseType):
            if t.name in BASE:
                return BASE[t.name]
            if t.name == "string":
                return "char *"
            raise CMappingError(f"{t.span}: type {t.name} has no C mapping")
        if isinstance(t, ir.NamedType):
            target = self.d.types.get(t.name)
            self.emit_named(t.name)
            if isinstance(target, ir.NativeType):
                return f"{cname(t.name)} *"
            return cname(t.name)
        if isinstance(t, ir.NativeType):
            self.emit_named(t.name)
            return f"{cname(t.name)} *"
        if isinstance(t, ir.StructType | ir.UnionType | ir.EnumType):
            self.emit_named(t.name)
            return cname(t.name)
        if isinstance(t, ir.StringType):
            return "char *" if t.bound is None else f"char[{t.bound}]"
        if isinstance(t, ir.ArrayType):
            d = self.declarator(t.element)
            dims = "".join(f"[{n}]" for n in t.dims)
            b = d.find("[")
            return d + dims if b < 0 else d[:b] + dims + d[b:]
        if isinstance(t, ir.SequenceType | ir.OptionalType):
            self.emit_template(t)
            return self.template_name(t)
        raise CMappingError(f"{t.span}: this type has no C mapping ({type(t).__name__})")

    def _part(self, t: ir.Type) -> str:
        """How an element type shows in a sequence's or optional's name: its C name, else its kind, and its bound."""
        name = self.scoped(t)
        if name is not None:
            text = "_" + cname(name)
        elif isinstance(t, ir.BaseType):
            text = "_" + cname(t.name)
        elif isinstance(t, ir.StringType):
            text = "_string"
        elif isinstance(t, ir.SequenceType):
            text = "_sequence"
        elif isinstance(t, ir.OptionalType):
            text = "_optional"
        elif isinstance(t, ir.ArrayType):
            text = "_array"
        else:
            text = "_" + type(t).__name__.lower()
        bound = getattr(t, "bound", None) if not isinstance(t, ir.ArrayType) else t.dims[0]
        return text + (str(bound) if bound is not None else "")

    def template_name(self, t: ir.SequenceType | ir.OptionalType) -> str:
        """``sequence_double``, ``sequence16_double``, ``optional_demo_state``, ``sequence_sequence_long``."""
        d = "sequence" if isinstance(t, ir.SequenceType) else "optional"
        if isinstance(t, ir.SequenceType) and t.bound is not None:
            d += str(t.bound)
        e = t.element
        d += self._part(e)
        while isinstance(e, ir.SequenceType | ir.OptionalType) and self.scoped(e) is None:
            e = e.element
            d += self._part(e)
        return d

    def emit_template(self, t: ir.SequenceType | ir.OptionalType) -> None:
        n = self.template_name(t)
        if n in self.done:
            return
        self.done.add(n)
        element = self.declarator(t.element)  # nested templates and named types first
        if isinstance(t, ir.OptionalType):
            body = f"\ntypedef struct {n} {{\n  bool _present;\n  {cdecl(element, '_value')};\n}} {n};"
        elif t.bound is None:
            body = (f"\ntypedef struct {n} {{\n  uint32_t _maximum, _length;\n  {cdecl(element, '*_buffer')};"
                    f"\n  void (*_release)(void *_buffer);\n}} {n};")
        else:
            copy = "_buffer[i] = x._buffer[i];"
            inner = self.resolve(t.element)
            if isinstance(inner, ir.StringType | ir.ArrayType):
                size = inner.bound if isinstance(inner, ir.StringType) else inner.dims[0]
                if size is not None:
                    copy = f"for (unsigned j = 0; j < {size}; j++) _buffer[i][j] = x._buffer[i][j];"
            body = (f"\ntypedef struct {n} {{\n  const uint32_t _maximum;\n  uint32_t _length;"
                    f"\n  {cdecl(element, f'_buffer[{t.bound}]')};"
                    f"\n# ifdef __cplusplus\n  {n}(): _maximum({t.bound}), _length(0) {{}}"
                    f"\n  {n}(const {n} &x): _maximum({t.bound}) {{ *this = x; }}"
                    f"\n  {n} &operator=(const {n} &x) {{\n    _length = x._length;"
                    f"\n    for (unsigned i = 0; i < _length; i++) {copy}\n    return *this;\n  }}"
                    f"\n# endif\n}} {n};")
        self.parts.append(guard(body, n))

    def emit_named(self, name: str) -> None:
        """The definition of a named type (and what it needs first), once."""
        n = cname(name)
        if n in self.done:
            return
        self.done.add(n)
        t = self.d.types.get(name)
        if isinstance(t, ir.Typedef):
            d = self.declarator(t.type)
            self.parts.append(guard(f"\ntypedef {cdecl(d, n)};", n))
        elif isinstance(t, ir.StructType):
            self.parts.append(guard(f"\ntypedef struct {n} {n};", n))
            members = "".join(f"\n  {cdecl(self.declarator(m.type), cname(m.name))};" for m in t.members)
            self.parts.append(guard(f"\nstruct {n} {{{members}\n}};", f"{n}_definition"))
        elif isinstance(t, ir.UnionType):
            self.parts.append(guard(f"\ntypedef struct {n} {n};", n))
            discr = self.declarator(t.discriminator)
            members = "".join(f"\n    {cdecl(self.declarator(c.member.type), cname(c.member.name))};"
                              for c in t.cases)
            self.parts.append(guard(f"\nstruct {n} {{\n  {discr} _d;\n  union {{{members}\n  }} _u;\n}};",
                                    f"{n}_definition"))
        elif isinstance(t, ir.EnumType):
            scope = name.rpartition("::")[0]
            values = ",".join(f"\n  {cname(f'{scope}::{e}' if scope else e)} = {k}"
                              for k, e in enumerate(t.enumerators))
            self.parts.append(guard(f"\ntypedef uint32_t {n};\nenum {{{values}\n}};", n))
        elif isinstance(t, ir.NativeType) or t is None:
            self.parts.append(guard(f"\ntypedef struct {n} {n};", n))

    def constant(self, c: ir.Constant) -> None:
        n = cname(c.name)
        if n in self.done:
            return
        self.done.add(n)
        d = self.declarator(c.type)
        v = c.value
        if isinstance(v, ir.EnumValue):
            text = cname(v.name)
        elif isinstance(v, bool):
            text = "true" if v else "false"
        elif isinstance(v, str):
            final = self.resolve(c.type)
            if isinstance(final, ir.BaseType) and final.name == "char":
                text = "'" + v.translate({ord("\\"): "\\\\", ord("'"): "\\'"}) + "'"
            else:
                text = '"' + v.translate({ord("\\"): "\\\\", ord('"'): '\\"'}) + '"'
                d = "char *const"  # a constant pointer: no unused-variable warning where it is not used
        else:
            text = repr(v)
        self.parts.append(guard(f"\nstatic const {cdecl(d, n)} = {text};", n))

    # -- component items ------------------------------------------------------------------------------------
    def exception(self, name: str) -> None:
        decl = self.d.exceptions.get(name)
        n = cname(name)
        if n + "_id" in self.done:
            return
        self.done.add(n + "_id")
        members = decl.members if decl is not None else []
        head = (f'\n#include "genom3/c/exception.h"\nconst char genom_extern_weak {n}_id[] = "::{name}";')
        if members:
            fields = "".join(f"\n  {cdecl(self.declarator(m.type), m.name)};" for m in members)
            self.parts.append(guard(head + f"\ntypedef struct {n}_detail {n}_detail;", n))
            self.parts.append(guard(
                f"\nstruct {n}_detail {{{fields}\n}};\nstatic inline genom_event\n{n}({n}_detail *d, "
                f"genom_context self) {{\n  return self->raise({n}_id, d, sizeof(*d), self);\n}}",
                f"{n}_definition"))
        else:
            self.parts.append(guard(head + f"\ntypedef void {n}_detail;", n))
            self.parts.append(guard(
                f"\nstatic inline genom_event\n{n}(genom_context self) {{\n  return self->raise({n}_id, NULL, 0, "
                "self);\n}", f"{n}_definition"))

    def event(self, component: str, name: str) -> None:
        n = cname(f"{component}::{name}")
        if n in self.done:
            return
        self.done.add(n)
        self.parts.append(guard(f'\n#include "genom3/c/exception.h"\nconst char genom_extern_weak {n}[] = '
                                f'"::{component}::{name}";', n))

    def return_type(self, t: ir.Type) -> str:
        """What a port's ``data()`` returns: a pointer to the data (to the first char of a bounded string)."""
        final = self.resolve(t)
        if isinstance(final, ir.StringType) and final.bound is not None:
            return "char *"
        if isinstance(final, ir.ArrayType):
            return cdecl(self.declarator(final.element), "*").rstrip()
        return self.argument(t, "reference", "").rstrip()

    def port(self, component: str, p: ir.Port) -> None:
        n = cname(f"{component}::{p.name}")
        if n in self.done:
            return
        self.done.add(n)
        rval = self.return_type(p.type)
        ident = "const char *id, " if p.multiple else ""
        lines = [f"  {rval} (*data)({ident}genom_context self);"]
        lines.append(f"  genom_event (*{'read' if p.direction == ir.Direction.IN else 'write'})"
                     f"({ident}genom_context self);")
        if p.multiple and p.direction == ir.Direction.OUT:
            lines += ["  genom_event (*open)(const char *id, genom_context self);",
                      "  genom_event (*close)(const char *id, genom_context self);"]
        body = "\n".join(lines)
        self.parts.append(guard(f'\n#include "genom3/c/exception.h"\ntypedef struct {n} {{\n{body}\n}} {n};', n))

    def remote(self, component: str, iface: ir.Interface, service: ir.Service) -> None:
        """``struct comp_S { genom_event (*call)(params..., genom_context self); }``: a used interface's service."""
        n = cname(f"{component}::{service.name}")
        if n in self.done:
            return
        self.done.add(n)
        args = []
        for p, t in remote_parameters(self, iface, service):
            args.append(self.argument(t, "value" if p.direction == ir.Direction.IN else "reference", p.name))
        args.append("genom_context self")
        self.parts.append(guard(f'\n#include "genom3/c/exception.h"\ntypedef struct {n} {{\n'
                                f'  genom_event (*call)({", ".join(args)});\n}} {n};', n))

    def argument(self, t: ir.Type, kind: str, var: str) -> str:
        """A codel argument: ``in`` by value (structured types by const pointer), ``out``/``inout`` by pointer."""
        final = self.resolve(t)
        d = self.declarator(t)
        if kind == "value":
            if isinstance(final, BY_POINTER) or isinstance(t, _PortRef):
                return f"const {cdecl(d, '*' + var)}"
            if isinstance(final, ir.StringType | ir.ArrayType | ir.NativeType) or (
                    isinstance(final, ir.BaseType) and final.name == "string"):
                return f"const {cdecl(d, var)}"
            return cdecl(d, var)
        if isinstance(final, ir.StringType | ir.ArrayType):
            unbounded = final.bound is None if isinstance(final, ir.StringType) else False
            return cdecl(d, "*" + var) if unbounded else cdecl(d, var)
        return cdecl(d, "*" + var)


class _PortRef(ir.Type):
    """A port handle as a codel argument's type (its C name is the port type's)."""

    def __init__(self, name: str) -> None:
        super().__init__()
        self.name = name


def _path_type(mapping: CMapping, members: list[ir.Member], path: str) -> ir.Type | None:
    """The type of ``pos.x`` / ``a[2]`` below ``members``."""
    root = re.split(r"[.\[]", path, maxsplit=1)[0]
    m = next((m for m in members if m.name == root), None)
    if m is None:
        return None
    t: ir.Type = m.type
    for field, _ in re.findall(r"\.(\w+)|\[(\d+)\]", path[len(root):]):
        final = mapping.resolve(t)
        if field:
            if isinstance(final, ir.StructType):
                t = next((x.type for x in final.members if x.name == field), None)
            elif isinstance(final, ir.UnionType):
                t = next((c.member.type for c in final.cases if c.member.name == field), None)
            else:
                return None
            if t is None:
                return None
        elif isinstance(final, ir.ArrayType):
            t = final.element if len(final.dims) == 1 else ir.ArrayType(final.element, final.dims[1:])
        elif isinstance(final, ir.SequenceType):
            t = final.element
        else:
            return None
    return t


def param_name(p: ir.CodelParam) -> str:
    """The C name of a codel argument: its alias, else the last identifier of its path."""
    if p.alias:
        return p.alias
    words = re.findall(r"[A-Za-z_]\w*", p.path)
    return words[-1] if words else "ids"


def signature(mapping: CMapping, c: ir.Component, codel: ir.Codel, service: ir.Service | None) -> str:
    """``genom_event name(args, const genom_context self)`` in the parameter order of the ``.gen``."""
    ids_type = mapping.d.types.get(f"{c.name}::ids")
    ids_members = ids_type.members if isinstance(ids_type, ir.StructType) else c.ids
    local: list[ir.Member] = []
    if service is not None:
        for p in service.parameters:
            ptype = p.type
            if ptype is None and p.source == ir.Origin.IDS:
                ptype = _path_type(mapping, ids_members, p.member or p.name)
            if ptype is not None:
                local.append(ir.Member(p.name, ptype))
        local += service.locals
    args = []
    for p in codel.params:
        name = param_name(p)
        source = p.source
        if source == ir.Origin.PORT:
            args.append(mapping.argument(_port_type(mapping, c, p.path), "value", name))
            continue
        if source == ir.Origin.REMOTE:
            args.append(f"const {cname(c.name + '::' + p.path)} *{name}")
            continue
        if source == ir.Origin.LOCAL or (source is None and _path_type(mapping, local, p.path) is not None):
            t = _path_type(mapping, local, p.path)
        else:
            t = ir.NamedType(f"{c.name}::ids") if p.path == "" else _path_type(mapping, ids_members, p.path)
        if t is None:
            raise CMappingError(f"{p.span}: codel {codel.name}: no variable {p.path!r} to give a C type")
        kind = "value" if p.direction in (None, ir.Direction.IN) else "reference"
        args.append(mapping.argument(t, kind, name))
    args.append("const genom_context self")
    return f"genom_event\n{codel.name}({', '.join(args)})"


def find_port(description: ir.Description, c: ir.Component, name: str) -> ir.Port | None:
    """The component's port ``name``: its own, else one of an interface it provides (as declared) or uses
    (the direction turned round: the interface's ``port out`` is the user's ``port in``)."""
    own = c.port(name)
    if own is not None:
        return own
    for iface, turn in [(x, False) for x in c.provides] + [(x, True) for x in c.uses]:
        found = next((p for p in getattr(description.interfaces.get(iface), "ports", []) if p.name == name), None)
        if found is not None:
            flipped = {ir.Direction.IN: ir.Direction.OUT, ir.Direction.OUT: ir.Direction.IN}
            direction = flipped.get(found.direction, found.direction) if turn else found.direction
            return ir.Port(found.name, direction, found.type, found.multiple, found.doc, span=found.span)
    return None


def remotes(description: ir.Description, c: ir.Component) -> list[tuple[ir.Interface, ir.Service]]:
    """The remote services of ``c``: every service of the interfaces it uses (GenoM3 imports them as remotes)."""
    out = []
    for name in dict.fromkeys(c.uses):
        iface = description.interfaces.get(name)
        if iface is not None:
            out += [(iface, s) for s in iface.services]
    return out


def remote_parameters(mapping: CMapping, iface: ir.Interface, service: ir.Service
                      ) -> list[tuple[ir.Parameter, ir.Type]]:
    """A remote service's parameters with their IDL types (an ``ids`` parameter: the interface's member's)."""
    out = []
    for p in service.parameters:
        t = p.type if p.type is not None else _path_type(mapping, iface.ids, p.member or p.name)
        if t is None:
            raise CMappingError(f"{p.span}: parameter {p.name} of {iface.name}.{service.name} has no C type")
        out.append((p, t))
    return out


def _port_type(mapping: CMapping, c: ir.Component, name: str) -> ir.Type:
    port = find_port(mapping.d, c, name)
    if port is None:
        raise CMappingError(f"{c.span}: no port {name} in component {c.name}")
    mapping.port(c.name, port)
    return _PortRef(f"{c.name}::{name}")


def _events(c: ir.Component) -> list[str]:
    """The component's events: GenoM3's standard ``ether``, ``start``, ``stop``, every state its codels name, and
    ``pause::s`` for the states they yield to with ``pause::``."""
    names: list[str] = ["ether", "start", "stop"]
    codels = [x for t in c.tasks for x in t.codels] + [x for s in c.services for x in s.fsm_codels()]
    for codel in codels:
        for state in codel.triggers:
            names.append(state)
        for y in codel.yields:
            names.append(f"pause::{y.state}" if y.pause else y.state)
    return list(dict.fromkeys(names))


def c_types_header(description: ir.Description, component: ir.Component, source: str = "",
                   version: str = "") -> str:
    """The text of ``<component>_c_types.h``; :class:`CMappingError` for what C cannot express."""
    m = CMapping(description)
    others = tuple(f"{c.name}::" for c in description.components if c is not component)
    for name in description.types:
        if not others or not name.startswith(others):
            m.emit_named(name)
    for c in description.constants.values():
        m.constant(c)
    for e in _events(component):
        m.event(component.name, e)
    for name in description.exceptions:
        if not name.startswith(others) or not others:
            m.exception(name)
    for iface in dict.fromkeys(component.provides + component.uses):  # an interface's ports have its own name
        for p in getattr(description.interfaces.get(iface), "ports", []):
            m.port(iface, p)
    for p in component.ports:
        m.port(component.name, p)
    for iface in dict.fromkeys(component.provides + component.uses):  # and as the component's own
        for p in getattr(description.interfaces.get(iface), "ports", []):
            m.port(component.name, find_port(description, component, p.name))
    for iface, service in remotes(description, component):
        m.remote(component.name, iface, service)
    signatures: list[str] = []
    seen: set[str] = set()
    owners: list[tuple[ir.Codel, ir.Service | None]] = [(x, None) for t in component.tasks for x in t.codels]
    for s in component.services:
        owners += ([(s.validate, s)] if s.validate is not None else []) + [(x, s) for x in s.codels]
    for codel, service in owners:
        if codel.name in seen:
            continue
        seen.add(codel.name)
        sig = signature(m, component, codel, service)
        signatures.append(f'\n#ifdef __cplusplus\nextern "C" {{\n#endif\n{sig};\n#ifdef __cplusplus\n}}\n#endif\n')
    body = "".join(m.parts) + "".join(signatures)
    includes = []
    if re.search(r"u?int(8|16|32|64)_t", body):
        includes.append("#include <stdint.h>")
    if re.search(r"\bbool\b", body):
        includes.append("#include <stdbool.h>")
    if "sequence" in body:
        includes.append('#include "genom3/c/idlsequence.h"')
    if "genom_context" in body:
        includes.append('#include "genom3/c/context.h"')
    head = (f"/* {component.name}_c_types.h: the C mapping of component {component.name}"
            f"{f' ({source})' if source else ''}.\n * Generated by genom2bip{f' {version}' if version else ''}:"
            " do not edit. */\n")
    return head + "\n".join(includes) + "\n" + body


# --------------------------------------------------------------------------- layouts for the runtime's binding

def layout(mapping: CMapping, t: ir.Type, named: dict[str, list]) -> list:
    """The C layout of ``t`` as plain data (runtime/ccodels/marshal.py builds its ctypes from it)."""
    if isinstance(t, _PortRef):
        return ["ref", t.name]
    if isinstance(t, ir.BaseType):
        if t.name == "string":
            return ["str", None]
        if t.name == "char":
            return ["b", "char"]
        if t.name not in BASE:
            raise CMappingError(f"{t.span}: type {t.name} has no C mapping")
        return ["b", BASE[t.name]]
    if isinstance(t, ir.StringType):
        return ["str", t.bound]
    if isinstance(t, ir.ArrayType):
        return ["arr", list(t.dims), layout(mapping, t.element, named)]
    if isinstance(t, ir.SequenceType):
        return ["seq", t.bound, layout(mapping, t.element, named)]
    if isinstance(t, ir.OptionalType):
        return ["opt", layout(mapping, t.element, named)]
    if isinstance(t, ir.NativeType):
        return ["native", t.name]
    name = mapping.scoped(t)
    target = mapping.d.types.get(name) if isinstance(t, ir.NamedType) else t
    if isinstance(target, ir.Typedef):
        return layout(mapping, target.type, named)
    if isinstance(target, ir.NativeType):
        return ["native", target.name]
    if isinstance(target, ir.StructType | ir.UnionType | ir.EnumType):
        if target.name not in named:
            named[target.name] = []  # a placeholder while its members are laid out
            if isinstance(target, ir.StructType):
                named[target.name] = ["struct", [[m.name, layout(mapping, m.type, named)] for m in target.members]]
            elif isinstance(target, ir.UnionType):
                enum = mapping.resolve(target.discriminator)
                cases = []
                for c in target.cases:
                    labels = [_label(x, enum) for x in c.labels if x != "default"]
                    cases.append([c.member.name, labels, "default" in c.labels, layout(mapping, c.member.type,
                                                                                       named)])
                named[target.name] = ["union", layout(mapping, target.discriminator, named), cases]
            else:
                named[target.name] = ["enum", list(target.enumerators)]
        return ["ref", target.name]
    raise CMappingError(f"{t.span}: type {getattr(t, 'name', type(t).__name__)} has no C layout")


def _label(value: object, enum: ir.Type) -> int:
    if isinstance(value, ir.EnumValue):
        return int(value)
    if isinstance(value, str) and isinstance(enum, ir.EnumType):
        short = value.rpartition("::")[2]
        return enum.enumerators.index(short) if short in enum.enumerators else 0
    if isinstance(value, bool):
        return int(value)
    return int(value) if isinstance(value, int) else 0


def _arg_type(mapping: CMapping, c: ir.Component, codel: ir.Codel, p: ir.CodelParam,
              service: ir.Service | None) -> ir.Type:
    """The IDL type of one codel argument (a port's: its data type), as :func:`signature` finds it."""
    ids_type = mapping.d.types.get(f"{c.name}::ids")
    ids_members = ids_type.members if isinstance(ids_type, ir.StructType) else c.ids
    local: list[ir.Member] = []
    if service is not None:
        for q in service.parameters:
            qtype = q.type if q.type is not None else (
                _path_type(mapping, ids_members, q.member or q.name) if q.source == ir.Origin.IDS else None)
            if qtype is not None:
                local.append(ir.Member(q.name, qtype))
        local += service.locals
    if p.source == ir.Origin.PORT:
        return find_port(mapping.d, c, p.path).type
    if p.source == ir.Origin.LOCAL or (p.source is None and _path_type(mapping, local, p.path) is not None):
        t = _path_type(mapping, local, p.path)
    else:
        t = ir.NamedType(f"{c.name}::ids") if p.path == "" else _path_type(mapping, ids_members, p.path)
    if t is None:
        raise CMappingError(f"{p.span}: codel {codel.name}: no variable {p.path!r} to give a C type")
    return t


def c_layouts(description: ir.Description, component: ir.Component) -> dict:
    """What the runtime needs to call the component's C codels: each codel's arguments, exceptions' details."""
    m = CMapping(description)
    named: dict[str, list] = {}
    codels: dict[str, list] = {}
    owners: list[tuple[ir.Codel, ir.Service | None]] = [(x, None) for t in component.tasks for x in t.codels]
    for s in component.services:
        owners += ([(s.validate, s)] if s.validate is not None else []) + [(x, s) for x in s.codels]
    for codel, service in owners:
        if codel.name in codels:
            continue
        args = []
        for p in codel.params:
            if p.source == ir.Origin.REMOTE:
                args.append(["remote", p.path])
                continue
            t = _arg_type(m, component, codel, p, service)
            if p.source == ir.Origin.PORT:
                port = find_port(description, component, p.path)
                args.append(["port", str(port.direction), port.multiple, layout(m, t, named)])
            else:
                kind = "value" if p.direction in (None, ir.Direction.IN) else "reference"
                args.append([kind, layout(m, t, named)])
        codels[codel.name] = args
    called = {}  # each remote service: its parameters' directions and layouts, for the handle's call()
    for iface, service in remotes(description, component):
        called[service.name] = [[str(p.direction), layout(m, t, named)]
                                for p, t in remote_parameters(m, iface, service)]
    # a simple codel (a function's ``codel f()``) returns genom_ok for its one way on, ether (genom3's skeleton)
    simple = sorted({x.name for s in component.services for x in s.codels if not x.triggers})
    exceptions = {}
    for name, decl in description.exceptions.items():
        exceptions[f"::{name}"] = [name, ["struct", [[x.name, layout(m, x.type, named)] for x in decl.members]]
                                   if decl.members else None]
    return {"codels": codels, "exceptions": exceptions, "types": dict(sorted(named.items())), "simple": simple,
            "remotes": called}
