"""What each slot of a state holds, which variables are dead where, and declared finite domains.

The explorer packs states slot by slot and, by default, resets *dead*
variables to their initial default: a variable is dead in a state when no
path from it reads the variable before writing it.  States differing only in
dead variables have the same future (same interactions, same labels), so
merging them is exact for deadlocks, properties and traces, and it removes
the copies of a codel's last ``outcome`` or a validate's ``verdict`` that
otherwise multiply the state space.  The analysis is per atom, over places
(docs/verification/explorer.md, *Dead-variable reduction*); anything a priority, an atom invariant or
a property can observe is always live, and what a connector reads is live while that connector may still
fire (an atom it needs in a place from which it can still take its port).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, fields, is_dataclass
from typing import Any, Callable, Iterable

from runtime.engine.cexpr import default_value
from runtime.engine.flatten import FlatAtom, FlatSystem, Leaf
from runtime.explore.choices import ExploreError
from runtime.explore.conjunctions import dead_with
from runtime.explore.firing import connector_alive
from runtime.model.expressions import Assign, Do, If, PortData, Var, variables


@dataclass(frozen=True)
class Slot:
    """One slot of the state tuple.

    ``kind`` is ``marking`` (bit mask over ``places`` places), ``bool``,
    ``int`` or ``value`` (anything else: floats, strings, extern data), or
    ``requests`` (the environment's counts, when a request budget is set).
    ``live`` is the mask of places where the variable is live (None: always);
    ``domain`` the inclusive range an ``@domain(range="lo..hi")`` annotation
    declares.
    """

    index: int
    kind: str
    atom: str | None
    name: str
    places: int = 0
    live: int | None = None
    default: Any = None
    domain: tuple[int, int] | None = None
    marking: int | None = None  # slot of the atom's marking, for variables
    alive: tuple[tuple[int, int], ...] = ()  # also live while the marking in one of these slots meets its mask
    #: ...but not when one of these flags, read in every conjunction that reads this variable, is false and can no
    #: longer be set: ``(flag slot, its marking slot, settable)`` (runtime/explore/conjunctions.py)
    void: tuple = ()

    @property
    def never_live(self) -> bool:
        """Always the default: no bits in a packed state."""
        return self.live == 0 and not self.alive

    def live_test(self, marking: Callable[[int], str], sep: str = " || ",
                  value: Callable[[int], str] | None = None) -> str:
        """The condition under which the variable is live, in C, Python or Promela: ``marking`` names a marking
        slot's value (``lambda m: f"L[{m}]"``), ``value`` a variable's (``marking`` unless given), ``sep`` joins
        the alternatives (`` or `` for Python, whose other operators follow)."""
        if not self.void:
            return sep.join(f"({marking(m)} & {mask})" for m, mask in ((self.marking, self.live), *self.alive))
        value = value or marking
        both, no = (" and ", "not ") if sep.strip() == "or" else (" && ", "!")

        def meets(pairs) -> str:
            return both.join(f"({marking(m)} & {mask})" for m, mask in pairs)

        read = sep.join(meets([pair]) for pair in self.alive)
        gone = sep.join(f"({no}{value(g)}{both}{no}({sep.join(f'({meets(alt)})' for alt in settable) or '0'}))"
                        for g, _, settable in self.void)
        return f"({marking(self.marking)} & {self.live}){sep}(({read}){both}{no}({gone}))"

    @property
    def title(self) -> str:
        return f"{self.atom}.{self.name}" if self.atom else self.name


_DOMAIN = re.compile(r"^\s*(-?\d+)\s*\.\.\s*(-?\d+)\s*$")


def declared_domain(decl, atom: str) -> tuple[int, int] | None:
    """The ``@domain(range="lo..hi")`` of a data declaration, if any."""
    for a in decl.annotations:
        if a.name == "domain":
            text = a.arguments.get("range", "")
            m = _DOMAIN.match(str(text))
            if not m or int(m.group(1)) > int(m.group(2)):
                raise ExploreError(f"atom {atom}: @domain of {decl.name} must read range=\"lo..hi\" with lo <= hi, "
                                   f"not {text!r}")
            if decl.type != "int":
                raise ExploreError(f"atom {atom}: @domain applies to int data, {decl.name} is {decl.type}")
            return int(m.group(1)), int(m.group(2))
    return None


def _reads(e) -> set[str]:
    return variables(e) if e is not None else set()


def _body(stmts) -> tuple[set[str], set[str]]:
    """Variables a block may read before writing them, and those it writes on every path."""
    reads: set[str] = set()
    writes: set[str] = set()
    for st in stmts:
        if isinstance(st, Assign):
            reads |= _reads(st.value) - writes
            if isinstance(st.target, Var):
                writes.add(st.target.name)
        elif isinstance(st, If):
            reads |= _reads(st.cond) - writes
            r1, w1 = _body(st.then)
            r2, w2 = _body(st.orelse)
            reads |= (r1 | r2) - writes
            writes |= w1 & w2
        elif isinstance(st, Do):
            reads |= _reads(st.call) - writes
    return reads, writes


def _port_data(node, acc: set[tuple[str, str]]) -> None:
    if isinstance(node, PortData):
        acc.add((node.port, node.name))
    elif isinstance(node, (list, tuple)):
        for x in node:
            _port_data(x, acc)
    elif is_dataclass(node) and not isinstance(node, type):
        for f in fields(node):
            _port_data(getattr(node, f.name), acc)


def readers_by_connectors(flat: FlatSystem) -> dict[tuple[int, str], list[int]]:
    """For each ``(atom index, variable)`` some connector reads through a port (guard, up, or a down's values),
    the ids of those connectors."""
    out: dict[tuple[int, str], list[int]] = {}
    for fc in flat.connectors:
        acc: set[tuple[str, str]] = set()
        for spec in fc.type.interactions:
            _port_data(spec.guard, acc)
            _port_data(list(spec.up), acc)
            _port_data([st.value if isinstance(st, Assign) else st for st in spec.down], acc)
        if not acc:
            continue
        for param, alts in zip(fc.type.params, fc.params):
            for alt in alts:
                if isinstance(alt, Leaf):
                    fp = flat.ports[alt.port]
                    for field_name, var in zip(fp.fields, fp.decl.data):
                        if (param.name, field_name) in acc and fc.id not in out.setdefault((fp.atom, var), []):
                            out[(fp.atom, var)].append(fc.id)
    return out


def observed_by_priorities(flat: FlatSystem) -> set[int]:
    """State slots read by guards of compound priorities."""
    out: set[int] = set()
    for pr in flat.priorities:
        acc: set[tuple[str, str]] = set()
        _port_data(pr.guard, acc)
        for key in acc:
            if key in pr.data:
                out.add(pr.data[key][0])
    return out


def live_places(fa: FlatAtom, always: set[str]) -> dict[str, int]:
    """For each variable of the atom not in ``always``: the mask of places where it is live (backward dataflow)."""
    t = fa.type
    live: dict[str, set[str]] = {p: set() for p in fa.places}
    effects = []
    for tr in t.transitions:
        r, w = _body(tr.action)
        effects.append((tr, _reads(tr.guard) | r, w))
    changed = True
    while changed:
        changed = False
        for tr, reads, writes in effects:
            after: set[str] = set()
            for q in tr.targets:
                after |= live.get(q, set())
            need = reads | (after - writes)
            for p in tr.sources:
                if p in live and not need <= live[p]:
                    live[p] |= need
                    changed = True
    out = {}
    for d in fa.variables:
        if d.name in always:
            continue
        out[d.name] = sum(1 << i for i, p in enumerate(fa.places) if d.name in live[p])
    return out


def layout(flat: FlatSystem, reduce: bool = True, observed: Iterable[tuple[str, str]] = (),
           requests: int = 0) -> list[Slot]:
    """The slots of the explorer's states: the engine's, then ``requests`` environment counters.

    ``observed`` names ``(atom, variable)`` pairs a property reads: they stay
    live.  With ``reduce=False`` every variable is always live (no reset).
    """
    observed = set(observed)
    by_connectors = readers_by_connectors(flat)
    by_priorities = observed_by_priorities(flat)
    void = dead_with(flat) if reduce else {}
    slots: list[Slot] = []
    for fa in flat.atoms:
        slots.append(Slot(fa.offset, "marking", fa.name, "marking", places=len(fa.places)))
        always = {d.name for d in fa.variables if d.exported or fa.slot(d.name) in by_priorities
                  or (fa.name, d.name) in observed}
        for pr in fa.type.priorities:
            always |= _reads(pr.guard)
        for inv in fa.type.invariants:  # checked in every state where it is in force
            always |= _reads(inv.guard)
        alive = {}  # variables connectors read: live while one of them may still fire, or while the atom reads them
        for d in fa.variables:
            readers = by_connectors.get((fa.index, d.name))
            if readers and d.name not in always:
                conditions = [connector_alive(flat, flat.connectors[c], fa.index) for c in readers]
                if not reduce or None in conditions:
                    always.add(d.name)
                else:
                    alive[d.name] = tuple(sorted({pair for c in conditions for pair in c}))
        masks = live_places(fa, always) if reduce else {}
        for d in fa.variables:
            kind = d.type if d.type in ("bool", "int") else "value"
            domain = declared_domain(d, fa.name)
            slots.append(Slot(fa.slot(d.name), kind, fa.name, d.name, live=masks.get(d.name),
                              default=default_value(d.type), domain=domain, marking=fa.offset,
                              alive=alive.get(d.name, ()),
                              void=void.get(fa.slot(d.name), ()) if d.name in alive else ()))
    for k in range(requests):
        slots.append(Slot(flat.state_size + k, "requests", None, f"requests[{k}]", default=0))
    return slots


def reduced(slots: list[Slot]) -> list[Slot]:
    """The variables the reduction may reset (live somewhere only, or never)."""
    return [s for s in slots if s.live is not None]
