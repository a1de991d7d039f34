"""The fixed part of every generated model: port types, Timer, Scheduler, Poster and connector types.

These are the paper's building blocks that do not depend on a particular
module (Fig. 7 bottom left: Timer and scheduler; posters); connector types are
made on demand by arity so that the ``.bip`` output declares only what it uses.
"""
from __future__ import annotations

from runtime.model import (
    Annotation,
    Assign,
    AtomType,
    Binary,
    Const,
    ConnectorExport,
    ConnectorParam,
    ConnectorType,
    DataDecl,
    DataParam,
    DefineGroup,
    DefinePort,
    InitialTransition,
    InteractionSpec,
    PortDecl,
    PortType,
    Transition,
    Var,
)
from runtime.model.expressions import Expr

#: A synchronisation without data.
PORT = "Port"
#: Marks the data of a timed model that count ticks: a zone explorer treats them as clocks (runtime/zones).
CLOCK = Annotation("tick_clock", {})
#: The status of a service controller: completed at least once, latest run succeeded, running now.
STATUS = "Status"
STATUS_FIELDS = ("done", "ok", "running")


def port_types() -> list[PortType]:
    return [
        PortType(PORT),
        PortType(STATUS, [DataParam("bool", f) for f in STATUS_FIELDS]),
    ]


def timer_type() -> AtomType:
    """Timer (paper Fig. 7): alternates ``trigger`` (a period starts) and ``sleep`` (it ends).

    ``period`` (µs) is a parameter so that the real-time runtime and the
    timing observers know when ``trigger`` may happen; the untimed semantics
    ignores it.  The ``@timer`` annotation tells the runtime which parameter
    and ports these are, without knowing the generator (docs/runtime.md).
    """
    return AtomType(
        name="Timer",
        annotations=[Annotation("timer", {"period": "period", "trigger": "trigger", "sleep": "sleep"})],
        params=[DataParam("int", "period")],
        ports=[PortDecl(PORT, "trigger", exported=True), PortDecl(PORT, "sleep", exported=True)],
        places=["WAIT", "PERIOD"],
        initial=InitialTransition(["WAIT"]),
        transitions=[
            Transition("trigger", ["WAIT"], ["PERIOD"]),
            Transition("sleep", ["PERIOD"], ["WAIT"]),
        ],
    )


def scheduler_type() -> AtomType:
    """Scheduler of a task: ``period`` opens a period, ``exec`` authorises one codel, ``sleep`` closes it.

    ``@scheduler`` names the ports for the runtime: a task without a timer
    opens a period only when a codel can then run (docs/runtime.md).
    """
    return AtomType(
        name="Scheduler",
        annotations=[Annotation("scheduler", {"period": "period", "exec": "exec", "sleep": "sleep"})],
        ports=[
            PortDecl(PORT, "period", exported=True),
            PortDecl(PORT, "exec", exported=True),
            PortDecl(PORT, "sleep", exported=True),
        ],
        places=["SLEEP", "RUN"],
        initial=InitialTransition(["SLEEP"]),
        transitions=[
            Transition("period", ["SLEEP"], ["RUN"]),
            Transition("exec", ["RUN"], ["RUN"]),
            Transition("sleep", ["RUN"], ["SLEEP"]),
        ],
    )


def idle_scheduler_type(scheduler: AtomType | None = None) -> AtomType:
    """``scheduler`` (by default :func:`scheduler_type`) without ``exec``: the scheduler of a task with no codel."""
    base = scheduler or scheduler_type()
    return AtomType(
        name="IdleScheduler",
        annotations=[Annotation("scheduler", {"period": "period", "sleep": "sleep"})],
        data=list(base.data),
        ports=[p for p in base.ports if p.name != "exec"],
        places=list(base.places),
        initial=base.initial,
        transitions=[t for t in base.transitions if t.port != "exec"],
    )


def unwritten_poster_type() -> AtomType:
    """A poster that no codel writes: :func:`poster_type` without ``write``."""
    base = poster_type()
    return AtomType(name="UnwrittenPoster", data=base.data, places=base.places, initial=base.initial)


def poster_type() -> AtomType:
    """Poster: ``write`` synchronises with every codel that has the port as ``port out``."""
    return AtomType(
        name="Poster",
        data=[DataDecl("bool", "written")],
        ports=[PortDecl(PORT, "write", exported=True)],
        places=["READY"],
        initial=InitialTransition(["READY"], [Assign(Var("written"), Const(False))]),
        transitions=[Transition("write", ["READY"], ["READY"], action=[Assign(Var("written"), Const(True))])],
    )


def param_names(n: int) -> list[str]:
    return [f"p{i + 1}" for i in range(n)]


def rendezvous_type(types: tuple[str, ...], exported: bool = False) -> ConnectorType:
    """All ports together or nothing; ``exported`` adds a port for use inside another connector."""
    names = param_names(len(types))
    suffix = "".join("S" if t == STATUS else "P" for t in types)
    return ConnectorType(
        name=f"{'RendezvousX' if exported else 'Rendezvous'}_{suffix}",
        params=[ConnectorParam(t, n) for t, n in zip(types, names)],
        define=DefineGroup([DefinePort(n) for n in names]),
        export=ConnectorExport(PORT, "ep") if exported else None,
    )


def triggered_type(together: int, receivers: int, exported: bool = False) -> ConnectorType:
    """``(p1 .. pk)' q1 .. qn``: the first ``together`` ports fire as one trigger, each receiver joins if it can.

    One connector instead of a rendezvous nested in a broadcast: the same
    interactions, and the engine enumerates them on its fast path.
    """
    names = param_names(together + receivers)
    head = DefineGroup([DefinePort(n) for n in names[:together]], trigger=True)
    suffix = f"{together}_{receivers}"
    return ConnectorType(
        name=f"{'TriggeredX' if exported else 'Triggered'}_{suffix}",
        params=[ConnectorParam(PORT, n) for n in names],
        define=DefineGroup([head] + [DefinePort(n) for n in names[together:]]),
        export=ConnectorExport(PORT, "ep") if exported else None,
    )


def broadcast_type(n: int, exported: bool = False) -> ConnectorType:
    """``p1' .. pn'``: any non-empty set of the ports that can, together (receivers gathered in one component)."""
    names = param_names(n)
    return ConnectorType(
        name=f"{'BroadcastX' if exported else 'Broadcast'}_{n}",
        params=[ConnectorParam(PORT, x) for x in names],
        define=DefineGroup([DefinePort(x, trigger=True) for x in names]),
        export=ConnectorExport(PORT, "ep") if exported else None,
    )


def guarded_type(name: str, types: tuple[str, ...], guard: Expr) -> ConnectorType:
    """A rendezvous whose guard reads status ports (constraints and rules)."""
    names = param_names(len(types))
    return ConnectorType(
        name=name,
        params=[ConnectorParam(t, n) for t, n in zip(types, names)],
        define=DefineGroup([DefinePort(n) for n in names]),
        interactions=[InteractionSpec(list(names), guard=guard)],
    )


def conjunction(terms: list[Expr]) -> Expr:
    """``t1 && t2 && ...`` (``true`` for no term)."""
    if not terms:
        return Const(True)
    out = terms[0]
    for t in terms[1:]:
        out = Binary("&&", out, t)
    return out
