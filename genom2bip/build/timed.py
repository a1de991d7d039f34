"""Symbolic time (paper §IV-D): ticks, bounded clocks and observers, added to the model before any back end.

``apply(level, options)`` rewrites a :class:`~genom2bip.build.functional.FunctionalLevel`
before it becomes a package, so that the ``.bip`` text, the Python package,
the explorer and the run-time monitors all see the same atoms:

* every Timer, Scheduler and observer gets a ``tick`` port; one rendezvous
  connector labelled ``tick`` joins them all (strong synchronisation: time
  passes for everybody at once, or not at all);
* a Timer counts the ticks of its period and opens the next period when it
  has elapsed (time cannot pass beyond that point before it does);
* a Scheduler is busy for the WCET of the codel it let run, in ticks: no
  other codel of the task runs and the period cannot close meanwhile, and
  time cannot pass while the task is idle in an open period (it has to run a
  codel or close the period first);
* an observer per periodic task (Fig. 8) counts the ticks of an open period
  and goes to ``ERROR`` once they exceed the period: an overrun;
* a latency observer per user observer (genom2bip/observers.py) counts the
  ticks from its ``from`` event to its ``to`` event and goes to ``ERROR``
  once they exceed its bound.

Ticks are ordinary ports and data (docs/verification/time.md, *Ticks as ports and data* says why).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import reduce

from genom2bip import ir
from genom2bip.build import library
from genom2bip.build.assembly import End, Path, Rank, Wire
from genom2bip.mission.spec import Mission
from genom2bip.platform import Platform
from genom2bip.build.names import ident
from runtime.diagnostics import NOWHERE, Reporter, Span
from runtime.model import (
    Annotation,
    Assign,
    AtomType,
    Binary,
    Const,
    ConnectorParam,
    ConnectorType,
    DataDecl,
    DataParam,
    DefineGroup,
    DefinePort,
    If,
    InitialTransition,
    InteractionSpec,
    PortData,
    PortDecl,
    PortType,
    Transition,
    Var,
)

#: The label of the interaction in which time passes by one tick.
TICK = "tick"
#: The place an observer reaches when its property is violated.
ERROR = "ERROR"
#: A codel without a ``wcet`` annotation is taken to run this long (µs): no time, and a warning names it.
DEFAULT_WCET_US = 0
#: Port type of a scheduler's ``exec``: the connector tells it how many ticks the codel takes.
COST = "Cost"
#: A service's reports: on a platform, time does not pass while one can be given.
REPORTS = ("start", "finish", "fail", "interrupted", "reject")


@dataclass
class LatencySpec:
    """A user observer: every ``begin`` event is followed by an ``end`` event within ``within_us``."""

    name: str
    begin: str  # event pattern, e.g. LaserRF.Scan:write
    end: str
    within_us: int
    doc: str | None = None
    begin_span: Span = NOWHERE  # where the file says it, for errors
    end_span: Span = NOWHERE


@dataclass
class TimeOptions:
    tick_us: int | None = None  # None: the gcd of every period, WCET and observer bound
    default_wcet_us: int = DEFAULT_WCET_US
    latencies: list[LatencySpec] = field(default_factory=list)
    ticks: bool = True  # False: observers only, for a controller that measures real time
    platform: Platform | None = None  # None: a core per task, codels take their WCET (genom2bip.platform)
    client: Mission | None = None  # a mission whose steps are the environment (genom2bip.build.client)
    responses: bool = False  # a response-time observer per periodic task and per service
    exceptions: bool = True  # False: codels take their declared yields only (they never throw)
    response_cap_us: int | None = None  # response times stop counting there (default: 10 x the longest period)


@dataclass
class Observer:
    """An observer atom of the timed model: ERROR reachable means its property is violated."""

    name: str  # what reports call it
    atom: str  # instance path, e.g. NDD.motion.overrun
    kind: str  # "overrun", "latency" or "response"
    bound_ticks: int
    text: str  # the property in words
    until_stopped: bool = False  # a service's: once started, only an interruption ends it (:func:`_ends_alone`)


@dataclass
class Timing:
    """What the transformation chose and added: reports and the run-time monitor read it."""

    tick_us: int
    observers: list[Observer]
    untimed_codels: list[str]  # codels that got the default WCET
    default_wcet_us: int
    costs: dict[str, int]  # exec label -> ticks
    ticks: bool = True
    platform: str = ""  # the platform in words, when the tasks run on one
    client: str = ""  # the mission that is the environment, when one is
    idle: list[str] = field(default_factory=list)  # tasks with nothing to run for the client (:func:`idle_tasks`)

    def annotation(self) -> Annotation:
        """``@timed(tick_us=...)`` (or ``@monitored`` without ticks) on the package: a ``.bip`` knows its resolution."""
        args = {"tick_us": str(self.tick_us)}
        if not self.ticks:
            return Annotation("monitored", args)
        if self.untimed_codels:
            args.update(untimed=",".join(self.untimed_codels), default_wcet_us=str(self.default_wcet_us))
        if self.platform:
            args["platform"] = self.platform
        if self.client:
            args["client"] = self.client
        if self.idle:
            args["idle"] = ",".join(self.idle)
        served = [f"{o.atom}={o.name.rsplit(':', 1)[0]}" for o in self.observers
                  if o.kind in ("response", "pending") and "." not in o.atom]
        if served:
            args["responses"] = ",".join(served)  # service observers sit at the root: whose response each one is
        stopped = [o.name.rsplit(":", 1)[0] for o in self.observers if o.until_stopped]
        if stopped:
            args["until_stopped"] = ",".join(stopped)  # the services whose requests only an interruption ends
        return Annotation("timed", args)


def cost_port_type() -> PortType:
    return PortType(COST, [DataParam("int", "cost")])


def ticks_up(us: int, tick: int) -> int:
    """A duration in ticks, rounded up: a WCET never shrinks."""
    return -(-us // tick)


def matching_wires(level, event: str) -> list[Wire]:
    """The wires an event ``Module.Name:port`` names: its label, the family ``port_*``, or a poster's writes."""
    head, port = event.rsplit(":", 1)
    module, thing = head.split(".", 1)
    poster = (ident(module), ident(thing))
    out = []
    for w in level.asm.wires:
        if port == "write":
            if any(isinstance(e, End) and e.atom == poster and e.port == "write" for e in w.ends):
                out.append(w)
        elif w.label is not None and (w.label == event or w.label.startswith(event + "_")):
            out.append(w)
    return out


def _resolve(level, spec: LatencySpec) -> tuple[list[Wire], list[Wire]]:
    """The wires of both events of an observer; located errors when one names nothing or both the same step."""
    reporter = Reporter()
    begin, end = matching_wires(level, spec.begin), matching_wires(level, spec.end)
    for wires, event, span in ((begin, spec.begin, spec.begin_span), (end, spec.end, spec.end_span)):
        if not wires:
            reporter.error(span, f"observer {spec.name}: no interaction of the model is a {event} event",
                           "the service or task has no codel for it")
    both = [w.label for w in begin if w in end]
    if both:
        reporter.error(spec.end_span, f"observer {spec.name}: {both[0]} is both a 'from' and a 'to' event",
                       "an observer needs two different events")
    reporter.raise_if_errors()
    return begin, end


def timer_type() -> AtomType:
    """Timer of a periodic task: its releases fall on a fixed grid, every ``ticks`` from the first one.

    Clock ``t`` counts the ticks since the last release, whatever the task
    does: time cannot pass beyond ``t == ticks`` before the next release.  A
    release opens the next period at once when the task sleeps (``trigger``
    in ``WAIT``); when the period is still open, it is kept (``late``:
    ``PERIOD`` to ``LATE``) and the next period opens as soon as this one
    closes (``DUE``), with ``t`` still counting from its release.  Releases
    kept while one is already kept are lost, as a periodic timer's are.
    """
    base = library.timer_type()
    base.params.append(DataParam("int", "ticks"))
    base.data.append(DataDecl("int", "t", annotations=[library.CLOCK]))
    base.ports += [PortDecl(library.PORT, "late", exported=True), PortDecl(library.PORT, "tick", exported=True)]
    base.places = ["WAIT", "PERIOD", "LATE", "DUE"]
    base.initial = InitialTransition(["WAIT"], [Assign(Var("t"), Var("ticks"))])
    t = Var("t")
    released = Binary(">=", t, Var("ticks"))
    passing = Binary("<", t, Var("ticks"))
    older = [Assign(t, Binary("+", t, Const(1)))]
    restart = [Assign(t, Const(0))]
    base.transitions = [
        Transition("trigger", ["WAIT"], ["PERIOD"], guard=released, action=restart),
        Transition("trigger", ["DUE"], ["PERIOD"]),
        Transition("sleep", ["PERIOD"], ["WAIT"]),
        Transition("sleep", ["LATE"], ["DUE"]),
        Transition("late", ["PERIOD"], ["LATE"], guard=released, action=restart),
        Transition("late", ["LATE"], ["LATE"], guard=released, action=restart),
    ] + [Transition("tick", [p], [p], guard=passing, action=list(older)) for p in ("WAIT", "PERIOD", "LATE")]
    return base


def idle_timer_type() -> AtomType:
    """The timer of a task with nothing to run for the client: no release is explored (:func:`idle_tasks`).

    Such a task's periods would each open and close at the instant they open, taking no core (the platform's
    ``rest``, ranked before every grant of that instant): nothing another task or an observer of another task
    can tell.  Its phase would only multiply the zones (a 200 ms timer beside a 75 ms one doubles the
    hyperperiod), so it keeps the timer's ports and parameters, and its clock and releases go.
    """
    base = timer_type()
    return AtomType(name="IdleTimer", annotations=list(base.annotations), params=list(base.params), data=[],
                    ports=list(base.ports), places=["WAIT"], initial=InitialTransition(["WAIT"]),
                    transitions=[Transition("tick", ["WAIT"], ["WAIT"])])


def idle_tasks(level, mission) -> list[tuple[str, ...]]:
    """The periodic tasks with nothing to run for ``mission``: no codel of their own (a permanent activity), and
    none of their services among the requests it sends (only a request starts a service).  A task that suspends
    after each release, or whose first release is delayed, is not one: its periods do not close at once."""
    sent = {step.target for step in mission.steps if step.kind == "send"}
    busy = {parts.task for parts in level.services.values() if parts.label in sent}
    out = []
    for task, wires in level.task_execs.items():
        timer = level.asm.atoms.get(task + ("timer",))
        scheduler = level.asm.atoms.get(task + ("scheduler",))
        own = any(isinstance(e, End) and e.atom == task + ("permanent",) for w in wires for e in w.ends)
        if (timer is not None and timer.type == "Timer" and task not in busy and not own
                and not (scheduler is not None and scheduler.type.startswith("Suspending"))):
            out.append(task)
    return out


def _capped(var: str, cap: str) -> If:
    """``if (var < cap) then var = var + 1; fi``: a clock that stops at ``cap`` (bounded clocks)."""
    return If(Binary("<", Var(var), Var(cap)), (Assign(Var(var), Binary("+", Var(var), Const(1))),))


def scheduler_type() -> AtomType:
    """Scheduler whose ``exec`` receives the ticks the codel takes; busy until they have passed."""
    base = library.scheduler_type()
    base.data = [DataDecl("int", "busy"), DataDecl("int", "cost")]
    base.ports = [
        PortDecl(library.PORT, "period", exported=True),
        PortDecl(COST, "exec", ["cost"], exported=True),
        PortDecl(library.PORT, "sleep", exported=True),
        PortDecl(library.PORT, "tick", exported=True),
    ]
    idle = Binary("==", Var("busy"), Const(0))
    base.initial = InitialTransition(["SLEEP"], [Assign(Var("busy"), Const(0)), Assign(Var("cost"), Const(0))])
    base.transitions = [
        Transition("period", ["SLEEP"], ["RUN"]),
        Transition("exec", ["RUN"], ["RUN"], guard=idle,
                   action=[Assign(Var("busy"), Var("cost")), Assign(Var("cost"), Const(0))]),
        Transition("sleep", ["RUN"], ["SLEEP"], guard=idle),
        Transition("tick", ["SLEEP"], ["SLEEP"]),
        Transition("tick", ["RUN"], ["RUN"], guard=Binary(">", Var("busy"), Const(0)),
                   action=[Assign(Var("busy"), Binary("-", Var("busy"), Const(1)))]),
    ]
    return base


def idle_scheduler_type() -> AtomType:
    """The scheduler of a periodic task that runs no codel: a period opens and closes at once, time passes while it
    sleeps.  :func:`scheduler_type` without ``exec`` behaves so too (``busy`` stays 0), but its tick would still
    change discrete data, which clock zones do not take; this one has no data."""
    base = library.idle_scheduler_type(library.scheduler_type())
    base.ports = [*base.ports, PortDecl(library.PORT, "tick", exported=True)]
    base.transitions = [*base.transitions, Transition("tick", ["SLEEP"], ["SLEEP"])]
    return base


def _observer_type(name: str, kind: str, opening: str, closing: str, bound: str, watching: str,
                   either_order: bool) -> AtomType:
    """An observer: ``opening`` starts clock ``c``, ``closing`` stops it, ``c > bound`` is ERROR.

    Every place has a transition on every port (an observer never blocks
    what it watches).  ``either_order``: the events may come in any order
    (a second opening keeps the first one's clock, a closing with nothing
    open is ignored); otherwise they alternate.  From ERROR, observing goes
    on: the closing ends the late observation, the next opening starts one.
    """
    c, limit = Var("c"), Var(bound)
    restart = [Assign(c, Const(0))]
    transitions = [
        Transition(opening, ["IDLE"], [watching], action=restart),
        Transition(closing, [watching], ["IDLE"]),
        Transition("tick", ["IDLE"], ["IDLE"]),
        Transition("tick", [watching], [watching], action=[Assign(c, Binary("+", c, Const(1)))]),
        Transition(None, [watching], [ERROR], guard=Binary(">", c, limit)),
        Transition(opening, [ERROR], [watching], action=restart),
        Transition(closing, [ERROR], ["IDLE"]),
        Transition("tick", [ERROR], [ERROR]),
    ]
    if either_order:
        transitions += [Transition(opening, [watching], [watching]), Transition(closing, ["IDLE"], ["IDLE"])]
    return AtomType(
        name=name,
        annotations=[Annotation("observer", {"kind": kind, "open": opening, "close": closing, "bound": bound})],
        params=[DataParam("int", bound)],
        data=[DataDecl("int", "c", annotations=[library.CLOCK])],
        ports=[PortDecl(library.PORT, n, exported=True) for n in (opening, closing, "tick")],
        places=["IDLE", watching, ERROR],
        initial=InitialTransition(["IDLE"], restart),
        transitions=transitions,
    )


def overrun_type() -> AtomType:
    """The paper's Fig. 8: clock ``c`` counts the ticks of an open period; ``c > p`` is an overrun (ERROR)."""
    return _observer_type("PeriodObserver", "overrun", "period", "sleep", "p", "RUN", either_order=False)


def latency_type() -> AtomType:
    """After ``cause``, ``effect`` must come within ``bound`` ticks, else ERROR; the oldest cause counts."""
    return _observer_type("LatencyObserver", "latency", "cause", "effect", "bound", "WAIT", either_order=True)


def response_type() -> AtomType:
    """Clock ``c`` counts from ``open`` to ``close`` (a period to its end, a request to its final report).

    It has no ERROR: its largest value over the reachable states is the response
    time (``verify --response-times``).  ``c`` stops at ``cap`` (a finite model):
    reaching it means "at least cap".  Every place takes every port.
    """
    c = Var("c")
    return AtomType(
        name="ResponseObserver",
        annotations=[Annotation("observer", {"kind": "response", "open": "open", "close": "close", "bound": "cap"})],
        params=[DataParam("int", "cap")],
        data=[DataDecl("int", "c", annotations=[library.CLOCK])],
        ports=[PortDecl(library.PORT, n, exported=True) for n in ("open", "close", "tick")],
        places=["IDLE", "WATCH"],
        initial=InitialTransition(["IDLE"], [Assign(c, Const(0))]),
        transitions=[
            Transition("open", ["IDLE"], ["WATCH"], action=[Assign(c, Const(0))]),
            Transition("open", ["WATCH"], ["WATCH"]),
            Transition("close", ["WATCH"], ["IDLE"]),
            Transition("close", ["IDLE"], ["IDLE"]),
            Transition("tick", ["IDLE"], ["IDLE"]),
            Transition("tick", ["WATCH"], ["WATCH"], action=[_capped("c", "cap")]),
        ],
    )


def observed(ctype: ConnectorType, extra: int) -> tuple[ConnectorType, int]:
    """``ctype`` with ``extra`` more ports that take part in every interaction (observer ports, always ready).

    Returns the type and the position of the new ports among the parameters: right after the trigger
    group of ``(t1 .. tk)' r1 .. rn`` (they fire with the trigger; a trigger group stays the first
    parameters, as connector splitting expects), else at the end.
    """
    items = list(ctype.define.items)
    head = items[0] if items and isinstance(items[0], DefineGroup) and items[0].trigger else None
    if head is not None and not ctype.interactions:  # (trigger group)' receivers: observers fire with the trigger
        k, n = len(head.items), len(ctype.params) + extra
        names = library.param_names(n)
        types = [p.port_type for p in ctype.params[:k]] + [library.PORT] * extra + \
            [p.port_type for p in ctype.params[k:]]
        define = DefineGroup([DefineGroup([DefinePort(x) for x in names[:k + extra]], trigger=True)]
                             + [DefinePort(x) for x in names[k + extra:]], trigger=ctype.define.trigger)
        return ConnectorType(name=f"{ctype.name}_O{extra}", params=[ConnectorParam(t, x) for t, x in zip(types, names)],
                             define=define, data=list(ctype.data), export=ctype.export,
                             annotations=list(ctype.annotations)), k
    names = [f"p{len(ctype.params) + i + 1}" for i in range(extra)]
    items += [DefinePort(n) for n in names]
    return ConnectorType(
        name=f"{ctype.name}_O{extra}",
        params=list(ctype.params) + [ConnectorParam(library.PORT, n) for n in names],
        define=DefineGroup(items, trigger=ctype.define.trigger),
        data=list(ctype.data),
        export=ctype.export,
        interactions=[InteractionSpec(list(s.ports) + names, s.guard, list(s.up), list(s.down), list(s.annotations))
                      for s in ctype.interactions],
        annotations=list(ctype.annotations),
    ), len(ctype.params)


def exec_type(ctype: ConnectorType, cost: int) -> ConnectorType:
    """An exec rendezvous that tells the scheduler (its first port) the codel's cost in ticks."""
    names = [p.name for p in ctype.params]
    return ConnectorType(
        name=f"Exec{cost}_{ctype.name.split('_', 1)[1]}",
        params=[ConnectorParam(COST, names[0])] + list(ctype.params[1:]),
        define=ctype.define,
        interactions=[InteractionSpec(names, down=[Assign(PortData(names[0], "cost"), Const(cost))])],
    )


def _codel_of(level, wire: Wire) -> tuple[str, int | None]:
    """The codel an exec wire runs: (its name, its WCET in µs or None).

    Read from the description, not from the activity's transitions: a codel
    of a state no run reaches has no transition left, and its wire still
    needs a cost.
    """
    codel = level.exec_codels[wire.label]
    return codel.name, round(codel.wcet.seconds * 1e6) if codel.wcet is not None else None


def _constants(level, options: TimeOptions, execs, timers) -> list[int]:
    """Every duration of the model in µs: the tick divides them all (periods, WCETs, bounds, the platform's)."""
    out = [inst.args[0].value for inst in timers.values()]
    out += [wcet for _, _, wcet in execs if wcet is not None]
    out += [spec.within_us for spec in options.latencies]
    if any(wcet is None for _, _, wcet in execs):
        out.append(options.default_wcet_us)
    platform = options.platform
    if platform is not None:
        out += [us for span in platform.execution.values() for us in (span.best_us, span.worst_us)]
        out += [us for t in platform.tasks.values() if t.delay for us in (t.delay.best_us, t.delay.worst_us)]
        out += [us for t in platform.tasks.values() if t.suspend for us in (t.suspend.best_us, t.suspend.worst_us)]
        out += [round(t.delay.seconds * 1e6) for _, t in level.task_of.values() if t is not None and t.delay]
        if isinstance(platform.best, int):
            out.append(platform.best)
    return out


def _flag(t: AtomType, name: str, initially: bool) -> Var:
    """A bool ``name`` added to ``t``'s data, set to ``initially`` by its initial transition."""
    t.data = list(t.data) + [DataDecl("bool", name)]
    flag = Var(name)
    t.initial = InitialTransition(list(t.initial.targets), list(t.initial.action) + [Assign(flag, Const(initially))])
    return flag


def _on_port(t: AtomType, port: str, flag: Var, value: bool, needed: bool = False) -> None:
    """Every transition of ``t`` on ``port`` ends by setting ``flag`` to ``value`` (and, ``needed``, requires it)."""
    def changed(tr: Transition) -> Transition:
        guard = library.conjunction([g for g in (tr.guard, flag) if g is not None]) if needed else tr.guard
        return replace(tr, guard=guard, action=list(tr.action) + [Assign(flag, Const(value))])

    t.transitions = [changed(tr) if tr.port == port else tr for tr in t.transitions]


def arm_requests(level, watch) -> None:
    """The default environment is not Zeno: a service of a periodic task is requested at most once per period.

    The acceptor's port of such a service is armed when its task's period
    opens and disarmed by the request it lets through (docs/verification/platform.md,
    *The environment*).
    """
    armed: dict[Path, dict[tuple[str, ...], list[str]]] = {}  # acceptor -> task -> services
    for (component, service), parts in level.services.items():
        if parts.service.kind != ir.ServiceKind.ACTIVITY or parts.task + ("timer",) not in level.asm.atoms:
            continue
        acceptor = (ident(component), "requests")
        armed.setdefault(acceptor, {}).setdefault(parts.task, []).append(ident(service))
    for acceptor, tasks in armed.items():
        inst = level.asm.atoms[acceptor]
        t = level.atom_types[inst.type]
        flags = {s: _flag(t, f"armed_{s}", True) for services in tasks.values() for s in services}
        for service, flag in flags.items():
            _on_port(t, service, flag, False, needed=True)
        for task, services in tasks.items():
            port = f"arm_{task[-1]}"
            t.ports = list(t.ports) + [PortDecl(library.PORT, port, exported=True)]
            t.transitions = list(t.transitions) + [
                Transition(port, ["READY"], ["READY"], action=[Assign(flags[s], Const(True)) for s in services])]
            for opening in (w for w in level.asm.wires if w.label == f"{level.task_labels[task]}:period"):
                watch(opening, End(acceptor, port))


def start_windows(level, watch, platform: bool) -> None:
    """An activity of a periodic task starts only when its task takes up new work, as GenoM3's execution task does.

    The execution task looks for newly started activities when its period
    opens and runs their codels in that period; a request that comes later
    starts its activity at the next opening.  Each such activity atom gets a
    ``window`` flag, set by the task's period opening and cleared once the
    task runs (its grant on a platform, else its first codel) or the period
    closes; its ``start`` needs it and closes it.  Starts at the instant of an
    opening come before the task runs (priorities), so no request waits a
    period more for a tie.
    """
    periodic = {task for task, label in level.task_labels.items()
                if any(w.label == f"{label}:period" for w in level.asm.wires) and task + ("timer",) in level.asm.atoms}
    for parts in level.services.values():
        if parts.service.kind != ir.ServiceKind.ACTIVITY or parts.task not in periodic:
            continue
        label = level.task_labels[parts.task]
        starts = [w for w in level.asm.wires if w.label == f"{parts.label}:start"]
        if not starts:
            continue
        inst = level.asm.atoms[parts.activity]
        t = level.atom_types[inst.type]
        if sum(1 for i in level.asm.atoms.values() if i.type == inst.type) > 1:  # a type of its own to change
            t = replace(t, name=f"{t.name}_{ident('_'.join(parts.path))}")
            level.atom_types[t.name] = t
            inst.type = t.name
        window = _flag(t, "window", False)
        t.ports = list(t.ports) + [PortDecl(library.PORT, "window_open", exported=True),
                                   PortDecl(library.PORT, "window_shut", exported=True)]
        _on_port(t, "start", window, False, needed=True)
        t.transitions += [Transition(port, [p], [p], action=[Assign(window, Const(value))])
                          for port, value in (("window_open", True), ("window_shut", False)) for p in t.places]
        for w in level.asm.wires:
            if w.label != f"{label}:period":
                continue
            joined = next((e.port for e in w.ends if isinstance(e, End) and e.atom == parts.activity), None)
            if joined is None:
                watch(w, End(parts.activity, "window_open"))
                continue
            # The opening already wakes this activity (a paused one goes on): that port opens the window too,
            # in every place (where it did nothing, it now only opens it).
            has = {src for tr in t.transitions if tr.port == joined for src in tr.sources}
            _on_port(t, joined, window, True)
            t.transitions += [Transition(joined, [p], [p], action=[Assign(window, Const(True))])
                              for p in t.places if p not in has]
        runs = [w for w in level.asm.wires if w.label == f"{label}:grant"] if platform else []
        runs = (runs or list(level.task_execs.get(parts.task, []))) + [w for w in level.asm.wires
                                                                       if w.label == f"{label}:sleep"]
        for k, w in enumerate(runs):
            joined = next((e.port for e in w.ends if isinstance(e, End) and e.atom == parts.activity), None)
            if joined is None:
                watch(w, End(parts.activity, "window_shut"))
            else:  # its own codel, or its being quiet when the period closes: that port closes the window
                _on_port(t, joined, window, False)
            for j, start in enumerate(starts):
                level.asm.rank(Rank(f"{ident('_'.join(parts.path))}_start_{j}_before_{w.name}_{k}", w, start,
                                    owner=(), comment="a request there when the task takes up work starts with it"))


#: Service reports that end a request.
FINALS = ("finish", "fail", "interrupted", "reject")


def pending_type() -> AtomType:
    """Whether a request is waiting for its final report, without a clock: for a service that can run for ever.

    An activity whose codels can go round a cycle (``pause::`` back to an
    earlier state) may never report: its response time has no bound, which a
    cycle of the model shows (a lasso), not a clock counting to a cap.
    """
    return AtomType(
        name="PendingObserver",
        annotations=[Annotation("observer", {"kind": "pending", "open": "open", "close": "close"})],
        ports=[PortDecl(library.PORT, n, exported=True) for n in ("open", "close")],
        places=["IDLE", "WATCH"],
        initial=InitialTransition(["IDLE"]),
        transitions=[
            Transition("open", ["IDLE"], ["WATCH"]),
            Transition("open", ["WATCH"], ["WATCH"]),
            Transition("close", ["WATCH"], ["IDLE"]),
            Transition("close", ["IDLE"], ["IDLE"]),
        ],
    )


def _loops(fsm) -> bool:
    """The activity's codels can go round a cycle: a state reachable again from itself."""
    edges = {s: {y.state for y in fsm.codel_of[s].yields if y.state in fsm.codel_of} for s in fsm.states}

    def reach(a: str) -> set[str]:
        seen, todo = set(), [a]
        while todo:
            for b in edges.get(todo.pop(), ()):
                if b not in seen:
                    seen.add(b)
                    todo.append(b)
        return seen

    return any(s in reach(s) for s in fsm.states)


def _ends_alone(fsm, exceptions: bool) -> bool:
    """A started activity may end without an interruption: a codel reached from ``start`` yields ether or throws."""
    seen, todo = {"start"}, ["start"]  # not from ``stop``: only an interruption leads there
    while todo:
        codel = fsm.codel_of.get(todo.pop())
        if codel is None:
            continue
        if exceptions and fsm.throws:
            return True
        for y in codel.yields:
            if y.state == "ether":
                return True
            if y.state not in seen:
                seen.add(y.state)
                todo.append(y.state)
    return False


def _longest(fsm) -> int:
    """Codel steps on the longest run of an activity without a cycle."""
    memo: dict[str, int] = {}

    def depth(s: str) -> int:
        if s not in memo:
            memo[s] = 1 + max([depth(y.state) for y in fsm.codel_of[s].yields if y.state in fsm.codel_of] or [0])
        return memo[s]

    return max([depth(s) for s in fsm.states] or [0])


def add_responses(level, options: TimeOptions, tick: int, periods, watch, ticking: list, observers: list) -> None:
    """A response observer per periodic task (release to end of cycle) and per service (request to final report).

    Clocks stop counting at a cap, past which a response time is reported as
    "more than the cap": a task's is 4 periods (an overrun long before); a
    service's, twice the periods its longest run of codels can take.  A
    service whose codels can cycle gets a :func:`pending_type` observer instead.
    """
    level.atom_types["ResponseObserver"] = response_type()
    level.docs.setdefault("ResponseObserver", "Response time: the ticks from an opening to its closing.")
    timers = {path[:-1]: inst.args[1].value for path, inst in level.asm.atoms.items()
              if inst.type in ("Timer", "DelayedTimer", "IdleTimer")}  # a task with a delay has a DelayedTimer

    def observe(path, label: str, opens: list, closes: list, what: str, cap: int | None,
                until_stopped: bool = False) -> None:
        """``path``: the observer's (a service's at the root: its trigger may join other modules' atoms)."""
        if options.response_cap_us is not None:
            cap = max(1, -(-options.response_cap_us // tick))
        kind, args = ("response", [Const(cap)]) if cap is not None else ("pending", [])
        if cap is None and "PendingObserver" not in level.atom_types:
            level.atom_types["PendingObserver"] = pending_type()
            level.docs["PendingObserver"] = "A request waiting for its report (a service that may never end)."
        atom = level.asm.atom(path, "ResponseObserver" if cap is not None else "PendingObserver", args)
        for w in opens:
            watch(w, End(atom, "open"))
        for w in closes:
            watch(w, End(atom, "close"))
        if cap is not None:
            ticking.append(End(atom, "tick"))
        observers.append(Observer(f"{label}:response", ".".join(atom), kind, cap or 0, what, until_stopped))

    for path, label in level.task_labels.items():
        opens = [w for w in level.asm.wires if w.label == f"{label}:period"]
        closes = [w for w in level.asm.wires if w.label == f"{label}:sleep"]
        if opens and path in timers:
            observe(path + ("response",), label, opens, closes, f"from a release of {label} to the end of its cycle",
                    4 * timers[path])
    for parts in level.services.values():
        opens = [w for w in level.asm.wires if w.label == f"{parts.label}:trigger"]
        closes = [w for w in level.asm.wires if w.label in {f"{parts.label}:{p}" for p in FINALS}]
        if not (closes and parts.fsm.states):
            continue  # no trigger (a client that never sends it): an observer never opened says "never requested"
        period = timers.get(parts.task, max(timers.values(), default=1))
        cap = None if _loops(parts.fsm) else 2 * (_longest(parts.fsm) + 2) * period
        observe((ident("_".join(parts.path + ("response",))),), parts.label, opens, closes,
                f"from a request of {parts.label} to its final report", cap,
                not _ends_alone(parts.fsm, options.exceptions))


def apply(level, options: TimeOptions) -> Timing:
    """Add time to ``level`` (a FunctionalLevel whose wires are all built); returns what was chosen.

    With ``options.ticks`` false only the observers are added (no tick, no
    clock moves): the model a controller runs, whose monitor measures real
    time instead (runtime/controller/monitor.py); bounds are then in µs.
    With ``options.platform`` the tasks run on its cores (genom2bip.build.platform).
    """
    execs: list[tuple[Wire, str, int | None]] = []
    for task, wires in level.task_execs.items():
        for w in wires:
            execs.append((w, *_codel_of(level, w)))
    timers = {path: inst for path, inst in level.asm.atoms.items() if inst.type == "Timer"}
    untimed = sorted({f"{w.label.split('.')[0]}.{name}" for w, name, wcet in execs if wcet is None})
    constants = _constants(level, options, execs, timers)
    tick = options.tick_us or reduce(math.gcd, [c for c in constants if c > 0], 0) or options.default_wcet_us or 1
    if not options.ticks:
        tick, untimed = 1, []
    periods = {path: max(1, inst.args[0].value // tick) for path, inst in timers.items()}  # rounded down

    ticking: list[End] = []
    costs: dict[str, int] = {}
    urgent: list[Wire] = []
    observers: list[Observer] = []
    extra: dict[int, tuple[Wire, list[End]]] = {}
    idle: list[str] = []

    def watch(wire: Wire, end: End) -> None:
        extra.setdefault(id(wire), (wire, []))[1].append(end)

    if not options.exceptions:  # the codels' outcomes are their yields: exploration never makes one throw
        for f in level.externs.values():
            for a in f.annotations:
                if a.name == "codel":
                    a.arguments["throws"] = ""
    if options.ticks:
        level.atom_types["Timer"] = timer_type()
        for path, inst in timers.items():
            inst.args.append(Const(periods[path]))
            ticking.append(End(path, "tick"))
            late = [End(path, "late")]
            label = f"{level.task_labels[path[:-1]]}:late"
            level.asm.wire(Wire(level._rendezvous(late), late, "late", path[:-1], label,
                                comment="a release while the period is still open: the next one opens at its end"))
        if options.platform is None:
            level.atom_types["Scheduler"] = scheduler_type()
            for w, name, wcet in execs:
                cost = ticks_up(options.default_wcet_us if wcet is None else wcet, tick)
                w.type = level._connector(exec_type(w.type, cost))
                costs[w.label] = cost
        else:
            from genom2bip.build import platform
            level.atom_types.pop("Scheduler", None)
            urgent = platform.apply(level, options.platform, tick, options.default_wcet_us)
            urgent += [w for w in level.asm.wires if w.label and w.label.rsplit(":", 1)[1] in REPORTS]
            for task in idle_tasks(level, options.client) if options.client is not None else ():
                level.asm.atoms[task + ("timer",)].type = "IdleTimer"
                idle.append(level.task_labels[task])
            if idle:
                level.atom_types["IdleTimer"] = idle_timer_type()
        if "IdleScheduler" in level.atom_types:
            level.atom_types["IdleScheduler"] = idle_scheduler_type()
        ticking += [End(task + ("scheduler",), "tick") for task in level.task_execs]
        if options.client is not None:
            from genom2bip.build import client
            added = client.apply(level, options.client, tick, watch)
            ticking.append(End(added.atom, "tick"))
            urgent += added.urgent
        else:
            arm_requests(level, watch)
        start_windows(level, watch, options.platform is not None)

    if timers:
        level.atom_types["PeriodObserver"] = overrun_type()
        level.docs.setdefault("PeriodObserver", "Period observer (paper Fig. 8): ERROR when a period overruns.")
    for path in timers:
        task = path[:-1]
        ticks = periods[path]
        atom = level.asm.atom(task + ("overrun",), "PeriodObserver", [Const(ticks)])
        label = level.task_labels[task]
        for w in level.asm.wires:
            if w.label in (f"{label}:period", f"{label}:sleep"):
                watch(w, End(atom, w.label.rsplit(":", 1)[1]))
        ticking.append(End(atom, "tick"))
        observers.append(Observer(f"{label}:overrun", ".".join(atom), "overrun", ticks,
                                  f"a period of {label} never lasts longer than the period"))
    if options.latencies:
        level.atom_types["LatencyObserver"] = latency_type()
        level.docs.setdefault("LatencyObserver", "Latency observer: ERROR when an answer comes too late.")
    for spec in options.latencies:
        bound = spec.within_us // tick
        begin, end = _resolve(level, spec)
        atom = level.asm.atom((ident(spec.name.replace("-", "_")),), "LatencyObserver", [Const(bound)])
        for w in begin:
            watch(w, End(atom, "cause"))
        for w in end:
            watch(w, End(atom, "effect"))
        ticking.append(End(atom, "tick"))
        observers.append(Observer(spec.name, ".".join(atom), "latency", bound,
                                  f"after {spec.begin}, {spec.end} within {spec.within_us / 1000:g} ms"))
    if options.responses:
        add_responses(level, options, tick, periods, watch, ticking, observers)
    for wire, ends in extra.values():
        ctype, at = observed(wire.type, len(ends))
        wire.ends = list(wire.ends)[:at] + ends + list(wire.ends)[at:]
        wire.type = level._connector(ctype)
    if options.ticks and ticking:  # no timed atom at all (a component with no task): time changes nothing
        passing = level.asm.wire(Wire(level._rendezvous(ticking), ticking, TICK, (), TICK,
                                      comment="time passes by one tick for every timed atom at once"))
        for w in urgent:
            level.asm.rank(Rank(f"tick_after_{'_'.join(w.owner)}_{w.name}", passing, w, owner=(),
                                comment="time passes only when nothing urgent can happen"))
    return Timing(tick, observers, untimed, options.default_wcet_us, costs, options.ticks,
                  options.platform.describe() if options.platform is not None else "",
                  options.client.name if options.client is not None else "", idle)
