"""The description IR: what a GenoM module says, independent of the dialect it was written in.

Both front ends (GenoM3 dotgen and GenoM2 ``.gen``) produce these plain
dataclasses; everything downstream (checks, the BIP model builder, the
summaries) reads only this.  Every node carries the :class:`Span` it came from
so that later errors can still point at ``file:line:column``.

Durations are stored in seconds (floats); the original text is kept on the
node for messages.  Names are kept as written in the description; renaming for
BIP reserved words happens in the back end.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields, is_dataclass, replace
from enum import StrEnum
from typing import Any

from runtime.diagnostics import NOWHERE, Span

# --------------------------------------------------------------------------- vocabularies
# String enums: a member equals its value ("activity"), prints as it and goes to JSON as it.


class Dialect(StrEnum):
    """The language a component was written in."""

    GENOM3 = "genom3"
    GENOM2 = "genom2"


class ServiceKind(StrEnum):
    """``attribute`` and ``function`` run in the control task, ``activity`` in an execution task."""

    ATTRIBUTE = "attribute"
    FUNCTION = "function"
    ACTIVITY = "activity"


class Direction(StrEnum):
    """Which way data flows: through a port (``in``/``out``), a parameter or a codel argument (also ``inout``)."""

    IN = "in"
    OUT = "out"
    INOUT = "inout"


class Origin(StrEnum):
    """Where a codel argument or a service parameter takes its value from."""

    IDS = "ids"
    LOCAL = "local"
    PORT = "port"
    REMOTE = "remote"


# --------------------------------------------------------------------------- types


@dataclass
class Node:
    """Base of every IR node that was written somewhere: the :class:`Span` it came from (not compared)."""

    span: Span = field(default=NOWHERE, compare=False, repr=False, kw_only=True)


#: Ranges of the IDL integer types (and C's fixed-width ones): what a constant or a schema of that type holds.
INTEGER_RANGES = {
    "short": (-(2 ** 15), 2 ** 15 - 1), "unsigned short": (0, 2 ** 16 - 1),
    "long": (-(2 ** 31), 2 ** 31 - 1), "unsigned long": (0, 2 ** 32 - 1),
    "long long": (-(2 ** 63), 2 ** 63 - 1), "unsigned long long": (0, 2 ** 64 - 1),
    "octet": (0, 255), "int8_t": (-128, 127), "uint8_t": (0, 255),
    "int16_t": (-(2 ** 15), 2 ** 15 - 1), "uint16_t": (0, 2 ** 16 - 1),
    "int32_t": (-(2 ** 31), 2 ** 31 - 1), "uint32_t": (0, 2 ** 32 - 1),
    "int64_t": (-(2 ** 63), 2 ** 63 - 1), "uint64_t": (0, 2 ** 64 - 1),
}


@dataclass
class Type(Node):
    """Base of IDL type expressions."""


@dataclass
class BaseType(Type):
    """A predefined IDL type: ``long``, ``unsigned short``, ``double``, ``boolean``, ``char``, ``octet``, ``any``..."""

    name: str


@dataclass
class NamedType(Type):
    """A reference to a declared type by scoped name (``ns::pose``)."""

    name: str


@dataclass
class StringType(Type):
    bound: int | None = None


@dataclass
class SequenceType(Type):
    element: Type
    bound: int | None = None


@dataclass
class OptionalType(Type):
    element: Type


@dataclass
class ArrayType(Type):
    """``T name[d1][d2]``: an array declarator turns the member type into this."""

    element: Type
    dims: list[int]


@dataclass
class NativeType(Type):
    """``native name;``: a type opaque to GenoM, only handled by codels."""

    name: str


@dataclass
class FixedType(Type):
    """IDL ``fixed<digits, scale>`` (both None for the unbounded form)."""

    digits: int | None = None
    scale: int | None = None


class EnumValue(int):
    """An enumerator used as a constant value: an ``int`` (its ordinal) that remembers its scoped name."""

    name: str

    def __new__(cls, value: int, name: str) -> "EnumValue":
        obj = super().__new__(cls, value)
        obj.name = name
        return obj

    def __repr__(self) -> str:
        return f"EnumValue({int(self)}, {self.name!r})"

    def __str__(self) -> str:
        return self.name


@dataclass
class Member(Node):
    """A struct/exception member, an ids member, or a local variable."""

    name: str
    type: Type
    initializer: Any = None
    doc: str | None = None


@dataclass
class StructType(Type):
    name: str
    members: list[Member] = field(default_factory=list)


@dataclass
class UnionCase(Node):
    labels: list[Any]  # constant values; the string "default" for ``default:``
    member: Member


@dataclass
class UnionType(Type):
    name: str
    discriminator: Type
    cases: list[UnionCase] = field(default_factory=list)


@dataclass
class EnumType(Type):
    name: str
    enumerators: list[str] = field(default_factory=list)


@dataclass
class Typedef(Node):
    name: str
    type: Type


@dataclass
class Constant(Node):
    name: str
    type: Type
    value: Any


@dataclass
class ExceptionDecl(Node):
    """An IDL/GenoM exception; members carry detail data with the failure."""

    name: str
    members: list[Member] = field(default_factory=list)


# --------------------------------------------------------------------------- codels


@dataclass
class Duration:
    """A time value such as a period or a WCET, normalised to seconds."""

    seconds: float
    text: str = ""

    def __str__(self) -> str:
        return self.text or f"{self.seconds}s"


@dataclass
class Yield(Node):
    """A target of a codel: ``main`` (run at once) or ``pause::main`` (wait for the next period)."""

    state: str
    pause: bool = False

    def __str__(self) -> str:
        return f"pause::{self.state}" if self.pause else self.state


@dataclass
class CodelParam(Node):
    """One codel argument: where it comes from, its direction, the variable path and an optional alias.

    ``source`` is ``ids``, ``local``, ``port``, ``remote`` or ``None`` when the
    description leaves it to name resolution (service parameter, then ids).
    """

    path: str
    direction: Direction | None = None
    source: Origin | None = None
    alias: str | None = None

    def __post_init__(self) -> None:
        self.direction = None if self.direction is None else Direction(self.direction)
        self.source = None if self.source is None else Origin(self.source)


@dataclass
class Codel(Node):
    """A C function of the module.  FSM codels have ``triggers`` (the states that run them) and ``yields``."""

    name: str
    triggers: list[str] = field(default_factory=list)
    yields: list[Yield] = field(default_factory=list)
    params: list[CodelParam] = field(default_factory=list)
    is_async: bool = False
    wcet: Duration | None = None


def fsm_states(codels: list[Codel]) -> list[str]:
    """The states an automaton of codels has: every trigger, in order of first appearance."""
    seen: list[str] = []
    for codel in codels:
        for t in codel.triggers:
            if t not in seen:
                seen.append(t)
    return seen


# --------------------------------------------------------------------------- component parts


@dataclass
class Port(Node):
    """A GenoM port: ``out`` ports are posters written by this component, ``in`` ports read others'."""

    name: str
    direction: Direction  # IN or OUT
    type: Type
    multiple: bool = False
    doc: str | None = None

    def __post_init__(self) -> None:
        self.direction = Direction(self.direction)


@dataclass
class Task(Node):
    """An execution task: its period (None = aperiodic), its permanent-activity codels and scheduling data."""

    name: str
    period: Duration | None = None
    delay: Duration | None = None
    priority: int | None = None
    stack: int | None = None
    codels: list[Codel] = field(default_factory=list)
    throws: list[str] = field(default_factory=list)
    doc: str | None = None
    scheduling: str | None = None  # "real-time" when the description asks for it
    # Where the names this task refers to were written ("period", "throws:e_x"), for messages.
    ref_spans: dict[str, Span] = field(default_factory=dict, compare=False, repr=False, kw_only=True)


@dataclass
class Parameter(Node):
    """A service parameter: ``in``/``out``/``inout``, named after an ids member or local, with a default and doc."""

    direction: Direction
    name: str
    type: Type | None = None  # None when it names an ids member whose type is found by lookup
    source: Origin = Origin.LOCAL  # IDS (the value is an ids member) or LOCAL (a service argument)
    default: Any = None
    doc: str | None = None
    # source IDS: the ids member path bound to the parameter (``pos.x``); "" binds the whole ids
    member: str | None = None
    # docs of parts of a structured default (``{ .x = 1 : "x doc" }``), keyed by path ("x", "[2]", "a.b")
    member_docs: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.direction, self.source = Direction(self.direction), Origin(self.source)


@dataclass
class Service(Node):
    """A service: ``attribute`` and ``function`` run in the control task, ``activity`` in its ``task``."""

    name: str
    kind: ServiceKind
    parameters: list[Parameter] = field(default_factory=list)
    task: str | None = None
    validate: Codel | None = None
    codels: list[Codel] = field(default_factory=list)
    interrupts: list[str] = field(default_factory=list)
    before: list[str] = field(default_factory=list)
    after: list[str] = field(default_factory=list)
    throws: list[str] = field(default_factory=list)
    locals: list[Member] = field(default_factory=list)
    doc: str | None = None
    # Where the names this service refers to were written, keyed "task", "interrupts:Stop",
    # "after:Init", "before:X", "throws:e_x": checks point at the offending name, not the service.
    ref_spans: dict[str, Span] = field(default_factory=dict, compare=False, repr=False, kw_only=True)

    def __post_init__(self) -> None:
        self.kind = ServiceKind(self.kind)

    @property
    def interrupts_itself(self) -> bool:
        """An activity whose ``interrupts`` names itself (or ``all``): a new request interrupts the running one."""
        return self.kind == ServiceKind.ACTIVITY and (self.name in self.interrupts or "all" in self.interrupts)

    def fsm_codels(self) -> list[Codel]:
        """The codels as an automaton: a plain ``codel f()`` (a function's) runs as ``<start> f() yield ether``."""
        return [c if c.triggers else replace(c, triggers=["start"], yields=[Yield("ether", span=c.span)])
                for c in self.codels]

    def states(self) -> list[str]:
        """The FSM states of the service, in order of first appearance."""
        return fsm_states(self.fsm_codels())


@dataclass
class Interface(Node):
    """A GenoM3 ``interface``: a component-like template merged into components that provide/use it."""

    name: str
    ids: list[Member] = field(default_factory=list)
    ports: list[Port] = field(default_factory=list)
    services: list[Service] = field(default_factory=list)
    throws: list[str] = field(default_factory=list)
    properties: dict[str, Any] = field(default_factory=dict)
    tasks: list[Task] = field(default_factory=list)
    # Where the names it refers to were written ("codels-require:eigen3"), for messages.
    ref_spans: dict[str, Span] = field(default_factory=dict, compare=False, repr=False, kw_only=True)


@dataclass
class Component(Node):
    """A GenoM module (GenoM3 ``component``, GenoM2 ``module``)."""

    name: str
    dialect: Dialect
    ids: list[Member] = field(default_factory=list)
    tasks: list[Task] = field(default_factory=list)
    ports: list[Port] = field(default_factory=list)
    services: list[Service] = field(default_factory=list)
    throws: list[str] = field(default_factory=list)
    provides: list[str] = field(default_factory=list)
    uses: list[str] = field(default_factory=list)
    clock_rate: Duration | None = None
    properties: dict[str, Any] = field(default_factory=dict)  # doc, version, lang, email, require, codels-require...
    file: str = ""
    # Where the names this component refers to were written ("provides:Iface"), for messages.
    ref_spans: dict[str, Span] = field(default_factory=dict, compare=False, repr=False, kw_only=True)

    def __post_init__(self) -> None:
        self.dialect = Dialect(self.dialect)

    def task(self, name: str) -> Task | None:
        return next((t for t in self.tasks if t.name == name), None)

    def service(self, name: str) -> Service | None:
        return next((s for s in self.services if s.name == name), None)

    def port(self, name: str) -> Port | None:
        return next((p for p in self.ports if p.name == name), None)


@dataclass
class Pragma(Node):
    """A ``#pragma`` line kept for later stages (``requires``, ``provides``, ...)."""

    name: str
    arguments: str


@dataclass
class Description:
    """Everything read from a set of files: components plus the shared types, constants and interfaces."""

    components: list[Component] = field(default_factory=list)
    types: dict[str, Any] = field(default_factory=dict)  # scoped name -> StructType/UnionType/EnumType/Typedef
    constants: dict[str, Constant] = field(default_factory=dict)
    exceptions: dict[str, ExceptionDecl] = field(default_factory=dict)
    interfaces: dict[str, Interface] = field(default_factory=dict)
    pragmas: list[Pragma] = field(default_factory=list)
    files: list[str] = field(default_factory=list)

    def component(self, name: str) -> Component | None:
        return next((c for c in self.components if c.name == name), None)


# --------------------------------------------------------------------------- JSON


def to_json(node: Any) -> Any:
    """Turn IR nodes into JSON-ready data; each dataclass gets a ``"node"`` key naming its class."""
    if isinstance(node, Span):
        return str(node) if node is not NOWHERE else None
    if is_dataclass(node) and not isinstance(node, type):
        out: dict[str, Any] = {"node": type(node).__name__}
        for f in sorted(fields(node), key=lambda f: f.name == "span"):  # the span last, as it always was
            value = getattr(node, f.name)
            if isinstance(value, Span):
                out[f.name] = str(value) if value is not NOWHERE else None
            else:
                out[f.name] = to_json(value)
        return out
    if isinstance(node, StrEnum):
        return node.value
    if isinstance(node, dict):
        return {str(k): to_json(v) for k, v in node.items()}
    if isinstance(node, (list, tuple)):
        return [to_json(v) for v in node]
    return node


