"""A mission file as the environment of a timed model: the decisional layer's requests, in order.

``verify --timed --client MISSION.yaml`` replaces "any request at any time" by
one atom, ``client``, that plays the mission's steps (genom2bip/mission/spec.py):

* ``send: M.S`` takes part in ``M.S:trigger`` (or in a rule's ``M.S:refuse``),
  as soon as the previous step is over and its ``after`` delay has passed;
* the step is over when the request has reached what it waits for:
  ``until: queued`` at once, ``started`` at ``M.S:start`` (or a final report),
  ``final`` (the default) at its final report;
* ``wait: SECONDS`` lets that much time pass; ``await: NAME`` waits for the
  final report of the request sent ``as: NAME``.

Expectations and timeouts are not part of the model: every outcome the
codels may have is explored.  The client watches reports with ports that are
always ready, as observers do, so it never blocks what it watches; its sends
are urgent: time does not pass while one can be made.
"""
from __future__ import annotations

from dataclasses import dataclass

from genom2bip.build import library
from genom2bip.build.assembly import End, Wire
from genom2bip.build.names import ident
from genom2bip.mission.spec import Mission
from genom2bip.rules import _suggest
from runtime.diagnostics import Reporter
from runtime.model import (
    Annotation,
    Assign,
    AtomType,
    Binary,
    Const,
    DataDecl,
    InitialTransition,
    PortDecl,
    Transition,
    Unary,
    If,
    Var,
    source_annotation,
)

#: Final reports of a request that was triggered.
FINALS = ("finish", "fail", "interrupted", "reject")


@dataclass
class Client:
    """What the client adds: its atom, the wires time may not pass by, and where it takes part."""

    atom: tuple[str, ...]
    urgent: list[Wire]


def _key(target: str) -> str:
    return ident(target.replace(".", "_"))


def _delay_ticks(seconds: float, tick_us: int) -> int:
    return -(-round(seconds * 1e6) // tick_us)


def check(mission: Mission, description, reporter: Reporter) -> None:
    """Every service a mission sends exists in the description (errors at the step's line), and its inputs are
    what the controller would take (errors at ``with:``, as ``genom2bip mission`` gives them)."""
    from genom2bip.back.interface import Schemas, component_interface
    from genom2bip.mission.inputs import check_inputs

    names = sorted(f"{c.name}.{s.name}" for c in description.components for s in c.services)
    for step in mission.steps:
        if step.kind == "send" and step.target not in names:
            reporter.error(step.span, f"client: no service {step.target} in the model", _suggest(step.target, names))
    schemas = Schemas(description)
    components = {c.name: component_interface(schemas, c) for c in description.components}
    check_inputs(mission, {"components": components, "types": schemas.named}, reporter)


def client_type(mission: Mission, tick_us: int, refusable: set[str]) -> tuple[AtomType, dict[str, str]]:
    """The client automaton of ``mission`` and, per service it sends, its ``Module.Service`` name by port key.

    ``refusable``: the services a rule may refuse (they have ``M.S:refuse`` connectors).  Clock ``c``
    counts the ticks of a step that waits for time (``wait``, ``after``) and is 0 elsewhere.
    """
    services: dict[str, str] = {}
    for step in mission.steps:
        if step.kind == "send":
            services.setdefault(_key(step.target), step.target)
    named = {step.name: step.target for step in mission.steps if step.kind == "send" and step.name}
    c = Var("c")
    restart = Assign(c, Const(0))
    places, transitions = [], []
    delays: dict[str, int] = {}  # place -> the ticks it waits

    def at(k: int) -> str:
        return f"STEP{k}" if k < len(mission.steps) else "DONE"

    for k, step in enumerate(mission.steps):
        here, nxt = at(k), at(k + 1)
        places.append(here)
        src = source_annotation(step.span)
        if step.kind == "wait":  # a port, not an internal transition: a wait ends by an (urgent) interaction
            delays[here] = _delay_ticks(step.seconds, tick_us)
            transitions.append(Transition(f"waited_{k}", [here], [nxt], guard=Binary(">=", c, Const(delays[here])),
                                          action=[restart], annotations=src))
            continue
        if step.kind == "await":
            flag = Var(f"open_{ident(step.target)}")
            transitions.append(Transition(None, [here], [nxt], guard=Unary("!", flag), annotations=src))
            continue
        key = _key(step.target)
        ready = None
        if step.after:
            delays[here] = _delay_ticks(step.after, tick_us)
            ready = Binary(">=", c, Const(delays[here]))
        opened = [Assign(Var(f"open_{ident(step.name)}"), Const(True))] if step.name else []
        waiting = f"WAIT{k}"
        after_send = nxt if step.until == "queued" else waiting
        transitions.append(Transition(f"send_{key}", [here], [after_send], guard=ready, action=[restart] + opened,
                                      annotations=src))
        if step.target in refusable:
            transitions.append(Transition(f"refused_{key}", [here], [nxt], guard=ready, action=[restart],
                                          annotations=src))
        if after_send == waiting:
            places.append(waiting)
            if step.until == "started":
                transitions.append(Transition(f"started_{key}", [waiting], [nxt], action=[restart], annotations=src))
            transitions.append(Transition(f"ended_{key}", [waiting], [nxt], action=[restart], annotations=src))
    places.append("DONE")
    # A named request is open from its send to the first final report of its service.
    for name, target in named.items():
        for t in transitions:
            if t.port == f"ended_{_key(target)}":
                t.action = list(t.action) + [Assign(Var(f"open_{ident(name)}"), Const(False))]
    # Watching ports are always ready: a self-loop wherever the step does not wait on them.
    taken = {(t.port, t.sources[0]) for t in transitions if t.port}
    for key, target in services.items():
        for port in (f"started_{key}", f"ended_{key}"):
            transitions += [Transition(port, [p], [p], action=[
                Assign(Var(f"open_{ident(n)}"), Const(False)) for n, t in named.items()
                if port.startswith("ended_") and _key(t) == key]) for p in places if (port, p) not in taken]
    ports = [PortDecl(library.PORT, f"{kind}_{key}", exported=True) for key, target in services.items()
             for kind in ("send", "refused", "started", "ended") if kind != "refused" or target in refusable]
    ports += [PortDecl(library.PORT, f"waited_{k}", exported=True) for k, step in enumerate(mission.steps)
              if step.kind == "wait"]
    ports.append(PortDecl(library.PORT, "tick", exported=True))
    for p in places:
        if p in delays:
            transitions.append(Transition("tick", [p], [p], action=[
                If(Binary("<", c, Const(delays[p])), (Assign(c, Binary("+", c, Const(1))),))]))
        else:
            transitions.append(Transition("tick", [p], [p]))
    data = [DataDecl("int", "c", annotations=[library.CLOCK])] + [DataDecl("bool", f"open_{ident(n)}")
                                                                     for n in named]
    return AtomType(
        name="Client",
        annotations=[Annotation("client", {"mission": mission.name})],
        data=data,
        ports=ports,
        places=places,
        initial=InitialTransition([places[0]], [restart] + [Assign(Var(d.name), Const(False)) for d in data[1:]]),
        transitions=transitions,
    ), services


def apply(level, mission: Mission, tick_us: int, watch) -> Client:
    """Add the client of ``mission`` to ``level``: its sends join triggers and refusals, its watches the reports.

    ``watch(wire, end)`` adds a port to every interaction of a wire, as observers are added: the client's
    watching ports are always ready, its sends are not (they gate the request).
    """
    refusable = {w.label.rsplit(":", 1)[0] for w in level.asm.wires if w.label and w.label.endswith(":refuse")}
    ctype, services = client_type(mission, tick_us, refusable)
    level.atom_types[ctype.name] = ctype
    level.docs.setdefault(ctype.name, f"The decisional layer of mission {mission.name}: its requests, in order.")
    atom = level.asm.atom(("client",), ctype.name)
    sent = set(services.values())
    level.asm.wires = [w for w in level.asm.wires  # what the mission never sends is never requested
                       if not (w.label and w.label.rsplit(":", 1)[-1] in ("trigger", "refuse")
                               and w.label.rsplit(":", 1)[0] not in sent)]
    urgent: list[Wire] = []
    for port in (p.name for p in ctype.ports if p.name.startswith("waited_")):
        ends = [End(atom, port)]
        urgent.append(level.asm.wire(Wire(level._rendezvous(ends), ends, port, ("client",), "client:wait",
                                          comment="the client's wait is over")))
    for key, target in services.items():
        for w in list(level.asm.wires):
            if w.label == f"{target}:trigger":
                watch(w, End(atom, f"send_{key}"))
                urgent.append(w)
            elif w.label == f"{target}:refuse":
                watch(w, End(atom, f"refused_{key}"))
                urgent.append(w)
            elif w.label == f"{target}:start":
                watch(w, End(atom, f"started_{key}"))
            elif w.label in {f"{target}:{p}" for p in FINALS}:
                watch(w, End(atom, f"ended_{key}"))
    return Client(atom, urgent)
