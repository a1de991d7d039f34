"""A central controller (R2C style) for the same rules, to compare with the connectors genom2bip synthesises.

Instead of guarding each trigger with the status ports of the services its
rules read, one atom ``r2c`` tracks the status of every service the rules
read (it takes part in their trigger and report interactions) and decides,
in guards of its own transitions, whether a request is accepted or refused by
which rule.  The rest of the model (services, tasks, interruptions) is built
as genom2bip builds it.
"""
from __future__ import annotations

from genom2bip.build import library
from genom2bip.build.assembly import End, Wire
from genom2bip.build.functional import FunctionalLevel
from genom2bip.build.names import ident
from genom2bip.rules import GUARD_KINDS, Rule
from runtime.model import (
    Annotation,
    Assign,
    AtomType,
    Const,
    DataDecl,
    InitialTransition,
    PortDecl,
    Transition,
    Unary,
    Var,
)
from runtime.model.expressions import Expr

REPORTS = {"finish": True, "fail": False, "interrupted": False, "reject": False}


def _var(field: str, ref: tuple[str, str]) -> str:
    return f"{field}_{ident(ref[0])}_{ident(ref[1])}"


def _condition(rule: Rule) -> Expr:
    terms: list[Expr] = []
    for o in rule.others:
        v = Var(_var(rule.status_field, o))
        terms.append(Unary("!", v) if rule.negated else v)
    return library.conjunction(terms)


class CentralLevel(FunctionalLevel):
    """The functional level with every guard rule checked by one central atom."""

    def _triggers(self) -> None:
        rules = [r for r in self.rules if r.kind in GUARD_KINDS]
        tracked = sorted({o for r in rules for o in r.others})
        ports: list[PortDecl] = []
        transitions: list[Transition] = []
        data = [DataDecl("bool", _var(f, t)) for t in tracked for f in library.STATUS_FIELDS]

        def port(name: str, guard: Expr | None = None, action=None) -> str:
            ports.append(PortDecl(library.PORT, name, exported=True))
            transitions.append(Transition(name, ["READY"], ["READY"], guard=guard, action=action or []))
            return name

        central = ("r2c",)
        accept: dict[tuple[str, str], str] = {}
        refuse: dict[tuple[str, str], list[tuple[Rule, str]]] = {}
        for key in self.services:
            mine = [r for r in rules if r.service == key]
            track = [Assign(Var(_var("running", key)), Const(True))] if key in tracked else []
            if mine or track:
                accept[key] = port(f"accept_{ident(key[0])}_{ident(key[1])}",
                                   library.conjunction([_condition(r) for r in mine]) if mine else None, track)
            for r in mine:
                if r.on_violation == "reject":
                    name = port(f"refuse_{ident(key[0])}_{ident(key[1])}_{ident(r.id)}", Unary("!", _condition(r)))
                    refuse.setdefault(key, []).append((r, name))
        reports: dict[tuple[tuple[str, str], str], str] = {}
        for t in tracked:
            for report, ok in REPORTS.items():
                action = [Assign(Var(_var("running", t)), Const(False))]
                if report != "reject":
                    action.append(Assign(Var(_var("ok", t)), Const(ok)))
                if ok:
                    action.append(Assign(Var(_var("done", t)), Const(True)))
                reports[(t, report)] = port(f"{report}_{ident(t[0])}_{ident(t[1])}", None, action)
        self.asm.atom(central, self._atom_type(AtomType(
            "R2C", data=data, ports=ports, places=["READY"],
            initial=InitialTransition(["READY"], [Assign(Var(d.name), Const(False)) for d in data]),
            transitions=transitions)))

        controls = {parts.control: key for key, parts in self.services.items()}
        for w in list(self.asm.wires):  # ... and the cancellation of a request accepted but not started
            for i, e in enumerate(w.ends):
                if isinstance(e, End) and e.port == "cancel" and controls.get(e.atom) in tracked:
                    key = controls[e.atom]
                    seen = [End(central, reports[(key, "reject")])]  # same bookkeeping: ended, not ok
                    inner = Wire(self._rendezvous([e] + seen, exported=True), [e] + seen, f"cancel_{key[1]}",
                                 self.services[key].path)
                    self.asm.wires.append(inner)
                    w.ends[i] = inner
        for w in self.asm.wires:  # the central controller observes the reports of the services it tracks
            if w.label and ":" in w.label:
                module, rest = w.label.split(".", 1)
                service, kind = rest.split(":")
                key = (module, service)
                if (key, kind) in reports:
                    w.ends.append(End(central, reports[(key, kind)]))
                    w.type = self._rendezvous(w.ends)

        for key, parts in self.services.items():
            request = End((ident(key[0]), "requests"), ident(key[1]))
            ends = [request, End(parts.control, "trigger")]
            if key in accept:
                ends.append(End(central, accept[key]))
            self.asm.wire(Wire(self._rendezvous(ends), ends, "trigger", parts.path, f"{parts.label}:trigger"))
            for rule, name in refuse.get(key, []):
                rends = [request, End(parts.control, "refuse"), End(central, name)]
                self.asm.wire(Wire(self._rendezvous(rends), rends, f"refuse_{ident(rule.id)}", parts.path,
                                   f"{parts.label}:refuse", annotations=[Annotation("rule", {"name": rule.id})]))
