"""The two atoms of a service (paper Fig. 6): its execution-task controller and its activity automaton.

Codels are extern functions that return an *outcome*: the index of the yield
they took, ``len(yields) + j`` for the ``j``-th exception the service throws,
or a negative number for a failure the description did not declare.  An
internal, eager transition per outcome then moves the activity to the target
place, so a codel step is one interaction in traces and exploration.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from genom2bip import ir
from genom2bip.build.library import PORT, STATUS, STATUS_FIELDS
from genom2bip.build.names import joined, place
from runtime.model import (
    Annotation,
    Assign,
    AtomType,
    Binary,
    Call,
    Const,
    DataDecl,
    Do,
    ExternFunction,
    InitialTransition,
    PortDecl,
    Transition,
    Unary,
    Var,
    SOURCE,
    coverable_places,
    source_annotation,
)
from runtime.diagnostics import NOWHERE, Span

ETHER, FINISHED, FAILED, INTERRUPTED = "ETHER", "FINISHED", "FAILED", "INTERRUPTED"


@dataclass
class Fsm:
    """An activity automaton read from the codels of a service or of a task's permanent activity."""

    states: list[str]
    codel_of: dict[str, ir.Codel]
    throws: list[str]
    paused: list[str] = field(default_factory=list)  # states entered through pause::

    @classmethod
    def of(cls, codels: list[ir.Codel], throws: list[str]) -> "Fsm":
        codel_of: dict[str, ir.Codel] = {}
        paused: list[str] = []
        for codel in codels:
            for t in codel.triggers:
                codel_of.setdefault(t, codel)
        states = ir.fsm_states(codels)
        for codel in codels:
            for y in codel.yields:
                if y.pause and y.state != "ether" and y.state not in paused:
                    paused.append(y.state)
        return cls(states, codel_of, list(throws), paused)

    def reachable(self, roots: list[str]) -> "Fsm":
        """The automaton without the states no run can reach from ``roots`` (BIP2 reports them as dead code).

        A task's ``stop`` codel runs when the component shuts down, which the
        model does not represent: a permanent activity starts at ``start`` only.
        """
        seen = [r for r in roots if r in self.codel_of]
        for state in seen:
            for y in self.codel_of[state].yields:
                if y.state != "ether" and y.state in self.codel_of and y.state not in seen:
                    seen.append(y.state)
        keep = [x for x in self.states if x in seen]
        return Fsm(keep, {x: c for x, c in self.codel_of.items() if x in seen}, self.throws,
                   [x for x in self.paused if x in seen])

    @property
    def has_stop(self) -> bool:
        return "stop" in self.codel_of


def exec_port(state: str) -> str:
    return f"exec_{state}"


def codel_extern(module: str, codel: ir.Codel, throws: list[str]) -> ExternFunction:
    """``extern function int NDD_nddPlan()`` annotated with the outcomes a codel may return.

    A validate codel is described with the single yield ``ok`` (outcome 0).
    """
    args = {"codel": codel.name, "yields": ",".join(str(y) for y in codel.yields), "throws": ",".join(throws)}
    if codel.wcet is not None:
        args["wcet_us"] = str(round(codel.wcet.seconds * 1e6))
    return ExternFunction(joined(module, codel.name), "int", [], [Annotation("codel", args)])


def located(transitions: list[Transition], span: Span) -> list[Transition]:
    """``transitions``, each without a line of its own given ``span``'s (the service or task whose protocol it is)."""
    for t in transitions:
        if not any(a.name == SOURCE for a in t.annotations):
            t.annotations = t.annotations + source_annotation(span)
    return transitions


def activity_type(module: str, name: str, fsm: Fsm, permanent: bool = False, origin: Span = NOWHERE,
                  abortable: bool = True) -> AtomType:
    """Activity automaton (Fig. 3): ETHER → start → codel steps → finish / fail / interrupted.

    A permanent activity (the codels of a task) starts at once and has no
    start/finish/abort ports: nobody requests it and nobody waits for it.
    ``abort`` exists when another service may interrupt this one (BIP2 warns
    about a port no connector binds).  ``origin`` is the service or task it
    models; each codel step carries the codel's line and each outcome the
    line of its yield (``@source``).
    """
    data = [DataDecl("int", "outcome"), DataDecl("bool", "aborted")]
    places = [ETHER] + [place(s) for s in fsm.states]
    places += [place(s) + "_PAUSED" for s in fsm.paused]
    places += [place(s) + "_YIELD" for s in fsm.states]
    ports: list[PortDecl] = []
    transitions: list[Transition] = []
    if not permanent:
        places += [FINISHED, FAILED, INTERRUPTED]
        ports.append(PortDecl(PORT, "start", exported=True))
        first = place("start") if "start" in fsm.codel_of else FINISHED
        transitions.append(
            Transition("start", [ETHER], [first], action=[Assign(Var("aborted"), Const(False))])
        )

    for state in fsm.states:
        codel = fsm.codel_of[state]
        ports.append(PortDecl(PORT, exec_port(state), exported=True))
        transitions.append(
            Transition(
                exec_port(state),
                [place(state)],
                [place(state) + "_YIELD"],
                action=[Assign(Var("outcome"), Call(joined(module, codel.name)))],
                annotations=source_annotation(codel.span),
            )
        )
        transitions += _outcome_transitions(state, codel, fsm, permanent)

    if fsm.paused:
        ports.append(PortDecl(PORT, "wake", exported=True))
        for s in fsm.paused:
            transitions.append(Transition("wake", [place(s) + "_PAUSED"], [place(s)]))

    if not permanent:
        for port, source in (("finish", FINISHED), ("fail", FAILED), ("interrupted", INTERRUPTED)):
            ports.append(PortDecl(PORT, port, exported=True))
            transitions.append(Transition(port, [source], [ETHER]))
    if not permanent and abortable:
        ports.append(PortDecl(PORT, "abort", exported=True))
        running = [place(s) for s in fsm.states if s != "stop"] + [
            place(s) + "_PAUSED" for s in fsm.paused if s != "stop"
        ]
        target = place("stop") if fsm.has_stop else INTERRUPTED
        for p in running:
            transitions.append(Transition("abort", [p], [target], action=[Assign(Var("aborted"), Const(True))]))

    init = place("start") if permanent and "start" in fsm.codel_of else ETHER
    places, transitions = _live(init, places, transitions)
    return AtomType(
        name=joined(module, name, "Activity"),
        data=data,
        ports=ports,
        places=places,
        initial=InitialTransition([init], [Assign(Var("outcome"), Const(0)), Assign(Var("aborted"), Const(False))]),
        transitions=located(transitions, origin),
        annotations=source_annotation(origin),
    )


def _live(init: str, places: list[str], transitions: list[Transition]) -> tuple[list[str], list[Transition]]:
    """The places a run can mark from ``init`` and the transitions leaving them (BIP2 reports the rest as dead code)."""
    seen = coverable_places([init], transitions)
    return [p for p in places if p in seen], [t for t in transitions if all(p in seen for p in t.sources)]


#: Outcome transitions leave one place with guards exclusive by construction (each pair has ``outcome == a``
#: against ``outcome == b`` or ``outcome != a``, or ``aborted`` against ``!aborted``); BIP2's analysis does
#: not read guards, so it is told (runtime.bip2.lint.exclusive checks the claim).
EXCLUSIVE = Annotation("SuppressWarning", {"nondeterminism": ""})


def _outcome_transitions(state: str, codel: ir.Codel, fsm: Fsm, permanent: bool) -> list[Transition]:
    """Eager internal transitions from ``STATE_YIELD``, one per outcome of the codel, with exclusive guards."""
    source = [place(state) + "_YIELD"]
    out: list[Transition] = []
    outcome = Var("outcome")
    spent = [Assign(outcome, Const(0))]  # read once: reset so that states differ only in what matters
    for k, y in enumerate(codel.yields):
        is_k = Binary("==", outcome, Const(k))
        at = source_annotation(y.span if y.span.line > 0 else codel.span) + [EXCLUSIVE]
        if y.state == "ether":
            if permanent:
                out.append(Transition(None, source, [ETHER], guard=is_k, action=spent, annotations=at))
            else:
                # Reaching ether after an interruption reports "interrupted", otherwise "finished".
                out.append(Transition(None, source, [FINISHED], guard=Binary("&&", is_k, Unary("!", Var("aborted"))),
                                      action=spent, annotations=at))
                out.append(Transition(None, source, [INTERRUPTED], guard=Binary("&&", is_k, Var("aborted")),
                                      action=spent, annotations=at))
        else:
            target = place(y.state) + "_PAUSED" if y.pause else place(y.state)
            out.append(Transition(None, source, [target], guard=is_k, action=spent, annotations=at))
    failed = [ETHER] if permanent else [FAILED]
    # Any other outcome (a thrown exception, or an undeclared failure): none of the yields.
    other = None
    for k in range(len(codel.yields)):
        not_k = Binary("!=", outcome, Const(k))
        other = not_k if other is None else Binary("&&", other, not_k)
    out.append(Transition(None, source, failed, guard=other, action=spent,
                          annotations=source_annotation(codel.span) + ([EXCLUSIVE] if out else [])))
    return out


def controller_type(module: str, service: ir.Service, constrained: bool, interruptible: bool = False,
                    observed: bool = True) -> AtomType:
    """Execution task of a service (Fig. 6 left): trigger → validate → reject or start → report.

    ``cancel`` exists when another service may interrupt this one: a request
    accepted but not started yet (being validated) is interrupted too, not
    left to start after the service that should have stopped it.

    ``status`` is available in every place and tells constraint connectors
    whether the service has completed (at least once / latest run) and whether
    it runs now: from the moment its request is accepted until it reports, so
    that two mutually exclusive services can never both be accepted; it exists
    when a rule reads it (``observed``).  ``reject`` exists when a validate codel may refuse the
    parameters, ``refuse`` when a constraint may refuse a request.
    """
    places = ["IDLE", "CHECK", "ACTIVE"]
    data = [DataDecl("int", "verdict")] + [DataDecl("bool", f) for f in STATUS_FIELDS]
    validate = (
        [Assign(Var("verdict"), Call(joined(module, service.validate.name)))]
        if service.validate
        else [Assign(Var("verdict"), Const(0))]
    )
    ports = [
        PortDecl(PORT, "trigger", exported=True),
        PortDecl(PORT, "start", exported=True),
        PortDecl(PORT, "finish", exported=True),
        PortDecl(PORT, "fail", exported=True),
        PortDecl(PORT, "interrupted", exported=True),
    ]
    if observed:
        ports.append(PortDecl(STATUS, "status", list(STATUS_FIELDS), exported=True))
    ended = [Assign(Var("running"), Const(False))]
    transitions = [
        Transition("trigger", ["IDLE"], ["CHECK"], action=validate + [Assign(Var("running"), Const(True))],
                   annotations=source_annotation(service.validate.span if service.validate else service.span)),
        Transition("start", ["CHECK"], ["ACTIVE"], guard=Binary("==", Var("verdict"), Const(0))),  # verdict is 0
        Transition("finish", ["ACTIVE"], ["IDLE"],
                   action=ended + [Assign(Var("done"), Const(True)), Assign(Var("ok"), Const(True))]),
        Transition("fail", ["ACTIVE"], ["IDLE"], action=ended + [Assign(Var("ok"), Const(False))]),
        Transition("interrupted", ["ACTIVE"], ["IDLE"], action=ended + [Assign(Var("ok"), Const(False))]),
    ]
    if observed:
        transitions += [Transition("status", [p], [p]) for p in places]
    if service.validate:
        ports.insert(1, PortDecl(PORT, "reject", exported=True))
        transitions.insert(1, Transition("reject", ["CHECK"], ["IDLE"], guard=Binary("!=", Var("verdict"), Const(0)),
                                         action=ended + [Assign(Var("verdict"), Const(0))]))
    if interruptible:
        ports.append(PortDecl(PORT, "cancel", exported=True))
        transitions.append(Transition("cancel", ["CHECK"], ["IDLE"], action=ended + [Assign(Var("verdict"), Const(0))]))
    if constrained:
        ports.insert(1, PortDecl(PORT, "refuse", exported=True))
        transitions.insert(1, Transition("refuse", ["IDLE"], ["IDLE"]))
    if service.interrupts_itself:
        places += ["RENEW", "HANDOVER"]
        _renewal(ports, transitions, validate, bool(service.validate), interruptible, constrained, observed)
    return AtomType(
        name=joined(module, service.name, "Control"),
        data=data,
        ports=ports,
        places=places,
        initial=InitialTransition(
            ["IDLE"], [Assign(Var(v), Const(0 if v == "verdict" else False)) for v in ("verdict",) + STATUS_FIELDS]
        ),
        transitions=located(transitions, service.span),
        annotations=source_annotation(service.span),
    )


def _renewal(ports: list[PortDecl], transitions: list[Transition], validate: list, has_validate: bool,
             interruptible: bool, constrained: bool, observed: bool) -> None:
    """A service that interrupts itself takes a new request while it runs one (GenoM3's rule, docs/runtime.md).

    ``trigger`` in ACTIVE validates the new request (RENEW); refused, the running one goes on; accepted,
    ``preempt`` aborts the running activity (HANDOVER); its end (finish, fail or interrupted, reported as
    the old request's) leads to CHECK, from where the new request starts as any other.
    """
    kept = [Assign(Var("done"), Const(True)), Assign(Var("ok"), Const(True))]
    transitions += [
        Transition("trigger", ["ACTIVE"], ["RENEW"], action=validate),
        Transition("preempt", ["RENEW"], ["HANDOVER"], guard=Binary("==", Var("verdict"), Const(0))),
    ]
    for source in ("RENEW", "HANDOVER"):  # the old request ends (by itself, or as told): the new one is next
        transitions += [Transition("finish", [source], ["CHECK"], action=kept),
                        Transition("fail", [source], ["CHECK"], action=[Assign(Var("ok"), Const(False))]),
                        Transition("interrupted", [source], ["CHECK"], action=[Assign(Var("ok"), Const(False))])]
    ports.append(PortDecl(PORT, "preempt", exported=True))
    if has_validate:
        transitions.append(Transition("reject", ["RENEW"], ["ACTIVE"], guard=Binary("!=", Var("verdict"), Const(0)),
                                      action=[Assign(Var("verdict"), Const(0))]))
    if interruptible:  # another service interrupts both: the running request is aborted, the new one cancelled
        transitions += [Transition("cancel", [p], ["ACTIVE"], action=[Assign(Var("verdict"), Const(0))])
                        for p in ("RENEW", "HANDOVER")]
    if constrained:
        transitions.append(Transition("refuse", ["ACTIVE"], ["ACTIVE"]))
    if observed:
        transitions += [Transition("status", [p], [p]) for p in ("RENEW", "HANDOVER")]


def acceptor_type(module: str, requests: list[tuple[str, str]], origin: Span = NOWHERE,
                  sources: dict[str, Span] | None = None) -> AtomType:
    """Request acceptor of a module: one port per service, enabled while a request for it is pending.

    ``requests`` pairs each port with the service's ``Module.Service`` name;
    ``request_pending("NDD.GoTo")`` is answered by the services interface at
    run time and by the environment (any request, any time) in exploration;
    ``take_request`` tells the interface the request has been consumed.
    ``origin`` is the component's span, ``sources`` each port's service span (``@source``).
    """
    ports = [PortDecl(PORT, port, exported=True) for port, _ in requests]
    transitions = [
        Transition(port, ["READY"], ["READY"], guard=Call("request_pending", (Const(name),)),
                   action=[Do(Call("take_request", (Const(name),)))],
                   annotations=source_annotation((sources or {}).get(port, NOWHERE)))
        for port, name in requests
    ]
    return AtomType(
        name=joined(module, "Requests"),
        ports=ports,
        places=["READY"],
        initial=InitialTransition(["READY"]),
        transitions=transitions,
        annotations=source_annotation(origin),
    )
