"""Semantic checks of a description, whatever dialect it was written in.

The parsers check syntax and what only they can see (field names, GenoM2
internal-data paths, duplicate type definitions); everything that can be judged
on the IR is checked here: names that refer to nothing, names declared twice,
codel FSMs that cannot finish, tasks that cannot run.  Each problem is
reported at the name that is wrong (``ref_spans``, yield and codel spans),
falling back to the enclosing declaration.
"""
from __future__ import annotations

import difflib
from collections import deque
from typing import Any, Iterable, Iterator

from genom2bip.check_async import check_async
from genom2bip.check_sizes import check_sizes
from genom2bip.ir import (
    ArrayType,
    Codel,
    Component,
    Description,
    Dialect,
    Direction,
    ExceptionDecl,
    Member,
    NamedType,
    OptionalType,
    Origin,
    SequenceType,
    Service,
    ServiceKind,
    StructType,
    Task,
    Type,
    Typedef,
    UnionType,
    fsm_states,
)
from runtime.diagnostics import NOWHERE, Reporter, Span

ETHER = "ether"
ALL = "all"  # in ``interrupts``: every service of the component (a name no service may take)


def check_description(description: Description, reporter: Reporter) -> None:
    """Report every semantic problem of ``description`` into ``reporter`` (nothing is raised)."""
    _Checker(description, reporter).run()


def _where(span: Span | None, fallback: Span) -> Span:
    return span if span is not None and span is not NOWHERE and span.line > 0 else fallback


def _suggest(wrong: str, names: Iterable[str], what: str) -> str | None:
    names = list(dict.fromkeys(names))
    close = difflib.get_close_matches(wrong, names, n=1)
    if close:
        return f"did you mean '{close[0]}'?"
    if not names:
        return f"no {what} are declared"
    if len(names) <= 12:
        return f"known {what}: {', '.join(names)}"
    return None


class _Checker:
    def __init__(self, description: Description, reporter: Reporter) -> None:
        self.d = description
        self.reporter = reporter
        self._type_keys = set(description.types) | set(description.exceptions)  # genom3: exceptions are types
        self._type_tails = {k.rsplit("::", 1)[-1] for k in self._type_keys}
        self._exceptions = self._exception_names(description.exceptions)
        self._reported_types: set[tuple[str, Span]] = set()

    def error(self, span: Span, message: str, hint: str | None = None) -> None:
        self.reporter.error(span, message, hint)

    # ------------------------------------------------------------------ driver

    def run(self) -> None:
        self._duplicates("component", self.d.components, "the description", NOWHERE)
        for comp in self.d.components:
            self._component(comp)
        self._types()

    def _component(self, comp: Component) -> None:
        where = f"component '{comp.name}'"
        self._duplicates("service", comp.services, where, comp.span)
        self._duplicates("task", comp.tasks, where, comp.span)
        self._duplicates("port", comp.ports, where, comp.span)
        self._duplicates("ids member", comp.ids, where, comp.span)
        for name in comp.throws:
            self._exception(name, comp.span, comp)
        for task in comp.tasks:
            self._task(comp, task)
        for service in comp.services:
            if service.name == ALL:
                self.error(service.span, f"'{ALL}' is a reserved service name", "'interrupts all' names every service")
            self._service(comp, service)
        for member in comp.ids:
            self._type_refs(member.type, member.span, comp)
        if comp.dialect == Dialect.GENOM3:
            check_async(comp, self.reporter)
        check_sizes(comp, self.d, self.reporter)
        for port in comp.ports:
            self._type_refs(port.type, port.span, comp, in_port=port.direction == Direction.IN)

    # ------------------------------------------------------------------ duplicates

    def _duplicates(self, what: str, items: list[Any], where: str, fallback: Span) -> None:
        first: dict[str, Any] = {}
        for item in items:
            name = item.name
            if name in first:
                before = _where(first[name].span, fallback)
                self.error(_where(item.span, fallback), f"duplicate {what} '{name}' in {where}",
                           f"first declared at {before}" if before is not NOWHERE else None)
            else:
                first[name] = item

    # ------------------------------------------------------------------ tasks

    def _task(self, comp: Component, task: Task) -> None:
        if task.period is not None and task.period.seconds <= 0:
            self.error(_where(task.ref_spans.get("period"), task.span),
                       f"task '{task.name}' has a non-positive period ({task.period})",
                       "a periodic task needs a period > 0; omit the period for an aperiodic task")
        for name in task.throws:
            self._exception(name, _where(task.ref_spans.get(f"throws:{name}"), task.span), comp)
        if task.codels:
            # genom3 needs no start state in a permanent activity: codels that neither
            # start nor stop reaches are reported by the connectivity rule instead
            states = fsm_states(task.codels)
            what = f"task '{task.name}'"
            if self._yields(task.codels, states, what, task.span):
                self._connected(task.codels, what, task.span, comp.dialect == Dialect.GENOM3)
        for codel in task.codels:
            self._codel_params(comp, codel, None)

    # ------------------------------------------------------------------ services

    def _service(self, comp: Component, service: Service) -> None:
        names = [s.name for s in comp.services]
        what = f"{service.kind} '{service.name}'"
        if service.kind == ServiceKind.ACTIVITY:
            if service.task is None:
                self.error(service.span, f"activity '{service.name}' has no task",
                           "an activity runs in an execution task: name one ('task T;' / 'exec_task: T;')")
        if service.task is not None and comp.task(service.task) is None:
            self.error(_where(service.ref_spans.get("task"), service.span),
                       f"unknown task '{service.task}' for {what}",
                       _suggest(service.task, [t.name for t in comp.tasks], "tasks"))
        for relation in ("interrupts", "after", "before"):
            for other in getattr(service, relation):
                if other not in names and not (relation == "interrupts" and other == ALL):
                    self.error(_where(service.ref_spans.get(f"{relation}:{other}"), service.span),
                               f"unknown service '{other}' in '{relation}' of {what}",
                               _suggest(other, names, "services"))
        for name in service.throws:
            self._exception(name, _where(service.ref_spans.get(f"throws:{name}"), service.span), comp)
        for param in service.parameters:
            if param.type is not None:
                self._type_refs(param.type, param.span, comp)
        for local in service.locals:
            self._type_refs(local.type, local.span, comp)
        for codel in ([service.validate] if service.validate else []) + service.codels:
            self._codel_params(comp, codel, service)
        self._fsm(comp, service)

    def _fsm(self, comp: Component, service: Service) -> None:
        what = f"{service.kind} '{service.name}'"
        if service.kind == ServiceKind.ATTRIBUTE or (
            service.kind == ServiceKind.FUNCTION and comp.dialect == Dialect.GENOM2
        ):
            # genom3 (since 2.99.x) lets an attribute run simple codels; never an automaton
            fsm = [c for c in service.codels if c.triggers or comp.dialect == Dialect.GENOM2]
            if fsm:
                codel = fsm[0]
                kind = "control request" if comp.dialect == Dialect.GENOM2 else service.kind
                self.error(_where(codel.span, service.span),
                           f"{kind} '{service.name}' has FSM codel '{codel.name}' (state "
                           f"{', '.join(codel.triggers) or '?'}); it runs in the control task and takes only a "
                           "validate codel" + (" (codel_control)" if comp.dialect == Dialect.GENOM2 else ""),
                           "make it an exec request" if comp.dialect == Dialect.GENOM2 else "make it an activity")
            return
        codels = service.fsm_codels()
        if not codels:
            if service.kind == ServiceKind.ACTIVITY:
                self.error(service.span, f"activity '{service.name}' has no codel for state 'start'",
                           "its FSM begins in state 'start'")
            return
        states = fsm_states(codels)
        if "start" not in states:
            self.error(service.span, f"{what} has no codel for state 'start'",
                       f"its FSM begins in state 'start'; declared states: {', '.join(states)}")
            self._yields(codels, states, what, service.span)
            return
        if not self._yields(codels, states, what, service.span):
            return  # an undeclared state already explains why ether may be unreachable
        self._connected(codels, what, service.span, comp.dialect == Dialect.GENOM3)

    def _connected(self, codels: list[Codel], what: str, fallback: Span, all_reached: bool) -> None:
        """genom3's rules (codel.c, codel_fsmcreate): ``stop`` must lead to ether; every codel is reached.

        The start state need not lead to ether: an activity that loops until it
        is interrupted ends through its stop codel (or at once when it has none).
        """
        graph = self._graph(codels)
        stop = next((c for c in codels if "stop" in c.triggers), None)
        if stop is not None and not self._reaches(graph, "stop"):
            self.error(_where(stop.span, fallback),
                       f"no path from stop to ether in {what}: an interruption can never end",
                       "codel<stop> must eventually yield to ether")
        if not all_reached:  # GenoM2: 'fail' is entered by a throw, task 'main2' never
            return
        reached = self._reachable(graph, "start") | self._reachable(graph, "stop")
        for codel in codels:  # genom3 judges a codel, not a state: one reached trigger suffices
            if codel.triggers and not reached.intersection(codel.triggers):
                self.error(_where(codel.span, fallback),
                           f"codel<{', '.join(codel.triggers)}> '{codel.name}' of {what} is never reached",
                           "no codel yields to it from start or stop")

    def _yields(self, codels: list[Codel], states: list[str], what: str, fallback: Span) -> bool:
        """Report yields to states that no codel handles; True when there are none."""
        ok = True
        for codel in codels:
            for y in codel.yields:
                if y.state != ETHER and y.state not in states:
                    ok = False
                    self.error(_where(y.span, _where(codel.span, fallback)),
                               f"yield to undeclared state '{y.state}' in codel '{codel.name}' of {what}",
                               _suggest(y.state, states + [ETHER], "states"))
        return ok

    @staticmethod
    def _graph(codels: list[Codel]) -> dict[str, set[str]]:
        graph: dict[str, set[str]] = {}
        for codel in codels:
            for t in codel.triggers:
                graph.setdefault(t, set()).update(y.state for y in codel.yields)
        return graph

    @classmethod
    def _reaches(cls, graph: dict[str, set[str]], origin: str) -> bool:
        return ETHER in cls._reachable(graph, origin)

    @staticmethod
    def _reachable(graph: dict[str, set[str]], origin: str) -> set[str]:
        """The states reachable from ``origin`` (itself included when it has a codel)."""
        if origin not in graph:
            return set()
        seen = {origin}
        todo = deque([origin])
        while todo:
            for nxt in graph.get(todo.popleft(), ()):
                if nxt not in seen:
                    seen.add(nxt)
                    todo.append(nxt)
        return seen

    # ------------------------------------------------------------------ codel parameters

    def _codel_params(self, comp: Component, codel: Codel, service: Service | None) -> None:
        ports = [p.name for p in comp.ports]
        ids = [m.name for m in comp.ids]
        for param in codel.params:
            head = param.path.replace("[", ".").split(".")[0].strip()
            where = _where(param.span, codel.span)
            if param.source == Origin.PORT and head and head not in ports:
                self.error(where, f"unknown port '{head}' in codel '{codel.name}'", _suggest(head, ports, "ports"))
            elif param.source == Origin.IDS and head and comp.ids and head not in ids:
                self.error(where, f"unknown ids member '{head}' in codel '{codel.name}'",
                           _suggest(head, ids, "ids members"))
            elif param.source == Origin.REMOTE:
                self._remote(comp, codel, service, param.path, where)

    def _remote(self, comp: Component, codel: Codel, service: Service | None, name: str, where: Span) -> None:
        """A ``remote`` argument names a service of an interface the component uses, in a codel of an activity
        or a task (GenoM3 refuses one in a simple codel: a function's, an attribute's or a validate codel)."""
        remotes = [s.name for i in comp.uses for s in getattr(self.d.interfaces.get(i), "services", [])]
        if name not in remotes:
            hint = _suggest(name, remotes, "remote services") if remotes else \
                f"a remote is a service of an interface the component uses; {comp.name} uses none"
            self.error(where, f"unknown remote '{name}' in codel '{codel.name}'", hint)
        elif service is not None and (service.kind != ServiceKind.ACTIVITY or codel is service.validate):
            self.error(where, f"remote '{name}' is not allowed in simple codel '{codel.name}'",
                       "a remote is called from a codel of an activity or a task, as in GenoM3")

    # ------------------------------------------------------------------ exceptions

    @staticmethod
    def _exception_names(exceptions: dict[str, ExceptionDecl]) -> set[str]:
        names: set[str] = set()
        for key, decl in exceptions.items():
            for n in (key, decl.name):
                names.add(n)
                names.add(n.lstrip(":"))
                names.add(n.rsplit("::", 1)[-1])
        return names

    def _exception(self, name: str, span: Span, comp: Component) -> None:
        if name in self._exceptions or name.lstrip(":") in self._exceptions:
            return
        self.error(span, f"unknown exception '{name}' in component '{comp.name}'",
                   _suggest(name, sorted(n for n in self._exceptions if "::" not in n), "exceptions"))

    # ------------------------------------------------------------------ types

    def _types(self) -> None:
        for name, node in self.d.types.items():
            span = getattr(node, "span", NOWHERE)
            if isinstance(node, Typedef):
                self._type_refs(node.type, span, None)
            elif isinstance(node, Type):
                self._type_refs(node, span, None, top=True)
        for exc in self.d.exceptions.values():
            for member in exc.members:
                self._type_refs(member.type, member.span, None)
        for const in self.d.constants.values():
            self._type_refs(const.type, const.span, None)

    def _known_type(self, name: str, comp: Component | None) -> bool:
        bare = name.lstrip(":")
        if name in self._type_keys or bare in self._type_keys or f"::{bare}" in self._type_keys:
            return True
        if "::" not in bare and bare in self._type_tails:
            return True
        return any(k.endswith("::" + bare) for k in self._type_keys)

    def _poster_ref(self, name: str) -> str | None:
        """For ``M::P`` naming a poster: None when M declares port P, else why it cannot be checked."""
        if "::" not in name:
            return "no"
        module, poster = name.lstrip(":").split("::", 1)
        comp = self.d.component(module)
        if comp is None:
            return f"module '{module}' is not in the description"
        return None if comp.port(poster) is not None else "no"

    def _type_refs(self, typ: Type | None, fallback: Span, comp: Component | None,
                   in_port: bool = False, top: bool = False) -> None:
        for named in _named_types(typ):
            if self._known_type(named.name, comp):
                continue
            span = _where(named.span, fallback)
            key = (named.name, span)
            if key in self._reported_types:
                continue
            self._reported_types.add(key)
            if in_port:
                why = self._poster_ref(named.name)
                if why is None:
                    continue
                if why != "no":
                    self.reporter.warning(span, f"type of poster '{named.name}' unchecked: {why}",
                                          "check its module together with this one")
                    continue
            self.error(span, f"unknown type '{named.name}'",
                       _suggest(named.name, sorted(self._type_keys), "types"))


def _named_types(typ: Any, depth: int = 0) -> Iterator[NamedType]:
    """Every NamedType inside a type expression (not through named types: those are checked where declared)."""
    if typ is None or depth > 64:
        return
    if isinstance(typ, NamedType):
        yield typ
    elif isinstance(typ, (SequenceType, OptionalType)):
        yield from _named_types(typ.element, depth + 1)
    elif isinstance(typ, ArrayType):
        yield from _named_types(typ.element, depth + 1)
    elif isinstance(typ, StructType):
        for m in typ.members:
            yield from _named_types(m.type, depth + 1)
    elif isinstance(typ, UnionType):
        yield from _named_types(typ.discriminator, depth + 1)
        for case in typ.cases:
            yield from _named_types(case.member.type, depth + 1)
    elif isinstance(typ, Member):
        yield from _named_types(typ.type, depth + 1)
