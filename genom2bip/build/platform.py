"""The platform as a transformation of the timed model: cores, a policy as priorities, execution intervals, locks.

Applied by :func:`genom2bip.build.timed.apply` when a platform is given
(``verify --timed --platform FILE``), before the observers are added:

* a task's scheduler becomes a ``CoreScheduler``: once its period opens it is
  READY and must be *granted* one of the platform's cores (``M.T:grant``, a
  rendezvous with ``platform.cores``) before its codels run; it gives the core
  back when its period closes (cooperative EDF) or after each codel (fixed
  priority, non-preemptive at codel boundaries);
* the policy is a set of priorities between the grants, as BIP models
  scheduling: EDF compares the time left to the end of each task's period,
  read from its timer; fixed priority compares the description's
  ``priority`` (0 highest);
* a codel runs for any number of ticks in ``[best, worst]``: ``exec`` starts
  it, ``end`` (``M.S:end_<state>``) ends it, after which the activity moves on;
* codels that use the same port, or IDS members GenoM3 would not let them use
  at once, take a ``Lock`` of ``platform`` at ``exec`` and give it back at
  ``end``: a codel waits, holding its core, while another holds the lock;
* a period closes when every activity of the task is quiet (no codel to run),
  which a blocked codel is not;
* urgency is priority too: time (``tick``) may not pass while a grant, a
  codel start, a period's closing or a report is possible.

docs/verification/platform.md (*The platform*) says what each choice models and why.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from genom2bip import ir
from genom2bip.build import library
from genom2bip.build.assembly import End, Rank, Wire
from genom2bip.build.names import ident
from genom2bip.platform import LOWEST_PRIORITY, Interval, Platform
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

#: Port type of a core scheduler's ``exec``: the codel's execution time ``[lo, hi]`` in ticks.
INTERVAL = "Interval"
#: Where the platform's atoms live: one compound under the functional level.
PLATFORM = "platform"
#: The time left to the deadline of a task without period (EDF): later than any periodic task's.
NO_DEADLINE = 1 << 30


def interval_port_type() -> PortType:
    return PortType(INTERVAL, [DataParam("int", "lo"), DataParam("int", "hi")])


def scheduler_type(core: bool, keep_core: bool) -> AtomType:
    """A task's scheduler on the platform: SLEEP, READY (waiting for a core), RUN, BUSY (a codel runs).

    ``core`` false: the control task, which runs beside the cores (SLEEP, RUN,
    BUSY).  ``keep_core``: the core stays granted from one codel to the next
    (cooperative EDF); otherwise each codel's end gives it back (fixed priority,
    non-preemptive at codel boundaries).  A codel runs ``x`` ticks, ending at
    any ``x`` in ``[lo, hi]``: ``done`` needs ``x >= lo`` and time stops at ``hi``.
    Under EDF (``keep_core``), while READY, ``x`` counts the ticks since the
    period opened: the time left to the deadline is the period less ``x``
    (the EDF ranks' guards, ``time_left``), below 0 once the deadline has
    passed, so that of two overdue tasks the one whose deadline passed first
    goes first.  ``x`` is not capped there: it grows as long as the task waits.
    """
    x, lo, hi = Var("x"), Var("lo"), Var("hi")
    clear = [Assign(x, Const(0)), Assign(lo, Const(0)), Assign(hi, Const(0))]
    places = ["SLEEP", "READY", "RUN", "BUSY"] if core else ["SLEEP", "RUN", "BUSY"]
    ports = [PortDecl(library.PORT, "period", exported=True)]
    transitions = [Transition("period", ["SLEEP"], ["READY" if core else "RUN"], action=[Assign(x, Const(0))])]
    if core:
        ports += [PortDecl(library.PORT, "grant", exported=True), PortDecl(library.PORT, "rest", exported=True)]
        transitions += [Transition("grant", ["READY"], ["RUN"]), Transition("rest", ["READY"], ["SLEEP"])]
    ports += [PortDecl(INTERVAL, "exec", ["lo", "hi"], exported=True), PortDecl(library.PORT, "done", exported=True),
              PortDecl(library.PORT, "sleep", exported=True), PortDecl(library.PORT, "tick", exported=True)]
    after = "RUN" if keep_core or not core else "READY"
    transitions += [
        Transition("exec", ["RUN"], ["BUSY"], action=[Assign(x, Const(0))]),
        Transition("done", ["BUSY"], [after], guard=Binary(">=", x, lo), action=clear),
        Transition("sleep", ["RUN"], ["SLEEP"]),
    ]
    edf = core and keep_core
    transitions += [Transition("tick", [p], [p]) for p in places if p != "BUSY" and not (edf and p == "READY")]
    if edf:
        transitions.append(Transition("tick", ["READY"], ["READY"], action=[Assign(x, Binary("+", x, Const(1)))]))
    transitions.append(Transition("tick", ["BUSY"], ["BUSY"], guard=Binary("<", x, hi),
                                  action=[Assign(x, Binary("+", x, Const(1)))]))
    name = ("CoreScheduler" if keep_core else "CodelScheduler") if core else "ControlScheduler"
    return AtomType(
        name=name,
        annotations=[Annotation("scheduler", {"period": "period", "exec": "exec", "sleep": "sleep"})],
        data=[DataDecl("int", "x", annotations=[library.CLOCK], exported=edf),
              DataDecl("int", "lo"), DataDecl("int", "hi")],
        ports=ports,
        places=places,
        initial=InitialTransition(["SLEEP"], clear),
        transitions=transitions,
    )


def suspending_type(t: AtomType, on_grant: bool = False) -> AtomType:
    """Scheduler ``t`` that waits ``[s_lo, s_hi]`` ticks (SUSPENDED) after each release, before it asks for a core;
    ``on_grant``: once granted its core, before its first codel, keeping the core (the artefact's delay).

    After a release, ``x`` counts from the release through the suspension and on while READY, so an EDF
    deadline stays a period after the release.  ``back`` (the suspension's end) is not urgent: time stops at
    ``s_hi``, as it does for a codel's end.
    """
    x, lo, hi = Var("x"), Var("s_lo"), Var("s_hi")
    step = next(tr for tr in t.transitions if tr.port == ("grant" if on_grant else "period"))
    wait = Transition("tick", ["SUSPENDED"], ["SUSPENDED"], guard=Binary("<", x, hi),
                      action=[Assign(x, Binary("+", x, Const(1)))])
    transitions = [Transition(step.port, list(step.sources), ["SUSPENDED"], action=[Assign(x, Const(0))]),
                   Transition("back", ["SUSPENDED"], list(step.targets), guard=Binary(">=", x, lo)), wait]
    ready = [tr for tr in t.transitions if tr.port == "tick" and tr.sources == ["READY"] and not tr.action]
    if on_grant:
        ready = []
    # a clock that stands still while READY is one the zones cannot read there (the ranks of 'back' read it)
    transitions += [Transition("tick", ["READY"], ["READY"], action=[If(Binary("<", x, hi), (
        Assign(x, Binary("+", x, Const(1))),))]) for _ in ready]
    transitions += [tr for tr in t.transitions if tr is not step and not any(tr is r for r in ready)]
    data = [DataDecl(d.type, d.name, annotations=list(d.annotations), exported=True) if d.name == "x" else d
            for d in t.data]
    return AtomType(
        name=("SuspendingOnGrant" if on_grant else "Suspending") + t.name,
        annotations=list(t.annotations),
        params=list(t.params) + [DataParam("int", "s_lo"), DataParam("int", "s_hi")],
        data=data,
        ports=list(t.ports) + [PortDecl(library.PORT, "back", exported=True)],
        places=list(t.places) + ["SUSPENDED"],
        initial=t.initial,
        transitions=transitions,
    )


def cores_type() -> AtomType:
    """The platform's cores, all alike: a count of free ones (two cores swapped are the same state)."""
    free = Var("free")
    return AtomType(
        name="Cores",
        params=[DataParam("int", "n")],
        data=[DataDecl("int", "free")],
        ports=[PortDecl(library.PORT, "take", exported=True), PortDecl(library.PORT, "give", exported=True)],
        places=["ON"],
        initial=InitialTransition(["ON"], [Assign(free, Var("n"))]),
        transitions=[
            Transition("take", ["ON"], ["ON"], guard=Binary(">", free, Const(0)),
                       action=[Assign(free, Binary("-", free, Const(1)))]),
            Transition("give", ["ON"], ["ON"], action=[Assign(free, Binary("+", free, Const(1)))]),
        ],
    )


def lock_type() -> AtomType:
    """A lock a codel holds from its start to its end (a port, or IDS members GenoM3 keeps exclusive)."""
    return AtomType(
        name="Lock",
        ports=[PortDecl(library.PORT, "take", exported=True), PortDecl(library.PORT, "give", exported=True)],
        places=["FREE", "HELD"],
        initial=InitialTransition(["FREE"]),
        transitions=[Transition("take", ["FREE"], ["HELD"]), Transition("give", ["HELD"], ["FREE"])],
    )


def delayed_timer_type(timer: AtomType) -> AtomType:
    """``timer`` whose first period opens at a tick in ``[first_lo, first_hi]`` (the task's ``delay``).

    The first opening is port ``first``, not ``trigger``: with ``releases: together`` the periods that open
    are above the grants (so that the policy chooses among every task released at an instant), which would
    make the first opening urgent and take the earliest offset only.
    """
    t = Var("t")
    out = AtomType(
        name="DelayedTimer",
        annotations=list(timer.annotations),
        params=list(timer.params) + [DataParam("int", "first_lo"), DataParam("int", "first_hi")],
        data=list(timer.data),
        ports=list(timer.ports) + [PortDecl(library.PORT, "first", exported=True)],
        places=["START"] + list(timer.places),
        initial=InitialTransition(["START"], [Assign(t, Const(0))]),
        transitions=[
            Transition("first", ["START"], ["PERIOD"], guard=Binary(">=", t, Var("first_lo")),
                       action=[Assign(t, Const(0))]),
            Transition("tick", ["START"], ["START"], guard=Binary("<", t, Var("first_hi")),
                       action=[Assign(t, Binary("+", t, Const(1)))]),
        ] + list(timer.transitions),
    )
    return out


# --------------------------------------------------------------------------- what runs where


@dataclass
class Codel:
    """One codel step of the model: the exec wire that starts it and what it needs."""

    wire: Wire
    component: ir.Component
    owner: str  # the task or service whose automaton runs it
    task: tuple[str, ...]  # the task compound whose scheduler runs it
    codel: ir.Codel
    service: ir.Service | None
    interval: tuple[int, int] = (0, 0)  # ticks
    locks: list[tuple[str, ...]] = field(default_factory=list)  # lock atoms


@dataclass
class TaskInfo:
    path: tuple[str, ...]
    label: str
    task: ir.Task | None  # None: the component's control task
    timer: bool
    activities: list[tuple[str, ...]] = field(default_factory=list)

    @property
    def core(self) -> bool:
        return self.task is not None


def _owner_key(codel: Codel) -> tuple[str, str, str]:
    return (codel.component.name, codel.owner, codel.codel.name)


def _ids_params(codel: ir.Codel, service: ir.Service | None) -> list[tuple[list[str], ir.Direction | None]]:
    """The IDS members a codel reads or writes, as member paths (``[]`` is the whole IDS) with directions."""
    local = {p.name for p in service.parameters} if service else set()
    local |= {m.name for m in service.locals} if service else set()
    out = []
    for p in codel.params:
        if p.source not in (None, ir.Origin.IDS):
            continue
        members = [m for m in p.path.replace("[", ".[").split(".") if m and not m.startswith("[")]
        if p.source is None and members and members[0] in local:
            continue  # a service parameter, not the IDS
        out.append((members, p.direction))
    return out


def _ids_conflict(a: list[tuple[list[str], ir.Direction | None]],
                  b: list[tuple[list[str], ir.Direction | None]]) -> bool:
    """GenoM3's rule (param_mutex): a shared member (one path a prefix of the other) that one of them writes."""
    for pa, da in a:
        for pb, db in b:
            if da == ir.Direction.IN and db == ir.Direction.IN:
                continue
            n = min(len(pa), len(pb))
            if pa[:n] == pb[:n]:
                return True
    return False


def _ports_used(codel: ir.Codel) -> list[str]:
    return list(dict.fromkeys(p.path.split(".")[0].split("[")[0] for p in codel.params if p.source == ir.Origin.PORT))


def _interrupts(a: ir.Service | None, b: ir.Service | None) -> bool:
    return a is not None and b is not None and (b.name in a.interrupts or "all" in a.interrupts)


def clique_cover(nodes: list[int], edges: set[tuple[int, int]]) -> list[list[int]]:
    """Cliques covering every edge (greedy): one lock per clique excludes exactly the pairs that conflict."""
    adj: dict[int, set[int]] = {n: set() for n in nodes}
    for u, v in edges:
        adj[u].add(v)
        adj[v].add(u)
    left = {tuple(sorted(e)) for e in edges}
    out = []
    for u, v in sorted(left):
        if (u, v) not in left:
            continue
        clique = [u, v]
        for w in sorted(adj[u] & adj[v]):
            if all(w in adj[c] for c in clique):
                clique.append(w)
        for i, a in enumerate(clique):
            for b in clique[i + 1:]:
                left.discard(tuple(sorted((a, b))))
        out.append(sorted(clique))
    return out


# --------------------------------------------------------------------------- the transformation


class PlatformBuilder:
    """Rewrites a functional level's tasks, codel steps and periods to run on ``platform``."""

    def __init__(self, level, platform: Platform, tick: int, default_wcet_us: int) -> None:
        self.level = level
        self.platform = platform
        self.tick = tick
        self.default_wcet_us = default_wcet_us
        self.asm = level.asm
        self.tasks: dict[tuple[str, ...], TaskInfo] = {}
        self.codels: list[Codel] = []
        self.urgent: list[Wire] = []  # time may not pass while one of these is possible
        self.grants: dict[tuple[str, ...], Wire] = {}
        self.rests: dict[tuple[str, ...], Wire] = {}
        self.resumes: dict[tuple[str, ...], Wire] = {}  # tasks that suspend: the end of their suspension
        self.suspend_ticks: dict[tuple[str, ...], int] = {}  # and its longest, in ticks

    # -- reading the level ----------------------------------------------------------------------
    def collect(self) -> None:
        """The tasks, their activities and every codel step, with the description they come from."""
        level = self.level
        for path, (component, task) in level.task_of.items():
            timer = path + ("timer",) in self.asm.atoms
            info = TaskInfo(path, level.task_labels[path], task, timer)
            if path + ("permanent",) in self.asm.atoms:
                info.activities.append(path + ("permanent",))
            self.tasks[path] = info
        for parts in level.services.values():
            if parts.fsm.states:
                self.tasks[parts.task].activities.append(parts.activity)
        by_activity = {parts.activity: parts for parts in level.services.values()}
        components = {c.name: c for c in level.description.components}
        for path, wires in level.task_execs.items():
            component, task = level.task_of[path]
            for w in wires:
                parts = by_activity.get(w.ends[1].atom)
                owner = parts.service.name if parts else task.name
                self.codels.append(Codel(w, components[component], owner, path, level.exec_codels[w.label],
                                         parts.service if parts else None))

    def interval(self, c: Codel) -> tuple[int, int]:
        """A codel's ``[best, worst]`` in ticks: the platform file's, else ``[best, wcet]`` (widened to ticks)."""
        given = self.platform.execution.get(_owner_key(c))
        if given is None:
            worst = self.default_wcet_us if c.codel.wcet is None else round(c.codel.wcet.seconds * 1e6)
            best = worst if self.platform.best == "wcet" else min(int(self.platform.best), worst)
            given = Interval(best, worst)
        return given.best_us // self.tick, -(-given.worst_us // self.tick)

    def locks(self) -> dict[tuple[str, ...], str]:
        """The lock atoms and which codel steps take each: ports by name, IDS members by GenoM3's rule."""
        written = {p.name for c in self.level.description.components for p in c.ports
                   if p.direction == ir.Direction.OUT}
        comments: dict[tuple[str, ...], str] = {}
        for c in self.codels:
            for port in _ports_used(c.codel):
                if port in written:
                    path = (PLATFORM, ident(f"port_{port}"))
                    c.locks.append(path)
                    comments[path] = f"port {port}: one codel at a time reads or writes it"
        for component in self.level.description.components:
            mine = [k for k, c in enumerate(self.codels) if c.component is component]
            params = {k: _ids_params(self.codels[k].codel, self.codels[k].service) for k in mine}
            edges = set()
            for i, a in enumerate(mine):
                for b in mine[i + 1:]:
                    ca, cb = self.codels[a], self.codels[b]
                    if ca.task == cb.task or _interrupts(ca.service, cb.service) or _interrupts(cb.service, ca.service):
                        continue
                    if _ids_conflict(params[a], params[b]):
                        edges.add((a, b))
            for n, clique in enumerate(clique_cover(mine, edges), 1):
                path = (PLATFORM, ident(f"ids_{component.name}_{n}"))
                names = ", ".join(sorted({f"{self.codels[k].owner}.{self.codels[k].codel.name}" for k in clique}))
                comments[path] = f"IDS of {component.name}: {names} exclude each other"
                for k in clique:
                    self.codels[k].locks.append(path)
        return comments

    # -- rewriting --------------------------------------------------------------------------------
    def apply(self) -> None:
        level, asm = self.level, self.asm
        self.collect()
        comments = self.locks()
        asm.group((PLATFORM,), "Platform", comment=f"the platform: {self.platform.describe()}")
        level.docs.setdefault("Platform", "The computer: its cores and the locks codels take.")
        level.atom_types["Cores"] = cores_type()
        level.docs.setdefault("Cores", "The platform's cores: a count of free ones; a task takes one to run.")
        self.cores = asm.atom((PLATFORM, "cores"), "Cores", [Const(self.platform.cores)])
        if comments:
            level.atom_types["Lock"] = lock_type()
            level.docs.setdefault("Lock", "A lock held by a codel from its start to its end (a port, IDS members).")
        for path in sorted(comments):
            asm.atom(path, "Lock")
        keep = self.platform.policy == "edf"
        core_type = scheduler_type(True, keep)
        level.atom_types[core_type.name] = core_type
        level.atom_types["ControlScheduler"] = scheduler_type(False, True)
        for path, info in list(self.tasks.items()):
            if not level.task_execs.get(path) and not info.timer:  # nothing ever runs there: no task at all
                asm.remove(path)
                del level.task_execs[path], self.tasks[path]
            elif level.task_execs.get(path):  # a periodic task that runs no codel keeps its idle scheduler
                scheduler = asm.atoms[path + ("scheduler",)]
                scheduler.type = core_type.name if info.core else "ControlScheduler"
        self.suspensions(core_type)
        self.activities()
        for c in self.codels:
            c.interval = self.interval(c)
            self.codel_step(c)
        for path, info in self.tasks.items():
            if level.task_execs.get(path):
                self.periods(info)
        self.delays()
        self.policy()
        # A period ends when its activities are quiet, which covers 'no codel can run': the untimed ranks go.
        sleeps = {id(w) for w in asm.wires if w.label and w.label.endswith(":sleep")}
        asm.ranks = [r for r in asm.ranks if id(r.low) not in sleeps]

    def suspensions(self, core_type: AtomType) -> None:
        """Tasks that suspend (``suspend``): a suspending scheduler, and ``back`` that queues them for a core."""
        level, asm = self.level, self.asm
        for path, info in self.tasks.items():
            settings = self.platform.tasks.get((level.task_of[path][0], info.task.name)) if info.task else None
            if settings is None or settings.suspend is None or not level.task_execs.get(path) or not info.core:
                continue
            on_grant = settings.suspend_after == "grant"
            name = ("SuspendingOnGrant" if on_grant else "Suspending") + core_type.name
            if name not in level.atom_types:
                level.atom_types[name] = suspending_type(core_type, on_grant)
                level.docs.setdefault(name, "A task's scheduler that suspends after each release " + (
                    "once granted its core, keeping it," if on_grant else "") + " before it runs its codels "
                    "(the platform's 'suspend').")
            scheduler = asm.atoms[path + ("scheduler",)]
            scheduler.type = name
            lo, hi = settings.suspend.best_us // self.tick, -(-settings.suspend.worst_us // self.tick)
            scheduler.args = list(scheduler.args) + [Const(lo), Const(hi)]
            ends = [End(path + ("scheduler",), "back")]
            self.resumes[path] = asm.wire(Wire(level._rendezvous(ends), ends, "back", path, f"{info.label}:back",
                                               comment=f"the task asks for a core after its suspension, "
                                                       f"{settings.suspend}"))
            if not on_grant:  # a task suspended with its core is not waiting for one: no grant waits for it
                self.suspend_ticks[path] = hi

    def activities(self) -> None:
        """Every activity: a codel runs between ``exec_<q>`` and ``end_<q>``; ``quiet`` where no codel can run."""
        level = self.level
        done = set()
        for info in self.tasks.values():
            for path in info.activities:
                name = self.asm.atoms[path].type
                if name in done:
                    continue
                done.add(name)
                level.atom_types[name] = self.activity_type(level.atom_types[name], not info.timer)

    @staticmethod
    def activity_type(t: AtomType, work: bool) -> AtomType:
        """``t`` with its codel steps split in two (start, end) and ``quiet`` (and, timer-less, ``work``) ports."""
        codel_places = [tr.sources[0] for tr in t.transitions if tr.port and tr.port.startswith("exec_")]
        transitions = []
        places = list(t.places)
        ports = list(t.ports)
        for p in t.ports:  # a codel no run reaches keeps its port, and gets an end port beside it
            if p.name.startswith("exec_"):
                ports.append(PortDecl(library.PORT, "end_" + p.name[len("exec_"):], exported=True))
        for tr in t.transitions:
            if tr.port and tr.port.startswith("exec_"):
                running = tr.sources[0] + "_RUN"
                places.append(running)
                transitions.append(Transition(tr.port, tr.sources, [running], tr.guard, tr.action,
                                              annotations=list(tr.annotations)))
                end = "end_" + tr.port[len("exec_"):]
                transitions.append(Transition(end, [running], list(tr.targets), annotations=list(tr.annotations)))
            else:
                transitions.append(tr)
        yields = {p for p in places if p.endswith("_YIELD")}
        quiet = [p for p in places if p not in codel_places and p not in yields and not p.endswith("_RUN")]
        ports.append(PortDecl(library.PORT, "quiet", exported=True))
        transitions += [Transition("quiet", [p], [p]) for p in quiet]
        if work:  # a task without period opens one when an activity has a codel to run, or is paused
            ports.append(PortDecl(library.PORT, "work", exported=True))
            ready = codel_places + [p for p in places if p.endswith("_PAUSED")]
            transitions += [Transition("work", [p], [p]) for p in ready]
        return AtomType(name=t.name, data=list(t.data), ports=ports, places=places, initial=t.initial,
                        transitions=transitions, params=list(t.params), annotations=list(t.annotations))

    def codel_step(self, c: Codel) -> None:
        """``exec_<q>`` starts the codel (scheduler told its interval, locks taken); ``end_<q>`` ends it."""
        level, w = self.level, c.wire
        scheduler, activity = w.ends[0], w.ends[1]
        writes = [e for e in w.ends[2:] if isinstance(e, End) and e.port == "write"]
        state = w.name[len("exec_"):]
        ends = [scheduler, activity] + [End(lock, "take") for lock in c.locks]
        lo, hi = c.interval
        names = library.param_names(len(ends))
        types = [INTERVAL] + [library.PORT] * (len(ends) - 1)
        w.type = level._connector(ConnectorType(
            name=f"Run{lo}_{hi}_{len(ends)}",
            params=[ConnectorParam(t, n) for t, n in zip(types, names)],
            define=DefineGroup([DefinePort(n) for n in names]),
            interactions=[InteractionSpec(names, down=[Assign(PortData(names[0], "lo"), Const(lo)),
                                                        Assign(PortData(names[0], "hi"), Const(hi))])],
        ))
        w.ends = ends
        w.comment = (w.comment or "") + f" ({lo}..{hi} ticks" + (", locks " + ", ".join(lk[-1] for lk in c.locks)
                                                               if c.locks else "") + ")"
        end_ends = [End(scheduler.atom, "done"), End(activity.atom, f"end_{state}")]
        end_ends += [End(lock, "give") for lock in c.locks] + writes
        if self.tasks[c.task].core and self.platform.policy != "edf":
            end_ends.append(End(self.cores, "give"))
        prefix = w.label.rsplit(":", 1)[0]
        self.asm.wire(Wire(level._rendezvous(end_ends), end_ends, f"end_{state}", w.owner, f"{prefix}:end_{state}",
                           comment=f"codel {c.codel.name} ends", annotations=list(w.annotations)))
        self.urgent.append(w)

    def periods(self, info: TaskInfo) -> None:
        """Grant, closing (when every activity is quiet) and, without a timer, opening when there is work."""
        level, asm = self.level, self.asm
        scheduler = info.path + ("scheduler",)
        quiet = [End(a, "quiet") for a in info.activities]
        timer = [End(info.path + ("timer",), "sleep")] if info.timer else []
        label = info.label
        sleep = next(w for w in asm.wires if w.label == f"{label}:sleep")
        ends = timer + [End(scheduler, "sleep")] + quiet + ([End(self.cores, "give")] if info.core else [])
        sleep.ends, sleep.type = ends, level._rendezvous(ends)
        self.urgent.append(sleep)
        if info.core:
            rest_ends = timer + [End(scheduler, "rest")] + quiet
            rest = asm.wire(Wire(level._rendezvous(rest_ends), rest_ends, "rest", info.path, f"{label}:sleep",
                                 comment="a period with nothing to run closes without a core",
                                 annotations=list(sleep.annotations)))
            grant_ends = [End(scheduler, "grant"), End(self.cores, "take")]
            grant = asm.wire(Wire(level._rendezvous(grant_ends), grant_ends, "grant", info.path, f"{label}:grant",
                                  comment="a core runs the task", annotations=list(sleep.annotations)))
            self.grants[info.path] = grant
            self.rests[info.path] = rest
            asm.rank(Rank(f"{'_'.join(info.path)}_grant_after_rest", grant, rest, owner=(),
                          comment="a period with nothing to run takes no core"))
            self.urgent += [rest, grant]
        if not info.timer:  # one opening per activity, when that activity has work
            opening = next(w for w in asm.wires if w.label == f"{label}:period")
            wakes = [e for e in opening.ends[1:] if isinstance(e, End) and e.port == "wake"]
            asm.wires.remove(opening)
            for a in info.activities:
                ends = [End(scheduler, "period"), End(a, "work")] + wakes
                w = asm.wire(Wire(level._connector(library.triggered_type(2, len(wakes))), ends,
                                  f"period_{a[-1] if a[-1] != 'activity' else a[-2]}", info.path, f"{label}:period",
                                  comment="the task runs as soon as an activity has work",
                                  annotations=list(opening.annotations)))
                self.urgent.append(w)

    def delays(self) -> None:
        """A task's ``delay`` (or the platform's): its first period opens at a tick of the interval."""
        level = self.level
        for path, info in self.tasks.items():
            if info.task is None or not info.timer:
                continue
            component = level.task_of[path][0]
            settings = self.platform.tasks.get((component, info.task.name))
            delay = settings.delay if settings and settings.delay else None
            if delay is None and info.task.delay is not None:
                us = round(info.task.delay.seconds * 1e6)
                delay = Interval(us, us)
            if delay is None or delay.worst_us == 0:
                continue
            timer = self.asm.atoms[path + ("timer",)]
            if "DelayedTimer" not in level.atom_types:
                level.atom_types["DelayedTimer"] = delayed_timer_type(level.atom_types[timer.type])
            timer.type = "DelayedTimer"
            timer.args += [Const(delay.best_us // self.tick), Const(-(-delay.worst_us // self.tick))]
            regular = next(w for w in self.asm.wires if w.label == f"{info.label}:period")
            ends = [End(e.atom, "first") if e == End(path + ("timer",), "trigger") else e for e in regular.ends]
            self.asm.wire(Wire(regular.type, ends, "first_period", regular.owner, regular.label,
                               comment=f"the first period opens after the task's delay, {delay}",
                               annotations=list(regular.annotations)))

    def policy(self) -> None:
        """The scheduling policy as priorities between the grants of the tasks that wait for a core.

        ``releases: together`` (the default): every period that opens at an
        instant opens before a core is granted at that instant, so the policy
        chooses among all the tasks released then, as when one timer interrupt
        wakes them all.  ``one-by-one``: nothing orders the releases and the
        grants of one instant, so a task whose release is seen first may take a
        free core before another released at the same instant is queued (the
        anchor's UPPAAL model, where a task enters the queue and is granted a
        core before the next timer of that instant fires).
        """
        tasks = [i for i in self.tasks.values() if i.path in self.grants]
        if self.platform.releases == "together":
            self.releases_first(tasks)
        self.rests_first(tasks)
        if self.platform.policy == "edf":
            left = {i.path: self.time_left(i) for i in tasks}
            for a in tasks:
                for b in tasks:
                    if a is b:
                        continue
                    self.asm.rank(Rank(f"{'_'.join(a.path)}_after_{'_'.join(b.path)}", self.grants[a.path],
                                       self.grants[b.path], owner=(), guard=Binary("<", left[b.path], left[a.path]),
                                       comment=f"EDF: {b.label} first when its deadline is earlier"))
            return
        prio = {i.path: self.priority(i) for i in tasks}
        for a in tasks:
            for b in tasks:
                if prio[b.path] < prio[a.path]:
                    self.asm.rank(Rank(f"{'_'.join(a.path)}_after_{'_'.join(b.path)}", self.grants[a.path],
                                       self.grants[b.path], owner=(),
                                       comment=f"fixed priority: {b.label} ({prio[b.path]}) before "
                                               f"{a.label} ({prio[a.path]})"))

    def rests_first(self, tasks: list[TaskInfo]) -> None:
        """A period with nothing to run closes before any core is granted at its instant."""
        for i in tasks:
            for j in tasks:
                if i is not j:
                    self.asm.rank(Rank(f"{'_'.join(i.path)}_grant_after_{'_'.join(j.path)}_rest", self.grants[i.path],
                                       self.rests[j.path], owner=(),
                                       comment="a period with nothing to run closes before a core is granted"))

    def releases_first(self, tasks: list[TaskInfo]) -> None:
        """Every grant waits for the periods that open at its instant (a delayed first one once it must)."""
        firsts = {id(w) for w in self.asm.wires if any(isinstance(e, End) and e.port == "first" for e in w.ends)}
        openings = [w for i in tasks if i.timer for w in self.asm.wires
                    if w.label == f"{i.label}:period" and id(w) not in firsts]
        for i in tasks:
            for w in openings:
                name = f"{'_'.join(i.path)}_grant_after_{'_'.join(w.owner)}_{w.name}"
                self.asm.rank(Rank(name, self.grants[i.path], w, owner=(),
                                   comment="the tasks released at an instant are all there to choose from"))
        for path, w in ((p, w) for p, w in self.resumes.items() if p in self.suspend_ticks):  # once it must end
            forced = Binary(">=", self.asm.expose(path + ("scheduler",), "x"), Const(self.suspend_ticks[path]))
            for i in tasks:
                name = f"{'_'.join(i.path)}_grant_after_{'_'.join(path)}_back"
                self.asm.rank(Rank(name, self.grants[i.path], w, owner=(), guard=forced,
                                   comment="a suspension that can last no longer ends before a core is granted"))
        for w in (w for w in self.asm.wires if id(w) in firsts):  # a first release: at the latest instant of its delay
            timer = next(e.atom for e in w.ends if isinstance(e, End) and e.port == "first")
            forced = Binary(">=", self.exposed_t(timer), self.asm.atoms[timer].args[-1])
            for i in tasks:
                name = f"{'_'.join(i.path)}_grant_after_{'_'.join(w.owner)}_{w.name}"
                self.asm.rank(Rank(name, self.grants[i.path], w, owner=(), guard=forced,
                                   comment="a first release that can wait no longer is there to choose from"))

    def exposed_t(self, timer: tuple[str, ...]):
        """A timer's clock ``t`` read at the root (the rank of a delayed first release reads it there)."""
        inst = self.asm.atoms[timer]
        for name in {inst.type, "Timer"} & set(self.level.atom_types):
            for d in self.level.atom_types[name].data:
                d.exported = d.exported or d.name == "t"
        return self.asm.expose(timer, "t")

    def priority(self, info: TaskInfo):
        component = self.level.task_of[info.path][0]
        settings = self.platform.tasks.get((component, info.task.name))
        if settings and settings.priority is not None:
            return settings.priority
        return info.task.priority if info.task.priority is not None else LOWEST_PRIORITY

    def period_ticks(self, info: TaskInfo) -> int:
        """The task's period in ticks (0 for a task without period)."""
        return self.asm.atoms[info.path + ("timer",)].args[1].value if info.timer else 0  # Timer(period_us, ticks)

    def time_left(self, info: TaskInfo):
        """Ticks to the task's deadline, a period after its period opened: ``p - x`` of its READY scheduler.

        A period that opens late (its release came while the previous one ran) gets a whole period from its
        opening, as in the anchor's EDF, whose queue counts a task's waiting time from when it enters.
        """
        if not info.timer:
            return Const(NO_DEADLINE)
        return Binary("-", Const(self.period_ticks(info)), self.asm.expose(info.path + ("scheduler",), "x"))


def apply(level, platform: Platform, tick: int, default_wcet_us: int) -> list[Wire]:
    """Put ``level``'s tasks on ``platform``; returns the wires time may not pass by (their ``tick`` ranks)."""
    builder = PlatformBuilder(level, platform, tick, default_wcet_us)
    builder.apply()
    return builder.urgent
