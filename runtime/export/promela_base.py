"""What every part of the Promela translation shares: names, scopes, monitors, and the global per state slot."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from runtime.engine.flatten import FlatAtom
from runtime.explore.choices import Choice, ExploreError
from runtime.explore.layout import Slot
from runtime.explore.space import StateSpace
from runtime.export.interactions import Static, all_interactions
from runtime.model.expressions import Assign, Call, Const, If, PortData, Var

#: Most simple paths through guarded priority rules before the translation gives up.
MAX_PATHS = 10_000


class PromelaError(ExploreError):
    """The model uses something Promela cannot express (or this translation does not)."""


@dataclass
class Name:
    text: str
    type: str | None


@dataclass
class Scope:
    """How names read in one context: atom variables, port data (or exported data), constants."""

    where: str
    variables: dict[str, Name] = field(default_factory=dict)
    ports: dict[tuple[str, str], Name] = field(default_factory=dict)
    constants: dict[str, tuple[Any, str]] = field(default_factory=dict)


@dataclass
class Monitor:
    """A safety observer compiled into the steps: a deterministic automaton over interactions.

    ``delta[k]`` maps a monitor state to the next one for interaction ``k``;
    ``bad`` are the states where the property is violated (``check`` then
    must hold, a Promela expression over the state, e.g. an invariant's
    predicate; ``false`` for ``never`` and ``precedes``).
    """

    name: str
    states: int
    delta: list[dict[int, int]]
    accepting: set[int]
    check: str = "false"
    initial: int = 0
    pred: Any = None  # the predicate F of [R] {F}, translated by the writer once names are known


def literal(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    raise PromelaError(f"Promela has no value like {value!r} (only integers and booleans)")


def int_type(lo: int, hi: int) -> str:
    if 0 <= lo and hi <= 255:
        return "byte"
    if -32768 <= lo and hi <= 32767:
        return "short"
    return "int"


class PromelaBase:
    """The translation's state: the explorer's layout and bound choices, a Promela global per slot, temporaries."""

    def __init__(self, space: StateSpace, monitors: list[Monitor] | None = None, hidden: bool = True) -> None:
        self.space = space
        self.hidden = hidden  # SPIN's multi-core mode refuses hidden variables: reset them after each step instead
        self.engine = space.engine
        self.flat = space.engine.flat
        self.slots: list[Slot] = space.slots
        self.monitors = monitors or []
        self.choices: dict[str, Choice] = {}
        for name, fn in self._bound_choices().items():
            self.choices[name] = fn
        self.names: dict[int, str] = {}
        self.types: dict[int, str] = {}
        self.temps: list[tuple[str, str]] = []
        self.lines: list[str] = []
        self.statics: list[Static] = all_interactions(self.engine)

    def _bound_choices(self) -> dict[str, Choice]:
        from runtime.explore.choices import codel_choices
        return codel_choices(self.engine.package)

    def temp(self, type_: str) -> str:
        name = f"t_{len(self.temps)}"
        self.temps.append((name, type_))
        return name

    def _declare_slots(self) -> None:
        ranges = self._int_ranges()
        for s in self.slots:
            if s.kind == "marking":
                fa = next(a for a in self.flat.atoms if a.offset == s.index)
                self.names[s.index] = f"m{fa.index}"
                self.types[s.index] = f"unsigned : {max(s.places, 1)}"
            elif s.kind == "requests":
                self.names[s.index] = f"r{s.index - self.space.width}"
                self.types[s.index] = "byte"
            else:
                fa = next(a for a in self.flat.atoms if a.name == s.atom)
                self.names[s.index] = f"a{fa.index}_{s.name}"
                if s.kind == "bool":
                    self.types[s.index] = "bool"
                elif s.kind == "int":
                    rng = s.domain or ranges.get(s.index)
                    self.types[s.index] = int_type(*rng) if rng else "int"
                else:
                    raise PromelaError(f"variable {s.title} is not an int or a bool: Promela cannot hold it")

    def _int_ranges(self) -> dict[int, tuple[int, int]]:
        """Int variables only ever assigned constants or codel outcomes: the range of those values."""
        written_by_connectors = set()
        for fc in self.flat.connectors:
            for spec in fc.type.interactions:
                for st in spec.down:
                    if isinstance(st, Assign) and isinstance(st.target, PortData):
                        written_by_connectors.add((fc.id, st.target.port))
        open_ports = set()
        for fc in self.flat.connectors:
            for (cid, pname) in written_by_connectors:
                if cid != fc.id:
                    continue
                k = next(i for i, p in enumerate(fc.type.params) if p.name == pname)
                for alt in fc.params[k]:
                    if hasattr(alt, "port"):
                        fp = self.flat.ports[alt.port]
                        open_ports.update((fp.atom, v) for v in fp.decl.data)
        out: dict[int, tuple[int, int]] = {}
        for fa in self.flat.atoms:
            for d in fa.variables:
                if d.type != "int" or (fa.index, d.name) in open_ports:
                    continue
                values = self._assigned_values(fa, d.name)
                if values is not None:
                    out[fa.slot(d.name)] = (min(values), max(values))
        return out

    def _assigned_values(self, fa: FlatAtom, var: str) -> set[int] | None:
        values: set[int] = {0}
        decl = next(d for d in fa.variables if d.name == var)
        bodies = [fa.type.initial.action] + [t.action for t in fa.type.transitions]
        if decl.init is not None:
            bodies.append([Assign(Var(var), decl.init)])

        def walk(stmts) -> bool:
            for st in stmts:
                if isinstance(st, Assign) and isinstance(st.target, Var) and st.target.name == var:
                    v = st.value
                    if isinstance(v, Const) and isinstance(v.value, int) and not isinstance(v.value, bool):
                        values.add(v.value)
                    elif isinstance(v, Var) and v.name in fa.constants and isinstance(fa.constants[v.name][0], int):
                        values.add(int(fa.constants[v.name][0]))
                    elif isinstance(v, Call) and v.function in self.choices:
                        values.update(int(x) for x in self.choices[v.function].values)
                    else:
                        return False
                elif isinstance(st, If):
                    if not walk(st.then) or not walk(st.orelse):
                        return False
            return True

        return values if all(walk(b) for b in bodies) else None
