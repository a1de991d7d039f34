"""Component invariants: the local states an atom can reach on its own, whatever its partners do.

An atom is explored alone, every port free to fire at any time: port data a
connector may write (``down``) take any value of their type.  A local state
is a marking and the variables' values; a variable whose values the analysis
cannot bound (an unknown extern result, or more than ``MAX_DISTINCT`` values
across the atom's states) is *untracked*: it is ``TOP`` everywhere.  Only
stable states count (no internal transition enabled): those are the ones a
global state can contain.  The result over-approximates the projection of
every reachable global state on the atom: it is the component invariant CI.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from runtime.codels import UNDECLARED, codel_specs
from runtime.compositional.values import TOP, Env, Evaluator, execute, truths
from runtime.engine.cexpr import coerce, default_value, evaluate
from runtime.engine.flatten import FlatAtom, FlatSystem
from runtime.model import Package

#: A tracked variable taking more values than this over the atom's states is dropped (becomes TOP).
MAX_DISTINCT = 16
#: Eager internal transitions chained longer than this in one step: the engine reports a livelock.
MAX_INTERNAL = 10000


@dataclass(frozen=True)
class Local:
    """One local state: the marking (bit i = place i) and the values of the variables (``TOP`` = unknown)."""

    marking: int
    env: Env


@dataclass
class Edge:
    """A port transition between stable local states (eager internal transitions folded in)."""

    source: int
    port: str
    target: int


@dataclass
class AtomAbstraction:
    """An atom's reachable local states (numbered), its edges, and which ports are enabled where."""

    atom: FlatAtom
    states: list[Local]
    initial: list[int]
    edges: list[Edge]
    untracked: set[str]
    certain: dict[str, set[int]] = field(default_factory=dict)  # port -> states where it is surely enabled
    possible: dict[str, set[int]] = field(default_factory=dict)  # port -> states where it may be enabled
    index: dict[Local, int] = field(default_factory=dict)

    def describe(self, k: int) -> str:
        """``ACTIVE done=true ok=false``: a local state as a reader wants it."""
        s = self.states[k]
        places = [p for i, p in enumerate(self.atom.places) if s.marking >> i & 1]
        data = [f"{d.name}={_show(v)}" for d, v in zip(self.atom.variables, s.env) if d.name not in self.untracked]
        return " ".join([",".join(places) or "(no place)"] + data)

    def port_values(self, port: str, k: int) -> tuple:
        """The values a port carries in local state k (``TOP`` for an untracked one)."""
        decl = self.atom.type.port(port)
        names = [d.name for d in self.atom.variables]
        env = self.states[k].env
        return tuple(env[names.index(x)] if x in names else TOP for x in (decl.data if decl else ()))

    def abstract(self, marking: int, values: tuple) -> int | None:
        """The local state a concrete marking and variable values fall in (None: outside the invariant)."""
        env = tuple(TOP if d.name in self.untracked else coerce(v, d.type)
                    for d, v in zip(self.atom.variables, values))
        return self.index.get(Local(marking, env))


def _show(v) -> str:
    if v is True:
        return "true"
    if v is False:
        return "false"
    return repr(v)


def extern_values(package: Package) -> dict[str, object]:
    """What each extern may return in exploration: a codel its outcomes, the environment's calls their answers."""
    out: dict[str, object] = {"request_pending": frozenset((True,)), "take_request": None}
    for name, spec in codel_specs(package).items():
        n = len(spec.outcomes)
        out[name] = frozenset(range(n)) if n else frozenset((UNDECLARED,))
    return out


def written_ports(flat: FlatSystem) -> set[int]:
    """Atom ports whose data some connector's ``down`` may write (their variables take any value)."""
    out: set[int] = set()
    for fc in flat.connectors:
        names = {p.name: i for i, p in enumerate(fc.type.params)}
        written: set[int] = set()
        for spec in fc.type.interactions:
            for stmt in spec.down:
                for target in _targets(stmt):
                    if target in names:
                        written.add(names[target])
        for i in written:
            for alt in fc.params[i]:
                if hasattr(alt, "port"):
                    out.add(alt.port)
                else:
                    out |= _under(flat, alt.connector)
    return out


def _under(flat: FlatSystem, cid: int) -> set[int]:
    out: set[int] = set()
    for alts in flat.connectors[cid].params:
        for alt in alts:
            out |= {alt.port} if hasattr(alt, "port") else _under(flat, alt.connector)
    return out


def _targets(stmt) -> list[str]:
    from runtime.model.expressions import Assign, If, PortData
    if isinstance(stmt, Assign) and isinstance(stmt.target, PortData):
        return [stmt.target.port]
    if isinstance(stmt, If):
        return [t for s in stmt.then + stmt.orelse for t in _targets(s)]
    return []


def abstract_atom(flat: FlatSystem, atom: FlatAtom, externs: dict[str, object],
                  written: set[int]) -> AtomAbstraction:
    """Explore one atom alone, dropping variables until its local states are finite and few."""
    untracked: set[str] = set()
    while True:
        result = _explore(flat, atom, externs, written, untracked)
        if isinstance(result, AtomAbstraction):
            return result
        untracked.add(result)


def _explore(flat: FlatSystem, atom: FlatAtom, externs, written: set[int], untracked: set[str]):
    t = atom.type
    names = {d.name: i for i, d in enumerate(atom.variables)}
    types = [d.type for d in atom.variables]
    constants = dict(flat.constants)
    constants.update(atom.constants)

    def make(env: Env) -> Evaluator:
        def lookup(name: str):
            k = names.get(name)
            if k is not None:
                v = env[k]
                return TOP if v is TOP else frozenset((v,))
            if name in constants:
                return frozenset((constants[name][0],))
            return TOP
        return Evaluator(lookup, externs)

    def run(body, env: Env) -> list[Env]:
        outs = execute(body, env, names, types, make)
        return [tuple(TOP if d.name in untracked else v for d, v in zip(atom.variables, e)) for e in outs]

    def mask(places: list[str]) -> int:
        return atom.place_mask(places)

    internals = [(mask(tr.sources), mask(tr.targets), tr) for tr in t.transitions if tr.internal]
    by_port: dict[str, list] = {}
    for tr in t.transitions:
        if not tr.internal:
            by_port.setdefault(tr.port, []).append((mask(tr.sources), mask(tr.targets), tr))

    def settle(marking: int, env: Env) -> set[Local]:
        """Stable states reachable by eager internal transitions."""
        out: set[Local] = set()
        seen = {Local(marking, env)}
        stack = [Local(marking, env)]
        while stack:
            cur = stack.pop()
            surely = False
            for src, dst, tr, sure in _offered(cur, internals, make):
                surely = surely or sure
                for e in run(tr.action, cur.env):
                    nxt = Local((cur.marking & ~src) | dst, e)
                    if nxt not in seen:
                        if len(seen) > MAX_INTERNAL:
                            break
                        seen.add(nxt)
                        stack.append(nxt)
            if not surely:
                out.add(cur)
        return out

    env0 = []
    for d in atom.variables:
        v = evaluate(d.init, constants, f"{atom.name}.{d.name}") if d.init is not None else default_value(d.type)
        env0.append(TOP if d.name in untracked else coerce(v, d.type))
    starts: set[Local] = set()
    init = t.initial
    for e in run(init.action if init else [], tuple(env0)):
        starts |= settle(mask(init.targets) if init else 0, e)

    states: list[Local] = []
    index: dict[Local, int] = {}

    def number(s: Local) -> int:
        k = index.get(s)
        if k is None:
            k = index[s] = len(states)
            states.append(s)
        return k

    initial = sorted(number(s) for s in starts)
    edges: list[Edge] = []
    certain: dict[str, set[int]] = {p.name: set() for p in t.ports}
    possible: dict[str, set[int]] = {p.name: set() for p in t.ports}
    port_ids = atom.ports
    done = 0
    while done < len(states):
        k = done
        done += 1
        cur = states[k]
        for port, trs in by_port.items():
            for src, dst, tr, sure in _offered(cur, trs, make):
                possible[port].add(k)
                if sure:
                    certain[port].add(k)
                env = cur.env
                pid = port_ids.get(port)
                if pid is not None and pid in written:
                    env = _free(atom, port, env)
                for e in run(tr.action, env):
                    for s in settle((cur.marking & ~src) | dst, e):
                        target = number(s)
                        edges.append(Edge(k, port, target))
        widest = _too_wide(atom, states, untracked)
        if widest is not None:
            return widest
    _atom_priorities(atom, states, certain, possible)
    return AtomAbstraction(atom, states, initial, _dedup(edges), untracked, certain, possible, index)


def _offered(cur: Local, transitions, make):
    """The transitions possibly enabled in a local state, each with whether it surely is."""
    ev = make(cur.env)
    for src, dst, tr in transitions:
        if cur.marking & src == src:
            tv = truths(ev.value(tr.guard))
            if True in tv:
                yield src, dst, tr, tv == {True}


def _free(atom: FlatAtom, port: str, env: Env) -> Env:
    """The port's variables after a connector may have written them: unknown."""
    decl = atom.type.port(port)
    names = [d.name for d in atom.variables]
    out = list(env)
    for x in decl.data if decl else ():
        if x in names:
            out[names.index(x)] = TOP
    return tuple(out)


def _too_wide(atom: FlatAtom, states: list[Local], untracked: set[str]) -> str | None:
    """A tracked variable with too many values, or one that became unknown somewhere: to drop."""
    for i, d in enumerate(atom.variables):
        if d.name in untracked:
            continue
        seen = {s.env[i] for s in states}
        if TOP in seen or len(seen) > MAX_DISTINCT:
            return d.name
    return None


def _dedup(edges: list[Edge]) -> list[Edge]:
    seen = set()
    out = []
    for e in edges:
        key = (e.source, e.port, e.target)
        if key not in seen:
            seen.add(key)
            out.append(e)
    return out


def _atom_priorities(atom: FlatAtom, states, certain, possible) -> None:
    """A port below another one of the same atom is surely enabled only where every higher port surely is not."""
    rules = atom.type.priorities
    if not rules:
        return
    ports = [p.name for p in atom.type.ports]
    above: dict[str, set[str]] = {p: set() for p in ports}
    for r in rules:
        lows = ports if r.low == "*" else [r.low]
        highs = ports if r.high == "*" else [r.high]
        for lo in lows:
            above[lo] |= {h for h in highs if h != lo}
    changed = True
    while changed:
        changed = False
        for p in ports:
            extra = set().union(*(above[q] for q in above[p])) - above[p] - {p} if above[p] else set()
            if extra:
                above[p] |= extra
                changed = True
    for p in ports:
        if above[p]:
            certain[p] = {k for k in certain[p] if not any(k in possible[q] for q in above[p])}
