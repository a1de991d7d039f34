"""A readable summary of each component of a description, for ``genom2bip check``.

What a robotics engineer wants to see at a glance: tasks with their periods,
services by kind with their task and codel FSM, ports and posters, the
constraints between services (interrupts/after/before) and what may fail.
"""
from __future__ import annotations

from genom2bip.ir import (
    ArrayType,
    BaseType,
    Codel,
    Component,
    Description,
    Duration,
    NamedType,
    OptionalType,
    SequenceType,
    Service,
    StringType,
    StructType,
    Task,
    Type,
)

KIND_ORDER = ("attribute", "function", "activity")


def type_text(typ: Type | None) -> str:
    """A type as a short IDL-like string."""
    if typ is None:
        return "?"
    if isinstance(typ, (BaseType, NamedType)):
        return typ.name
    if isinstance(typ, StringType):
        return f"string<{typ.bound}>" if typ.bound else "string"
    if isinstance(typ, SequenceType):
        bound = f", {typ.bound}" if typ.bound else ""
        return f"sequence<{type_text(typ.element)}{bound}>"
    if isinstance(typ, OptionalType):
        return f"optional<{type_text(typ.element)}>"
    if isinstance(typ, ArrayType):
        return type_text(typ.element) + "".join(f"[{d}]" for d in typ.dims)
    name = getattr(typ, "name", None)
    if isinstance(typ, StructType) and name:
        return f"struct {name}"
    return name or type(typ).__name__


def duration_text(d: Duration | None) -> str:
    """``50 ms`` plus the original text when it says something else (``5 ticks``)."""
    if d is None:
        return "none"
    s = d.seconds
    if s != 0 and abs(s) < 1e-3:
        shown = f"{s * 1e6:g} us"
    elif abs(s) < 1:
        shown = f"{s * 1e3:g} ms"
    else:
        shown = f"{s:g} s"
    if d.text and d.text.replace(" ", "") != shown.replace(" ", ""):
        return f"{shown} ({d.text})"
    return shown


def _codel_line(codel: Codel) -> str:
    yields = ", ".join(str(y) for y in codel.yields) or "-"
    wcet = f"  wcet {duration_text(codel.wcet)}" if codel.wcet else ""
    asynchronous = "async " if codel.is_async else ""
    if not codel.triggers:
        return f"codel {asynchronous}{codel.name}{wcet}"
    return f"{'/'.join(codel.triggers)}: {asynchronous}{codel.name} -> {yields}{wcet}"


def _task_lines(task: Task) -> list[str]:
    head = f"  {task.name}: " + (f"period {duration_text(task.period)}" if task.period else "aperiodic")
    extra = []
    if task.delay:
        extra.append(f"delay {duration_text(task.delay)}")
    if task.priority is not None:
        extra.append(f"priority {task.priority}")
    if task.stack is not None:
        extra.append(f"stack {task.stack}")
    lines = [head + ("  " + "  ".join(extra) if extra else "")]
    lines += [f"      {_codel_line(c)}" for c in task.codels]
    if task.throws:
        lines.append(f"      throws {', '.join(task.throws)}")
    return lines


def _service_lines(service: Service) -> list[str]:
    params = ", ".join(
        f"{p.direction} {p.name}" + (f"::{p.member}" if p.member and p.member != p.name else "")
        + (f": {type_text(p.type)}" if p.type is not None else "")
        for p in service.parameters)
    head = f"  {service.kind} {service.name}({params})"
    if service.task:
        head += f"  in task {service.task}"
    lines = [head]
    if service.validate:
        lines.append(f"      validate {service.validate.name}")
    if service.codels:
        states = service.states()
        lines.append(f"      states: {', '.join(states)}")
        lines += [f"      {_codel_line(c)}" for c in service.codels]
    for relation in ("interrupts", "after", "before"):
        names = getattr(service, relation)
        if names:
            lines.append(f"      {relation} {', '.join(names)}")
    if service.throws:
        lines.append(f"      throws {', '.join(service.throws)}")
    return lines


def component_summary(comp: Component) -> str:
    """The summary of one component, as lines of text."""
    where = f"  [{comp.span}]" if comp.span.line > 0 else ""
    lines = [f"{'component' if comp.dialect == 'genom3' else 'module'} {comp.name} ({comp.dialect}){where}"]
    if comp.clock_rate:
        lines.append(f"  clock tick {duration_text(comp.clock_rate)}")
    lines.append(f"tasks ({len(comp.tasks)}):")
    for task in comp.tasks:
        lines += _task_lines(task)
    by_kind = sorted(comp.services, key=lambda s: KIND_ORDER.index(s.kind) if s.kind in KIND_ORDER else 9)
    lines.append(f"services ({len(comp.services)}):")
    for service in by_kind:
        lines += _service_lines(service)
    lines.append(f"ports ({len(comp.ports)}):")
    posters = comp.properties.get("posters", {}) if isinstance(comp.properties.get("posters"), dict) else {}
    for port in comp.ports:
        extra = ""
        info = posters.get(port.name)
        if isinstance(info, dict) and info.get("exec_task"):
            extra = f"  written by {info['exec_task']}"
        lines.append(f"  {port.direction:<3} {port.name}: {type_text(port.type)}"
                     + ("[]" if port.multiple else "") + extra)
    if comp.throws:
        lines.append(f"throws: {', '.join(comp.throws)}")
    return "\n".join(lines)


def description_summary(description: Description) -> str:
    """Every component's summary, separated by blank lines; a description of types only says so."""
    if not description.components:
        return no_component(description) + " (nothing to generate, run or verify)"
    return "\n\n".join(component_summary(c) for c in description.components)


def no_component(description: Description) -> str:
    """``no component in a.gen: 2 types, 1 constant``: what a description without any component holds."""
    files = ", ".join(description.files) or "the description"
    counts = [(len(description.types), "type"), (len(description.constants), "constant"),
              (len(description.exceptions), "exception"), (len(description.interfaces), "interface")]
    held = ", ".join(f"{n} {word}{'s' if n != 1 else ''}" for n, word in counts if n)
    return f"no component in {files}" + (f": {held} only" if held else ": the file is empty")
