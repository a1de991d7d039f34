"""Behaviour layer: port types and atom types (places, transitions, guards, actions, atom priorities)."""
from __future__ import annotations

from dataclasses import dataclass, field

from runtime.diagnostics import Span
from runtime.model.common import Annotation, DataDecl, DataParam, _span
from runtime.model.expressions import Expr, Stmt
from runtime.model.timing import ClockDecl, Invariant, Resume


@dataclass
class PortType:
    """``port type T(int x, bool y)``: the data a port carries."""

    name: str
    params: list[DataParam] = field(default_factory=list)
    annotations: list[Annotation] = field(default_factory=list)
    span: Span = _span()


@dataclass
class PortDecl:
    """``[export] port T p(x, y)`` in an atom: a port of type ``T`` bound to the atom's variables."""

    type: str
    name: str
    data: list[str] = field(default_factory=list)
    exported: bool = False
    annotations: list[Annotation] = field(default_factory=list)
    span: Span = _span()
    #: ``export port T p(), q() as e``: the atom offers p and q merged as one port e (either may take part)
    export_as: str | None = None
    #: ``extern port T p(x) as "Name" policy``: events pushed from outside the model fire p, carrying x;
    #: ``backend`` names the code behind it, ``policy`` (remember, ignore, error) says what an event that
    #: no transition can take becomes (None: not written)
    extern: bool = False
    backend: str | None = None
    policy: str | None = None

    @property
    def interface_name(self) -> str:
        """The name the atom's compound sees this port by."""
        return self.export_as or self.name


@dataclass
class InitialTransition:
    """``initial to p1, p2 do { ... }``."""

    targets: list[str]
    action: list[Stmt] = field(default_factory=list)
    span: Span = _span()
    # timed BIP2 (runtime/model/timing.py)
    resume: Resume | None = None


@dataclass
class Transition:
    """``on p from s to t provided (g) do { ... }``; ``port`` is None for an ``internal`` transition."""

    port: str | None
    sources: list[str]
    targets: list[str]
    guard: Expr | None = None
    action: list[Stmt] = field(default_factory=list)
    annotations: list[Annotation] = field(default_factory=list)
    span: Span = _span()
    # timed BIP2 (runtime/model/timing.py): None is lazy, the default
    urgency: str | None = None
    resume: Resume | None = None

    @property
    def internal(self) -> bool:
        return self.port is None


def coverable_places(initial: list[str], transitions: list[Transition]) -> set[str]:
    """The places some run from ``initial`` can mark, guards aside: a transition fires once its sources all can."""
    marked = set(initial)
    grown = True
    while grown:
        grown = False
        for t in transitions:
            if set(t.sources) <= marked and not set(t.targets) <= marked:
                marked |= set(t.targets)
                grown = True
    return marked


@dataclass
class AtomPriority:
    """``priority name low < high provided (g)`` between ports of one atom (``*`` allowed on either side)."""

    name: str
    low: str
    high: str
    guard: Expr | None = None
    span: Span = _span()


@dataclass
class AtomType:
    """An atomic component type: an automaton extended with data."""

    name: str
    params: list[DataParam] = field(default_factory=list)
    data: list[DataDecl] = field(default_factory=list)
    ports: list[PortDecl] = field(default_factory=list)
    places: list[str] = field(default_factory=list)
    initial: InitialTransition | None = None
    transitions: list[Transition] = field(default_factory=list)
    priorities: list[AtomPriority] = field(default_factory=list)
    annotations: list[Annotation] = field(default_factory=list)
    span: Span = _span()
    # timed BIP2 (runtime/model/timing.py)
    clocks: list[ClockDecl] = field(default_factory=list)
    invariants: list[Invariant] = field(default_factory=list)

    @property
    def timed(self) -> bool:
        return bool(self.clocks or self.invariants)

    def port(self, name: str) -> PortDecl | None:
        return next((p for p in self.ports if p.name == name), None)

    def exported_ports(self, name: str) -> list[PortDecl]:
        """The ports behind the exported port ``name``: one, several when merged with ``as``, or none."""
        return [p for p in self.ports if p.exported and p.interface_name == name]

    def variable(self, name: str) -> DataDecl | None:
        return next((d for d in self.data if d.name == name), None)
