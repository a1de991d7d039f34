"""The functional level as a BIP model, following the paper's grammar (§II-B).

``Functional level ::= Module+``, ``Module ::= Service+ . ControlTask . Poster+``,
``Service ::= ExecutionTask . Activity``, ``ControlTask ::= Timer . SchedulerActivity``.

Every atom and connector is named after what it comes from in the
description (``NDD.GoTo.activity``, the connector labelled ``NDD.GoTo:trigger``),
so that a trace, a counterexample or a line of the ``.bip`` output leads back
to the ``.gen`` file.  docs/genom-to-bip.md has the construct-by-construct table.
"""
from __future__ import annotations

from dataclasses import dataclass

from genom2bip import ir
from genom2bip.rules import GUARD_KINDS, Rule, description_rules
from genom2bip.build import library
from genom2bip.build.assembly import Assembly, End, Path, Rank, Wire
from genom2bip.build.names import ident, joined
from genom2bip.build.service import Fsm, acceptor_type, activity_type, codel_extern, controller_type, exec_port
from runtime.model import (
    Annotation,
    AtomType,
    Const,
    ConnectorType,
    ExternFunction,
    Package,
    PortData,
    Unary,
    source_annotation,
)
from runtime.diagnostics import NOWHERE, Span
from runtime.model.expressions import Expr

CONTROL_TASK = "control"


def rule_condition(rule: Rule, first_param: int) -> Expr:
    """The guard a rule puts on its service's trigger, over status ports ``p<first_param>``..."""
    terms: list[Expr] = []
    for i, _ in enumerate(rule.others):
        value = PortData(f"p{first_param + i}", rule.status_field)
        terms.append(Unary("!", value) if rule.negated else value)
    return library.conjunction(terms)


@dataclass
class ServiceParts:
    module: str  # the component's name as written in the description
    service: ir.Service
    path: Path  # the service compound
    task: Path  # the task compound whose scheduler runs its codels
    fsm: Fsm

    @property
    def control(self) -> Path:
        return self.path + ("control",)

    @property
    def activity(self) -> Path:
        return self.path + ("activity",)

    @property
    def label(self) -> str:
        return f"{self.module}.{self.service.name}"


class FunctionalLevel:
    """Builds the package for a set of components: one compound per module under one root compound."""

    def __init__(self, description: ir.Description, system: str, rules: list[Rule] | None = None,
                 time=None) -> None:
        self.description = description
        self.time = time  # genom2bip.build.timed.TimeOptions: add symbolic time (docs/verification/time.md)
        self.timing = None  # what the time transformation chose, once built
        self.system = system
        self.rules = description_rules(description) if rules is None else rules
        self.atom_types: dict[str, AtomType] = {}
        self.connector_types: dict[str, ConnectorType] = {}
        self.externs: dict[str, ExternFunction] = {}
        self.asm = Assembly(self._port_type, self._connector)
        self.services: dict[tuple[str, str], ServiceParts] = {}  # (component, service) as written
        self.task_execs: dict[Path, list[Wire]] = {}
        self.exec_codels: dict[str, ir.Codel] = {}  # exec wire label -> the codel it runs (even one no state reaches)
        self.wakes: dict[Path, list[End]] = {}
        self.docs: dict[str, str] = {}  # type name -> one line saying what it stands for
        self.task_labels: dict[Path, str] = {}  # task compound -> "Component.task" as its labels say it
        self.task_spans: dict[Path, Span] = {}  # task compound -> where the description declares the task
        self.task_of: dict[Path, tuple[str, ir.Task | None]] = {}  # task compound -> (component, task; None: control)

    # -- registries ---------------------------------------------------------------------
    def _port_type(self, atom_type: str, port: str) -> str:
        decl = self.atom_types[atom_type].port(port)
        return decl.type if decl else library.PORT

    def _atom_type(self, t: AtomType, doc: str = "") -> str:
        self.atom_types.setdefault(t.name, t)
        if doc:
            self.docs.setdefault(t.name, doc)
        return t.name

    def _connector(self, t: ConnectorType) -> ConnectorType:
        return self.connector_types.setdefault(t.name, t)

    def _types(self, ends: list[End]) -> tuple[str, ...]:
        """The port types of atom ports, in order: the parameters of a connector joining them."""
        return tuple(self._port_type(self.asm.atoms[e.atom].type, e.port) for e in ends)

    def _rendezvous(self, ends: list[End], exported: bool = False) -> ConnectorType:
        return self._connector(library.rendezvous_type(self._types(ends), exported))

    # -- the whole level ------------------------------------------------------------------
    def build(self) -> Package:
        self._atom_type(library.timer_type(), "Timer of a periodic task: a period starts (trigger), then ends (sleep).")
        self._atom_type(library.scheduler_type(), "Scheduler of a task: opens a period, authorises codels, closes it.")
        self._atom_type(
            library.poster_type(), "Poster (GenoM port out): written by the codels that have it as port out."
        )
        # const: a guard may call only functions that cannot change their arguments (BIP2).
        self.externs["request_pending"] = ExternFunction("request_pending", "bool", ["string"], param_const=[True])
        self.externs["take_request"] = ExternFunction("take_request", None, ["string"], param_const=[True])
        self.asm.group((), ident(self.system.upper()), comment=f"functional level {self.system}")
        for component in self.description.components:
            self._module(component)
        self._interruptions()
        written = {e.atom for w in self.asm.wires for e in w.ends if e.port == "write"}
        for path, inst in self.asm.atoms.items():
            if inst.type == "Poster" and path not in written:  # no codel has it as port out (BIP2: unbound port)
                inst.type = self._atom_type(library.unwritten_poster_type(),
                                            "Poster (GenoM port out) that no codel writes: it keeps its initial value.")
        for task_path, execs in self.task_execs.items():
            if not execs:  # no codel runs in this task: a scheduler without exec (BIP2 warns of unbound ports)
                self.asm.atoms[task_path + ("scheduler",)].type = self._atom_type(
                    library.idle_scheduler_type(), "Scheduler of a task that runs no codel: opens and closes periods.")
            self._period(task_path[0], task_path, execs)
        self._triggers()
        port_types = library.port_types()
        annotations = []
        if self.time is not None:
            from genom2bip.build import timed
            self.timing = timed.apply(self, self.time)
            if self.timing.ticks:
                port_types.append(timed.cost_port_type())
            if self.time.platform is not None:
                from genom2bip.build.platform import interval_port_type
                port_types.append(interval_port_type())
            annotations.append(self.timing.annotation())
        compounds = self.asm.compounds()  # may add connector and port types: before the package lists them
        port_types += sorted(self.asm.port_types.values(), key=lambda t: t.name)
        return Package(
            name=ident(self.system.lower()),
            annotations=annotations,
            extern_functions=sorted(self.externs.values(), key=lambda f: f.name),
            port_types=port_types,
            atom_types=list(self.atom_types.values()),
            connector_types=sorted(self.connector_types.values(), key=lambda c: c.name),
            compound_types=compounds,
        )

    # -- one module -----------------------------------------------------------------------
    def _module(self, c: ir.Component) -> None:
        m = ident(c.name)
        root: Path = (m,)
        self.asm.group(root, joined(m, "Module"), comment=f"GenoM component {c.name}")
        requests = [(ident(s.name), f"{c.name}.{s.name}") for s in c.services]
        acceptor = acceptor_type(m, requests, c.span, {ident(s.name): s.span for s in c.services})
        self.asm.atom(root + ("requests",), self._atom_type(acceptor, f"Request acceptor of {c.name}."))
        for port in c.ports:
            if port.direction == ir.Direction.OUT:
                self.asm.atom(root + (ident(port.name),), "Poster")

        tasks: dict[str, Path] = {}
        taken = {ident(s.name) for s in c.services}
        for task in c.tasks:
            tasks[task.name] = self._task(c.name, root, task, taken)
            self.task_of[tasks[task.name]] = (c.name, task)
        tasks[CONTROL_TASK + "\0"] = self._task(c.name, root, ir.Task(CONTROL_TASK, span=c.span), taken)  # GenoM's own
        self.task_of[tasks[CONTROL_TASK + "\0"]] = (c.name, None)

        for s in c.services:
            on = (
                tasks.get(s.task or "", tasks[CONTROL_TASK + "\0"])
                if s.kind == ir.ServiceKind.ACTIVITY
                else tasks[CONTROL_TASK + "\0"]
            )
            self._service(m, c, root, s, on)

    def _task(self, component: str, root: Path, task: ir.Task, taken: set[str]) -> Path:
        """A task's compound: Timer (when periodic), Scheduler, and its permanent activity (its own codels)."""
        m = root[0]
        name, shown = ident(task.name), task.name
        if name in taken:  # a service has the task's name: both keep labels of their own
            name, shown = name + "_task", shown + "_task"
        taken.add(name)
        path = self.asm.group(root + (name,), joined(m, name, "Task"), comment=f"task {task.name}")
        self.task_labels[path] = f"{component}.{shown}"
        self.task_spans[path] = task.span
        if task.period is not None:
            period_us = round(task.period.seconds * 1e6)
            self.asm.atom(path + ("timer",), "Timer", [Const(period_us)])
        self.asm.atom(path + ("scheduler",), "Scheduler")
        self.task_execs[path] = []
        self.wakes[path] = []
        if task.codels:
            fsm = Fsm.of(task.codels, task.throws).reachable(["start"])
            atom = self._atom_type(activity_type(m, name, fsm, permanent=True, origin=task.span),
                                   f"Permanent activity of task {m}.{task.name}: states {', '.join(fsm.states)}.")
            self._codel_externs(m, fsm)
            activity = self.asm.atom(path + ("permanent",), atom)
            for state in fsm.states:
                self._exec(m, self.task_labels[path], path, activity, state, fsm.codel_of[state], owner=path)
            if fsm.paused:
                self.wakes[path].append(End(activity, "wake"))
        return path

    def _codel_externs(self, m: str, fsm: Fsm) -> None:
        for codel in fsm.codel_of.values():
            self.externs.setdefault(joined(m, codel.name), codel_extern(m, codel, fsm.throws))

    def _exec(self, m: str, label: str, task: Path, activity: Path, state: str, codel: ir.Codel, owner: Path) -> Wire:
        """``exec_<state>``: the task's scheduler lets the activity run the codel of ``state``.

        The posters the codel writes join the interaction.
        """
        ends = [End(task + ("scheduler",), "exec"), End(activity, exec_port(state))]
        for p in codel.params:
            if p.source == ir.Origin.PORT and p.direction in (ir.Direction.OUT, ir.Direction.INOUT):
                poster = (m, ident(p.path.split(".")[0].split("[")[0]))
                if poster in self.asm.atoms and End(poster, "write") not in ends:
                    ends.append(End(poster, "write"))
        w = self.asm.wire(
            Wire(self._rendezvous(ends), ends, name=exec_port(state), owner=owner, label=f"{label}:{exec_port(state)}",
                 comment=f"codel {codel.name} of state {state}", annotations=source_annotation(codel.span))
        )
        self.task_execs[task].append(w)
        self.exec_codels[w.label] = codel
        return w

    def _service(self, m: str, c: ir.Component, root: Path, s: ir.Service, task: Path) -> None:
        name = ident(s.name)
        path = self.asm.group(root + (name,), joined(m, name, "Service"), comment=f"{s.kind} {s.name}")
        fsm = Fsm.of(s.fsm_codels(), list(dict.fromkeys(s.throws + c.throws))).reachable(["start", "stop"])
        constrained = any(r.service == (c.name, s.name) and r.kind in GUARD_KINDS and r.on_violation == "reject"
                          for r in self.rules)
        interruptible = any(r.kind == "interrupts" and (c.name, s.name) in r.others for r in self.rules)
        observed = any(r.kind in GUARD_KINDS and (c.name, s.name) in r.others for r in self.rules)
        control = self.asm.atom(
            path + ("control",),
            self._atom_type(
                controller_type(m, s, constrained, interruptible, observed),
                f"Execution task of {c.name}.{s.name}: trigger, validate, start, report.",
            ),
        )
        states = f"states {', '.join(fsm.states)}" if fsm.states else "no codel"
        activity = self.asm.atom(path + ("activity",), self._atom_type(
            activity_type(m, name, fsm, origin=s.span, abortable=interruptible or s.interrupts_itself),
            f"Activity of {s.kind} {c.name}.{s.name}: {states}."))
        self._codel_externs(m, fsm)
        if s.validate is not None:
            v = s.validate
            ok = ir.Codel(v.name, yields=[ir.Yield("ok")], params=v.params, wcet=v.wcet)
            self.externs.setdefault(joined(m, v.name), codel_extern(m, ok, s.throws))
        parts = ServiceParts(c.name, s, path, task, fsm)
        self.services[(c.name, s.name)] = parts

        label = parts.label
        if s.validate is not None:
            reject = [End(control, "reject")]
            self.asm.wire(Wire(self._rendezvous(reject), reject, "reject", path, f"{label}:reject",
                               comment=f"the validate codel {s.validate.name} refused the parameters",
                               annotations=source_annotation(s.validate.span)))
        for port in ("finish", "fail", "interrupted"):
            ends = [End(control, port), End(activity, port)]
            self.asm.wire(Wire(self._rendezvous(ends), ends, port, path, f"{label}:{port}",
                               annotations=source_annotation(s.span)))
        execs = [self._exec(m, label, task, activity, state, fsm.codel_of[state], owner=path) for state in fsm.states]
        if s.interrupts_itself:
            ends = [End(control, "preempt"), End(activity, "abort")]
            preempt = self.asm.wire(Wire(self._rendezvous(ends), ends, "preempt", path, f"{label}:preempt",
                                         comment=f"a new request to {s.name} interrupts the running one",
                                         annotations=source_annotation(s.ref_spans.get(f"interrupts:{s.name}",
                                                                                       s.span))))
            for w in execs:
                if w.name == exec_port("stop"):  # the stop codel runs after an abort: no abort to wait for
                    continue
                self.asm.rank(Rank(f"{ident(s.name)}_{w.name}_before_preempt", w, preempt, owner=path[:1],
                                   comment=f"a new request to {s.name} takes effect before the running one runs "
                                           "another codel"))
        if fsm.paused:
            self.wakes[task].append(End(activity, "wake"))

    def _interruptions(self) -> None:
        """``start`` of every service; one that interrupts others aborts them as it starts (paper: Stop → GoTo).

        Victims come from the description's ``interrupts`` and from rules, in
        any module: the connector is placed where the ports meet.
        """
        victims: dict[tuple[str, str], list[tuple[str, str]]] = {}
        reasons: dict[tuple[str, str], list[str]] = {}
        for r in self.rules:
            if r.kind == "interrupts":
                for v in r.others:
                    if v not in victims.setdefault(r.service, []):
                        victims[r.service].append(v)
                reasons.setdefault(r.service, []).append(r.id)
        for key, parts in self.services.items():
            start = [End(parts.control, "start"), End(parts.activity, "start")]
            mine = victims.get(key, [])
            if not mine:
                self.asm.wire(Wire(self._rendezvous(start), start, "start", parts.path, f"{parts.label}:start",
                                   annotations=source_annotation(parts.service.span)))
                continue
            # A running victim is aborted; one accepted but not started yet is cancelled.
            aborts = [End(self.services[v].activity, "abort") for v in mine]
            aborts += [End(self.services[v].control, "cancel") for v in mine]
            names = ", ".join(f"{m}.{n}" if m != key[0] else n for m, n in mine)
            outer = self.asm.wire(
                Wire(self._connector(library.triggered_type(len(start), len(aborts))), [*start, *aborts], "start",
                     parts.path, f"{parts.label}:start",
                     comment=f"{key[1]} interrupts {names} ({', '.join(reasons[key])})",
                     annotations=source_annotation(parts.service.span))
            )
            for v in mine:
                victim = self.services[v]
                for w in self.task_execs[victim.task]:
                    if w.ends[1].atom == victim.activity:
                        same = v[0] == key[0]
                        name = (f"{ident(v[1])}_{w.name}_before_{ident(key[1])}_start" if same else
                                f"{ident(v[0])}_{ident(v[1])}_{w.name}_before_{ident(key[0])}_{ident(key[1])}_start")
                        self.asm.rank(Rank(name, w, outer, owner=(ident(v[0]),) if same else (),
                                           comment=f"an interruption by {key[0]}.{key[1]} takes effect before "
                                                   f"{v[0]}.{v[1]} runs another codel"))

    def _period(self, m: str, task: Path, execs: list[Wire]) -> None:
        """Period start (timer trigger, waking the paused activities) and end (only once no codel can run)."""
        timer = task + ("timer",)
        has_timer = timer in self.asm.atoms
        opening = ([End(timer, "trigger")] if has_timer else []) + [End(task + ("scheduler",), "period")]
        wakes = self.wakes[task]
        tname = task[-1]
        at = source_annotation(self.task_spans.get(task, NOWHERE))
        if wakes:
            self.asm.wire(Wire(self._connector(library.triggered_type(len(opening), len(wakes))), [*opening, *wakes],
                               "period", task, f"{self.task_labels[task]}:period",
                               comment="a period starts: paused activities wake up", annotations=at))
        else:
            self.asm.wire(Wire(self._rendezvous(opening), opening, "period", task, f"{self.task_labels[task]}:period",
                               annotations=at))
        closing = ([End(timer, "sleep")] if has_timer else []) + [End(task + ("scheduler",), "sleep")]
        sleep = self.asm.wire(Wire(self._rendezvous(closing), closing, "sleep", task, f"{self.task_labels[task]}:sleep",
                                   annotations=at))
        for w in execs:
            self.asm.rank(Rank(f"{tname}_sleep_before_{w.owner[-1] if len(w.owner) > 1 else m}_{w.name}", sleep, w,
                               owner=(m,), comment="a period ends only when no codel of the task can run"))

    # -- requests ---------------------------------------------------------------------------
    def _triggers(self) -> None:
        """``trigger`` of every service, guarded by its rules; one ``refuse`` connector per refusing rule.

        A rule with ``on_violation: wait`` has no refuse connector: the request
        stays in the acceptor until the guard holds; the trigger connector
        names such rules in ``@wait(rules=...)`` for the reports.
        """
        for key, parts in self.services.items():
            mine = [r for r in self.rules if r.service == key and r.kind in GUARD_KINDS]
            request = End((ident(key[0]), "requests"), ident(key[1]))
            ends: list[End] = [request, End(parts.control, "trigger")]
            terms: list[Expr] = []
            for r in mine:
                terms.append(rule_condition(r, len(ends) + 1))
                ends += [End(self.services[o].control, "status") for o in r.others]
            m, name = ident(key[0]), ident(key[1])
            ttype = self._rendezvous(ends) if not terms else self._guarded(f"{m}_{name}_Trigger", ends,
                                                                          library.conjunction(terms))
            waits = [r.id for r in mine if r.on_violation == "wait"]
            self.asm.wire(Wire(ttype, ends, "trigger", parts.path, f"{parts.label}:trigger",
                               comment="; ".join(f"{r.id}: {r.describe()}" for r in mine) or None,
                               annotations=source_annotation(parts.service.span)
                               + ([Annotation("wait", {"rules": ",".join(waits)})] if waits else [])))
            for r in mine:
                if r.on_violation != "reject":
                    continue
                tag = r.id.rsplit(".", 1)[-1] if r.origin == "description" else r.id
                rends = [request, End(parts.control, "refuse")] + [End(self.services[o].control, "status")
                                                                    for o in r.others]
                rtype = self._guarded(f"{m}_{name}_Refuse_{ident(tag)}", rends, Unary("!", rule_condition(r, 3)))
                self.asm.wire(
                    Wire(
                        rtype,
                        rends,
                        f"refuse_{ident(tag)}",
                        parts.path,
                        f"{parts.label}:refuse",
                        comment=f"rule {r.id}: refuse the request unless {r.describe()}",
                        annotations=[Annotation("rule", {"name": r.id})] + source_annotation(parts.service.span),
                    )
                )

    def _guarded(self, name: str, ends: list[End], guard: Expr) -> ConnectorType:
        return self._connector(library.guarded_type(name, self._types(ends), guard))


def build_package(description: ir.Description, system: str, rules: list[Rule] | None = None) -> Package:
    """The BIP package of the functional level; ``rules`` default to the description's own constraints."""
    return FunctionalLevel(description, system, rules).build()
