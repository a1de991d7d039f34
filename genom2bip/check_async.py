"""Async codels may not share data with codels or services that run in other tasks.

An ``async`` codel runs outside its task's lock, so genom3 (codel.c,
``codel_check`` with ``codel_codel_mutex`` and ``codel_service_mutex``)
refuses one that accesses an ids member or a port that a codel or a service
parameter of another task (the control task included) accesses too.  This
module reproduces that rule on the description IR.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator

from genom2bip.ir import Codel, CodelParam, Component, Direction, Origin, Parameter, Service, Task
from runtime.diagnostics import Reporter

CONTROL = ""  # the task of functions and attributes


@dataclass(frozen=True)
class _Access:
    """What a parameter touches: ``source`` is ids or port, ``path`` the member path as a tuple."""

    source: str
    direction: str
    path: tuple[str, ...]


@dataclass
class _Site:
    """A codel and where it runs."""

    codel: Codel
    task: str
    service: Service | None
    permanent: Task | None


def check_async(comp: Component, reporter: Reporter) -> None:
    """Report every async codel of ``comp`` that shares a parameter with another task."""
    sites = list(_sites(comp))
    for site in sites:
        if not site.codel.is_async:
            continue
        mine = [a for a in (_codel_access(comp, site, p) for p in site.codel.params) if a]
        if not mine:
            continue
        for other in sites:
            if other.codel is site.codel or not _concurrent(comp, site, other):
                continue
            theirs = [a for a in (_codel_access(comp, other, p) for p in other.codel.params) if a]
            if any(_mutex(a, b, inverse=False) for a in mine for b in theirs):
                reporter.error(site.codel.span, f"async codel '{site.codel.name}' conflicts with codel "
                               f"'{other.codel.name}' (shared parameters)",
                               f"codel '{other.codel.name}' is declared at {other.codel.span}")
        for service in comp.services:
            if (service.task or CONTROL) == site.task:
                continue
            theirs = [a for a in (_service_access(p) for p in service.parameters) if a]
            if any(_mutex(a, b, inverse=True) for a in mine for b in theirs):
                reporter.error(site.codel.span, f"async codel '{site.codel.name}' conflicts with {service.kind} "
                               f"'{service.name}' (shared parameters)",
                               f"{service.kind} '{service.name}' is declared at {service.span}")


def _sites(comp: Component) -> Iterator[_Site]:
    for task in comp.tasks:
        for codel in task.codels:
            yield _Site(codel, task.name, None, task)
    for service in comp.services:
        where = service.task or CONTROL
        for codel in ([service.validate] if service.validate else []) + service.codels:
            yield _Site(codel, where if codel.triggers else CONTROL, service, None)


def _concurrent(comp: Component, site: _Site, other: _Site) -> bool:
    """Whether ``other`` may run while the async codel of ``site`` does (genom3's codel_codel_mutex)."""
    if other.task == site.task:
        return False
    if other.permanent is not None:
        # the start and stop codels of a permanent activity run alone, before and after everything else
        if "start" in other.codel.triggers:
            return False
        return _from_start(other.permanent, other.codel)
    if other.service is not None and other.codel.triggers and site.codel.triggers and site.service is not None:
        # the automaton of a service that interrupts the async codel's service never runs beside it
        if site.service.name in other.service.interrupts or "all" in other.service.interrupts:
            return False
    return True


def _from_start(task: Task, codel: Codel) -> bool:
    graph: dict[str, set[str]] = {}
    for c in task.codels:
        for t in c.triggers:
            graph.setdefault(t, set()).update(y.state for y in c.yields)
    seen, todo = {"start"}, ["start"]
    while todo:
        for nxt in graph.get(todo.pop(), ()):
            if nxt not in seen:
                seen.add(nxt)
                todo.append(nxt)
    return any(t in seen for t in codel.triggers)


def _split(path: str) -> tuple[str, ...]:
    return tuple(p for p in path.replace("[", ".[").split(".") if p)


def _codel_access(comp: Component, site: _Site, param: CodelParam) -> _Access | None:
    source = param.source
    head = _split(param.path)[0] if param.path else ""
    if source is None:
        local = site.service is not None and (
            any(p.name == head for p in site.service.parameters) or any(m.name == head for m in site.service.locals))
        if any(m.name == head for m in comp.ids):
            source = "ids"
        elif local:
            source = "local"
        elif comp.port(head) is not None:
            source = "port"
    if source not in ("ids", "port"):
        return None
    return _Access(source, param.direction or "in", _split(param.path))


def _service_access(param: Parameter) -> _Access | None:
    if param.source != Origin.IDS:
        return None
    return _Access("ids", param.direction, _split(param.member or ""))


def _mutex(p: _Access, q: _Access, inverse: bool) -> bool:
    """genom3's param_mutex: same resource, not both reading (a service's ``out`` parameter reads the ids)."""
    if p.source != q.source:
        return False
    if p.source == Origin.PORT:
        return p.path[:1] == q.path[:1]
    if p.direction == Direction.IN and q.direction == ("out" if inverse else "in"):
        return False
    return all(a == b for a, b in zip(p.path, q.path))
