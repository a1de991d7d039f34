"""A TChecker network as the timed BIP model the zone engine explores (runtime/zones/model.py's fragment).

* each process is an atom: a place per location, a port per edge whose
  transition carries the edge's clock guard, the clock part of its target's
  invariant and its clock resets; the process's clocks are its data annotated
  ``@tick_clock``; a ``tick`` transition from each location that is neither
  urgent nor committed, guarded by the invariant, advances them;
* the integer variables live in one atom, ``Globals``, with a port per global
  edge that reads or writes them: its transition carries the integer guards,
  the assignments in order (a sync vector's edges in the order it lists
  them), and the bounds every assigned variable must stay
  within (TChecker does not take an edge that would leave them);
* every global edge (an asynchronous edge, or one edge per process of a sync
  vector) is a rendezvous connector of those ports; one ``tick`` rendezvous
  joins every process: time passes for all or for none;
* a weak constraint ``p@e?`` is met by one of p's ``e`` edges, or by p's
  ``absent`` port, a self-loop of each location no ``e`` edge leaves: p takes
  part whenever it has an ``e`` edge where it is, as TChecker instantiates it;
* committed locations: ``Globals`` counts the processes in one, and a global
  edge with no committed source waits for the count to be zero.

Clock constants are multiplied by the time grid ``scale`` (1 unless strict
constraints are read on a grid): ``x < c`` becomes ``x <= scale*c - 1``.
"""
from __future__ import annotations

import itertools
import re
from dataclasses import dataclass, field

from runtime.model import (
    Annotation,
    Assign,
    AtomType,
    Binary,
    ComponentInstance,
    CompoundType,
    Const,
    ConnectorParam,
    ConnectorType,
    DataDecl,
    DefineGroup,
    DefinePort,
    InitialTransition,
    Package,
    PortDecl,
    PortType,
    Transition,
    Unary,
    Var,
)
from runtime.model.priorities import PortRef
from runtime.tchecker.syntax import Node
from runtime.tchecker.system import ClockBound, Edge, System

PORT = "Port"
GLOBALS = "Globals"
COMMITTED = "committed__"
ROOT = "Net()"
UNUSED = "unused_clock__"


@dataclass
class Translation:
    package: Package
    root: str
    scale: int
    atoms: dict[str, str]  # process -> atom instance
    places: dict[tuple[str, str], str]  # (process, location) -> place
    labels: dict[str, set[tuple[str, str]]] = field(default_factory=dict)  # label -> {(atom, place)}
    edges: int = 0  # global edges (connectors besides tick)
    variables: dict[str, str] = field(default_factory=dict)  # integer variable -> its name in Globals


def _ident(name: str, taken: set[str]) -> str:
    base = re.sub(r"[^A-Za-z0-9_]", "_", name)
    if not re.match(r"[A-Za-z_]", base):
        base = "_" + base
    out, k = base, 1
    while out in taken:
        k += 1
        out = f"{base}_{k}"
    taken.add(out)
    return out


def translate(system: System, scale: int = 1, keep_integers: bool = False) -> Translation:
    """The package and root of ``system``, clock constants times ``scale``.  ``keep_integers``: every integer
    variable is kept in every state (exported), where the explorer would reset one no guard reads any more."""
    return _Builder(system, scale, keep_integers).build()


class _Builder:
    def __init__(self, system: System, scale: int, keep_integers: bool) -> None:
        self.s, self.scale, self.keep = system, scale, keep_integers
        taken = {GLOBALS}
        self.atoms = {p: _ident(p, taken) for p in system.processes}
        self.places: dict[tuple[str, str], str] = {}
        for p in system.processes.values():
            names: set[str] = set()
            for loc in p.locations:
                self.places[(p.name, loc)] = _ident(loc, names)
        self.clock_names: dict[str, str] = {}
        for p in system.processes.values():
            taken: set[str] = {UNUSED}
            self.clock_names.update({c: _ident(c, taken) for c in p.clocks})
        names = {COMMITTED}
        self.vars = {v: _ident(v, names) for v in system.ints}
        self.committed = any(loc.committed for p in system.processes.values() for loc in p.locations.values())

    # -- clocks -----------------------------------------------------------------------------------
    def bound(self, b: ClockBound) -> tuple[str, int]:
        """``clock op bound`` as a non-strict comparison of scaled integers."""
        v = b.bound * self.scale
        return {"<": ("<=", v - 1), ">": (">=", v + 1)}.get(b.op, (b.op, v))

    def clock_guard(self, edge: Edge) -> list | None:
        """The edge's clock guard and its target's invariant after the resets (None: never satisfiable)."""
        parts = []
        resets = dict(edge.resets)
        target = self.s.processes[edge.process].locations[edge.target]
        for b in edge.clocks:
            op, v = self.bound(b)
            parts.append(Binary(op, Var(self.clock_var(b.clock)), Const(v)))
        for b in target.invariant:
            op, v = self.bound(b)
            if b.clock in resets:
                if not _holds(resets[b.clock] * self.scale, op, v):
                    return None
                continue
            parts.append(Binary(op, Var(self.clock_var(b.clock)), Const(v)))
        return parts

    def clock_var(self, clock: str) -> str:
        return self.clock_names[clock]

    # -- atoms ------------------------------------------------------------------------------------
    def process_type(self, name: str) -> AtomType:
        p = self.s.processes[name]
        mine = [self.clock_names[c] for c in p.clocks]
        if not self.s.clocks and name == next(iter(self.s.processes)):
            mine = [UNUSED]  # the zone engine needs one clock: a finite-state model gets one no guard reads
        transitions = []
        for e in p.edges:
            guard = self.clock_guard(e)
            if guard is None:
                continue  # its target's invariant fails after its resets: TChecker never takes it
            action = [Assign(Var(self.clock_var(c)), Const(v * self.scale)) for c, v in e.resets]
            transitions.append(Transition(f"e{e.index}", [self.places[(name, e.source)]],
                                          [self.places[(name, e.target)]], _and(guard), action))
        absent = {port: ev for (q, ev), port in self.absent.items() if q == name}
        for port, ev in absent.items():  # a self-loop where no ``ev`` edge leaves: the weak constraint is not met
            for loc in p.locations.values():
                if not any(e.source == loc.name and e.event == ev for e in p.edges):
                    place = self.places[(name, loc.name)]
                    transitions.append(Transition(port, [place], [place]))
        advance = [Assign(Var(c), Binary("+", Var(c), Const(1))) for c in mine]
        for loc in p.locations.values():
            if loc.urgent or loc.committed:
                continue  # time does not pass there
            inv = []
            for b in loc.invariant:
                op, v = self.bound(b)  # "<=" : a tick needs x <= v - 1 before it, so x <= v after
                inv.append(Binary("<", Var(self.clock_var(b.clock)), Const(v)))
            transitions.append(Transition("tick", [self.places[(name, loc.name)]], [self.places[(name, loc.name)]],
                                          _and(inv), list(advance)))
        clock = Annotation("tick_clock", {})
        return AtomType(
            name=f"Process_{self.atoms[name]}",
            data=[DataDecl("int", c, annotations=[clock]) for c in mine],
            ports=[PortDecl(PORT, f"e{e.index}", exported=True) for e in p.edges]
            + [PortDecl(PORT, port, exported=True) for port in absent] + [PortDecl(PORT, "tick", exported=True)],
            places=[self.places[(name, loc)] for loc in p.locations],
            initial=InitialTransition([self.places[(name, p.initial.name)]],
                                      [Assign(Var(c), Const(0)) for c in mine]),
            transitions=transitions,
        )

    def globals_transition(self, port: str, edges: list[Edge]) -> Transition | None:
        """``Globals``' side of a global edge: integer guards, assignments, bounds, committed locations."""
        guard = [self.expr(g, boolean=True) for e in edges for g in e.guard]
        env: dict[str, object] = {}
        action = []
        for e in edges:
            for target, value in e.assigns:
                expr = self.expr(value)
                action.append(Assign(Var(self.vars[target]), expr))
                env[target] = _substitute(expr, {self.vars[k]: v for k, v in env.items()})
        for name, value in env.items():
            var = self.s.ints[name]
            guard += [Binary(">=", value, Const(var.low)), Binary("<=", value, Const(var.high))]
        if self.committed:
            locs = self.s.processes
            sources = sum(locs[e.process].locations[e.source].committed for e in edges)
            targets = sum(locs[e.process].locations[e.target].committed for e in edges)
            if not sources:
                guard.append(Binary("==", Var(COMMITTED), Const(0)))
            if targets != sources:
                action.append(Assign(Var(COMMITTED), Binary("+", Var(COMMITTED), Const(targets - sources))))
        if not guard and not action:
            return None
        return Transition(port, ["S"], ["S"], _and(guard), action)

    def expr(self, n: Node, boolean: bool = False):
        if n.op == "int":
            e = Const(n.value)
        elif n.op == "var":
            e = Var(self.vars[n.name])
        elif n.op == "neg":
            e = Unary("-", self.expr(n.args[0]))
        elif n.op == "!":
            return Unary("!", self.expr(n.args[0], boolean=True))
        elif n.op == "&&":
            return Binary("&&", self.expr(n.args[0], True), self.expr(n.args[1], True))
        elif n.op in ("==", "!=", "<", "<=", ">", ">="):
            return Binary(n.op, self.expr(n.args[0]), self.expr(n.args[1]))
        else:
            e = Binary(n.op, self.expr(n.args[0]), self.expr(n.args[1]))
        return Binary("!=", e, Const(0)) if boolean else e

    # -- the network ------------------------------------------------------------------------------
    def global_edges(self) -> list[tuple[list[Edge], list[tuple[str, str]]]]:
        """Asynchronous edges one by one, then each sync vector's tuples of edges, in the order the sync lists its
        processes (the order TChecker runs their statements in).  A weak constraint ``p@e?`` is met by one of
        p's ``e`` edges or, where p has none from its location, by p's absence: the ``(process, event)`` pairs
        of each tuple's absent processes come with it."""
        synced = {(p, ev) for sync in self.s.syncs for p, ev in sync.parts}
        out = [([e], []) for p in self.s.processes.values() for e in p.edges if (p.name, e.event) not in synced]
        for sync in self.s.syncs:
            choices = []
            for p, ev in sync.parts:
                edges: list = [e for e in self.s.processes[p].edges if e.event == ev]
                choices.append(edges + [(p, ev)] if p in sync.weak else edges)
            for t in itertools.product(*choices):
                edges = [e for e in t if isinstance(e, Edge)]
                if edges:  # a vector of weak constraints alone needs one of them met
                    out.append((edges, [e for e in t if not isinstance(e, Edge)]))
        return out

    def absent_port(self, process: str, event: str) -> str:
        """The port of ``process`` meaning "no ``event`` edge leaves my location" (a weak constraint not met)."""
        return self.absent.setdefault((process, event), f"absent{len(self.absent)}")

    def build(self) -> Translation:
        self.absent: dict[tuple[str, str], str] = {}
        global_edges = self.global_edges()
        for _, absent in global_edges:
            for p, ev in absent:
                self.absent_port(p, ev)
        types = [self.process_type(p) for p in self.s.processes]
        ports: list[PortDecl] = []
        g_transitions = []
        connectors, arities = [], set()
        for k, (edges, absent) in enumerate(global_edges):
            refs = [PortRef(self.atoms[e.process], f"e{e.index}") for e in edges]
            refs += [PortRef(self.atoms[p], self.absent_port(p, ev)) for p, ev in absent]
            t = self.globals_transition(f"g{k}", edges)
            if t is not None:
                ports.append(PortDecl(PORT, f"g{k}", exported=True))
                g_transitions.append(t)
                refs.append(PortRef(GLOBALS, f"g{k}"))
            label = ",".join(f"{e.process}@{e.event}({e.source}->{e.target})" for e in edges)
            arities.add(len(refs))
            connectors.append((f"c{k}", refs, label))
        components = [ComponentInstance(t.name, self.atoms[p]) for t, p in zip(types, self.s.processes)]
        if g_transitions:
            # each variable's declared bounds as its domain: the edges keep it there (an assignment that would leave
            # it disables the edge), and the compiled step then packs it in a field of the right width at once
            data = [DataDecl("int", self.vars[v], Const(iv.init), exported=self.keep,
                             annotations=[Annotation("domain", {"range": f"{iv.low}..{iv.high}"})])
                    for v, iv in self.s.ints.items()]
            init = [Assign(Var(self.vars[v]), Const(iv.init)) for v, iv in self.s.ints.items()]
            if self.committed:
                n = sum(p.initial.committed for p in self.s.processes.values())
                data.append(DataDecl("int", COMMITTED, Const(n)))
                init.append(Assign(Var(COMMITTED), Const(n)))
            types.append(AtomType(name="GlobalsType", data=data, ports=ports, places=["S"],
                                  initial=InitialTransition(["S"], init), transitions=g_transitions))
            components.append(ComponentInstance("GlobalsType", GLOBALS))
        tick = [PortRef(self.atoms[p], "tick") for p in self.s.processes]
        arities.add(len(tick))
        instances = [_connector(name, refs, label) for name, refs, label in connectors]
        instances.append(_connector("tick", tick, "tick"))
        compound = CompoundType("Net", components=components, connectors=instances)
        package = Package(name=_ident(self.s.name, set()), port_types=[PortType(PORT)], atom_types=types,
                          connector_types=[_rendezvous(n) for n in sorted(arities)], compound_types=[compound])
        labels: dict[str, set[tuple[str, str]]] = {}
        for p in self.s.processes.values():
            for loc in p.locations.values():
                for lab in loc.labels:
                    labels.setdefault(lab, set()).add((self.atoms[p.name], self.places[(p.name, loc.name)]))
        return Translation(package, ROOT, self.scale, dict(self.atoms), dict(self.places), labels, len(connectors),
                           dict(self.vars))


def _connector(name: str, refs: list[PortRef], label: str):
    from runtime.model import ConnectorInstance

    return ConnectorInstance(f"Sync{len(refs)}", name, refs, annotations=[Annotation("label", {"name": label})])


def _rendezvous(n: int) -> ConnectorType:
    names = [f"p{k + 1}" for k in range(n)]
    return ConnectorType(f"Sync{n}", [ConnectorParam(PORT, x) for x in names], DefineGroup([DefinePort(x)
                                                                                            for x in names]))


def _and(parts: list):
    out = None
    for p in parts:
        out = p if out is None else Binary("&&", out, p)
    return out


def _holds(v: int, op: str, b: int) -> bool:
    return {"<": v < b, "<=": v <= b, "==": v == b, ">=": v >= b, ">": v > b}[op]


def _substitute(e, env: dict):
    """``e`` with the variables of ``env`` replaced by their expressions (values after earlier assignments)."""
    if isinstance(e, Var):
        return env.get(e.name, e)
    if isinstance(e, Binary):
        return Binary(e.op, _substitute(e.left, env), _substitute(e.right, env))
    if isinstance(e, Unary):
        return Unary(e.op, _substitute(e.operand, env))
    return e
