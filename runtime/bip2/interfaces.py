"""What instances offer to their compound: the port and data behind ``c.p``, and their types.

The Verimag form ``export port c.p as n`` does not name the port type; the
reader fills ``ExportPort.type`` (and ``ExportData.type``) from what the
target offers, so that a model read from text equals the one the generator
built.
"""
from __future__ import annotations

from dataclasses import dataclass

from runtime.model import AtomType, CompoundType, Package, PortRef


@dataclass
class Offer:
    """The answer to "what is c.p?": a type name, or a sentence saying why there is none."""

    type: str | None
    problem: str | None = None


def port_offer(pkg: Package, compound: CompoundType, ref: PortRef) -> Offer:
    """The port type behind ``ref`` inside ``compound`` (a component's port or a connector's exported port)."""
    inst = compound.component(ref.component)
    if inst is not None:
        typ = pkg.component_type(inst.type)
        if typ is None:
            return Offer(None)  # unknown component type: reported where the component is declared
        if isinstance(typ, AtomType):
            merged = typ.exported_ports(ref.port)
            if merged:
                return Offer(merged[0].type)
            port = typ.port(ref.port)
            if port is None:
                return Offer(None, f"component '{inst.name}' (atom type {typ.name}) has no port '{ref.port}'")
            if port.exported:
                return Offer(None, f"port '{ref.port}' of component '{inst.name}' (atom type {typ.name}) is "
                                   f"exported as '{port.export_as}'")
            if port.extern:
                return Offer(None, f"port '{ref.port}' of component '{inst.name}' (atom type {typ.name}) is an "
                                   "extern port: events from outside the model fire it, no connector")
            return Offer(None, f"port '{ref.port}' of component '{inst.name}' (atom type {typ.name}) is not "
                               f"exported; declare it 'export port'")
        export = next((p for p in typ.ports if p.name == ref.port), None)
        if export is None:
            return Offer(None, f"component '{inst.name}' (compound type {typ.name}) exports no port '{ref.port}'")
        return Offer(export.type or None)
    conn = compound.connector(ref.component)
    if conn is not None:
        ctype = pkg.connector_type(conn.type)
        if ctype is None:
            return Offer(None)
        if ctype.export is None:
            return Offer(None, f"connector '{conn.name}' (connector type {ctype.name}) exports no port")
        if ctype.export.name != ref.port:
            return Offer(None, f"connector '{conn.name}' exports port '{ctype.export.name}', not '{ref.port}'")
        return Offer(ctype.export.port_type)
    return Offer(None, f"no component or connector named '{ref.component}' in compound type {compound.name}")


def data_offer(pkg: Package, compound: CompoundType, ref: PortRef) -> Offer:
    """The data type behind ``c.x`` inside ``compound`` (exported data of a component)."""
    inst = compound.component(ref.component)
    if inst is None:
        return Offer(None, f"no component named '{ref.component}' in compound type {compound.name}")
    typ = pkg.component_type(inst.type)
    if typ is None:
        return Offer(None)
    if isinstance(typ, AtomType):
        data = typ.variable(ref.port)
        if data is None:
            return Offer(None, f"component '{inst.name}' (atom type {typ.name}) has no data '{ref.port}'")
        if not data.exported:
            return Offer(None, f"data '{ref.port}' of component '{inst.name}' (atom type {typ.name}) is not "
                               f"exported; declare it 'export data'")
        return Offer(data.type)
    export = next((d for d in typ.data if d.name == ref.port), None)
    if export is None:
        return Offer(None, f"component '{inst.name}' (compound type {typ.name}) exports no data '{ref.port}'")
    return Offer(export.type or None)


def resolve_export_types(pkg: Package) -> None:
    """Fill the empty types of compound exports from their targets, inner compounds first."""
    done: set[str] = set()

    def visit(compound: CompoundType, stack: tuple[str, ...]) -> None:
        if compound.name in done or compound.name in stack:
            return
        for inst in compound.components:
            inner = pkg.compound_type(inst.type)
            if inner is not None:
                visit(inner, stack + (compound.name,))
        for export in compound.ports:
            if not export.type:
                found = (port_offer(pkg, compound, t).type for t in export.targets)
                export.type = next((t for t in found if t), "")
        for export in compound.data:
            if not export.type:
                export.type = data_offer(pkg, compound, export.target).type or ""
        done.add(compound.name)

    for compound in pkg.compound_types:
        visit(compound, ())
