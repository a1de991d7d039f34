"""A TChecker file's declarations checked into a network of timed automata (names resolved, every use declared).

What the zone engine cannot take is refused here, at its place in the file:
guards on weakly synchronised edges (as tck-reach refuses them), diagonal clock constraints (``x - y < c``),
clocks compared with integer variables, clock-to-clock assignments, invariants
on integer variables, clocks shared by several processes, several initial
locations in one process, ``/``, ``%``, conditional terms and ``if``/``while``/
``local`` statements.  Strict clock constraints (``x < c``, ``x > c``) are read
only on a time grid chosen by the caller (docs/verification/tchecker.md).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from runtime.diagnostics import Span
from runtime.tchecker.syntax import KINDS, Declaration, Node, Source, parse_expression, parse_statements

_FLIP = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "==": "=="}


@dataclass
class IntVar:
    name: str  # flattened: ``a[2]`` for an array element
    low: int
    high: int
    init: int


@dataclass
class ClockBound:
    """``clock op bound`` (bound an integer, op one of < <= == >= >), where it was written."""

    clock: str
    op: str
    bound: int
    span: Span


@dataclass
class Location:
    process: str
    name: str
    initial: bool = False
    committed: bool = False
    urgent: bool = False
    invariant: list[ClockBound] = field(default_factory=list)  # upper bounds only
    labels: list[str] = field(default_factory=list)
    span: Span | None = None


@dataclass
class Edge:
    process: str
    index: int  # within its process
    source: str
    target: str
    event: str
    clocks: list[ClockBound] = field(default_factory=list)  # guard's clock part
    guard: list[Node] = field(default_factory=list)  # guard's integer part (conjuncts)
    resets: list[tuple[str, int]] = field(default_factory=list)
    assigns: list[tuple[str, Node]] = field(default_factory=list)  # integer assignments, in order
    span: Span | None = None
    guard_span: Span | None = None  # of its ``provided`` attribute


@dataclass
class Process:
    name: str
    locations: dict[str, Location] = field(default_factory=dict)
    edges: list[Edge] = field(default_factory=list)
    clocks: list[str] = field(default_factory=list)  # the clocks only this process reads or sets
    span: Span | None = None

    @property
    def initial(self) -> Location:
        return next(loc for loc in self.locations.values() if loc.initial)


@dataclass
class Sync:
    parts: list[tuple[str, str]]  # (process, event)
    span: Span
    weak: set[str] = field(default_factory=set)  # the processes of ``p@e?`` constraints


@dataclass
class System:
    name: str
    file: str
    processes: dict[str, Process]
    events: set[str]
    ints: dict[str, IntVar]
    clocks: list[str]
    syncs: list[Sync]
    strict: Span | None = None  # the first strict clock constraint, if any

    def labels(self) -> set[str]:
        return {lab for p in self.processes.values() for loc in p.locations.values() for lab in loc.labels}


def check(src: Source, decls: list[Declaration]) -> System:
    """The network the declarations describe; a located DiagnosticError at the first problem."""
    return _Checker(src).run(decls)


class _Checker:
    def __init__(self, src: Source) -> None:
        self.src = src
        self.processes: dict[str, Process] = {}
        self.events: set[str] = set()
        self.ints: dict[str, IntVar] = {}
        self.arrays: dict[str, tuple[str, int]] = {}  # declared name -> ("int"|"clock", size)
        self.clocks: list[str] = []
        self.syncs: list[Sync] = []
        self.owner: dict[str, tuple[str, Span]] = {}
        self.strict: Span | None = None

    def fail(self, span: Span, message: str, hint: str | None = None):
        raise self.src.error(span, message, hint)

    def run(self, decls: list[Declaration]) -> System:
        if not decls:
            self.fail(Span(self.src.file, 1, 1), "empty file: expected 'system:NAME' first")
        if decls[0].kind != "system":
            self.fail(decls[0].span, "the first declaration must be 'system:NAME'")
        name = self.identifier(self.fields(decls[0], 1)[0])
        for d in decls[1:]:
            getattr(self, "decl_" + d.kind)(d)
        if not self.processes:
            self.fail(decls[0].span, "the system has no process", hint="declare one with 'process:NAME'")
        for p in self.processes.values():
            initial = [loc for loc in p.locations.values() if loc.initial]
            if not initial:
                self.fail(p.span, f"process {p.name} has no initial location",
                          hint="give one location the attribute 'initial:'")
            if len(initial) > 1:
                self.fail(initial[1].span, f"process {p.name} has several initial locations",
                          hint="the engine starts each component in one place: keep one 'initial:'")
            for b in initial[0].invariant:
                if not _holds(0, b.op, b.bound):
                    self.fail(b.span, f"the initial location's invariant is false at time 0: {b.clock} {b.op} "
                                      f"{b.bound}")
        weak = {(p, ev) for sync in self.syncs for p, ev in sync.parts if p in sync.weak}
        for p in self.processes.values():
            for e in p.edges:
                if (p.name, e.event) in weak and (e.clocks or any(_variables(g) for g in e.guard)):
                    self.fail(e.guard_span, f"a guard on an edge of {p.name}'s weakly synchronised event "
                                            f"'{e.event}'", hint="tck-reach refuses it too (a constant guard aside): "
                                                                 "whether a guarded edge makes its process take "
                                                                 "part is not defined")
        for clock, (proc, _) in self.owner.items():
            self.processes[proc].clocks.append(clock)
        return System(name, self.src.file, self.processes, self.events, self.ints,
                      [c for c in self.clocks if c in self.owner], self.syncs, self.strict)

    # -- declarations -----------------------------------------------------------------------------
    def fields(self, d: Declaration, n: int) -> list:
        got = [f for f in d.fields if f.text not in "@?"]
        if len(got) != n or len(got) != len(d.fields):
            at = d.fields[min(len(d.fields), n) - 1].span if d.fields and len(d.fields) > n else d.span
            self.fail(at, f"'{d.kind}' takes {n} field(s), found {len(d.fields)}",
                      hint=_SHAPES.get(d.kind))
        return got

    def no_attributes(self, d: Declaration) -> None:
        if d.attributes:
            self.fail(d.attributes[0].span, f"'{d.kind}' declarations take no attributes")

    def fresh(self, f, what: str) -> str:
        name = self.identifier(f)
        if name in self.arrays or name in self.events and what == "event" or name in self.processes and \
                what == "process":
            self.fail(f.span, f"'{name}' is declared twice")
        return name

    def identifier(self, f) -> str:
        if f.text in KINDS:
            self.fail(f.span, f"'{f.text}' is a keyword, not a name", hint="keywords: " + ", ".join(KINDS))
        if not (f.text[0].isalpha() or f.text[0] == "_"):
            self.fail(f.span, f"'{f.text}' is not an identifier")
        return f.text

    def number(self, f, low: int | None = None) -> int:
        try:
            v = int(f.text)
        except ValueError:
            self.fail(f.span, f"expected an integer, found '{f.text}'")
        if low is not None and v < low:
            self.fail(f.span, f"expected an integer >= {low}, found {v}")
        return v

    def decl_system(self, d: Declaration) -> None:
        self.fail(d.span, "a second 'system' declaration", hint="a file describes one system, declared first")

    def decl_process(self, d: Declaration) -> None:
        (f,) = self.fields(d, 1)
        self.no_attributes(d)
        self.processes[self.fresh(f, "process")] = Process(f.text, span=f.span)

    def decl_event(self, d: Declaration) -> None:
        (f,) = self.fields(d, 1)
        self.no_attributes(d)
        self.events.add(self.fresh(f, "event"))

    def decl_clock(self, d: Declaration) -> None:
        size, f = self.fields(d, 2)
        self.no_attributes(d)
        n = self.number(size, 1)
        name = self.fresh(f, "clock")
        self.arrays[name] = ("clock", n)
        self.clocks += [name] if n == 1 else [f"{name}[{k}]" for k in range(n)]

    def decl_int(self, d: Declaration) -> None:
        size, low, high, init, f = self.fields(d, 5)
        self.no_attributes(d)
        n, lo, hi, v = self.number(size, 1), self.number(low), self.number(high), self.number(init)
        if hi < lo:
            self.fail(high.span, f"the largest value {hi} is below the smallest {lo}")
        if not lo <= v <= hi:
            self.fail(init.span, f"the initial value {v} is outside [{lo}, {hi}]")
        name = self.fresh(f, "int")
        self.arrays[name] = ("int", n)
        for k in range(n):
            key = name if n == 1 else f"{name}[{k}]"
            self.ints[key] = IntVar(key, lo, hi, v)

    def process(self, f) -> Process:
        p = self.processes.get(f.text)
        if p is None:
            self.fail(f.span, f"unknown process '{f.text}'", hint=_known(self.processes))
        return p

    def decl_location(self, d: Declaration) -> None:
        pf, lf = self.fields(d, 2)
        p = self.process(pf)
        if lf.text in p.locations:
            self.fail(lf.span, f"location '{lf.text}' of process {p.name} is declared twice")
        loc = Location(p.name, self.identifier(lf), span=lf.span)
        for a in d.attributes:
            if a.key in ("initial", "committed", "urgent"):
                setattr(loc, a.key, True)
            elif a.key == "labels":
                loc.labels = [x.strip() for x in a.value.split(",") if x.strip()]
            elif a.key == "invariant":
                loc.invariant = self.invariant(parse_expression(self.src, a), p.name)
        p.locations[loc.name] = loc

    def decl_edge(self, d: Declaration) -> None:
        pf, sf, tf, ef = self.fields(d, 4)
        p = self.process(pf)
        for f in (sf, tf):
            if f.text not in p.locations:
                self.fail(f.span, f"unknown location '{f.text}' of process {p.name}", hint=_known(p.locations))
        if ef.text not in self.events:
            self.fail(ef.span, f"unknown event '{ef.text}'", hint=_known(self.events))
        e = Edge(p.name, len(p.edges), sf.text, tf.text, ef.text, span=d.span)
        for a in d.attributes:
            if a.key == "provided":
                e.guard_span = a.span
                for c in _conjuncts(parse_expression(self.src, a)):
                    if self.mentions_clock(c):
                        e.clocks.append(self.clock_bound(c, p.name))
                    else:
                        e.guard.append(self.int_expr(c, boolean=True))
            elif a.key == "do":
                for s in parse_statements(self.src, a):
                    if s.op == "nop":
                        continue
                    target = self.lvalue(s.args[0])
                    if target in self.clocks:
                        if self.mentions_clock(s.args[1]):
                            self.fail(s.span, f"unsupported: clock {target} set from a clock",
                                      hint="the engine resets a clock to a constant")
                        value = self.constant(s.args[1], f"the value clock {target} is set to")
                        if value < 0:
                            self.fail(s.args[1].span, f"clock {target} set to {value}: clocks are never negative")
                        e.resets.append((target, value))
                        self.own(target, p.name, s.args[0].span)
                    else:
                        e.assigns.append((target, self.int_expr(s.args[1])))
        p.edges.append(e)

    def decl_sync(self, d: Declaration) -> None:
        self.no_attributes(d)
        parts, weak, fs, k = [], set(), d.fields, 0
        while k < len(fs):
            if k + 2 >= len(fs) or fs[k + 1].text != "@":
                self.fail(fs[k].span, "expected 'process@event' in a sync", hint="sync:P1@a:P2@b")
            p = self.process(fs[k])
            if fs[k + 2].text not in self.events:
                self.fail(fs[k + 2].span, f"unknown event '{fs[k + 2].text}'", hint=_known(self.events))
            if any(q == p.name for q, _ in parts):
                self.fail(fs[k].span, f"process {p.name} appears twice in one sync")
            parts.append((p.name, fs[k + 2].text))
            k += 3
            if k < len(fs) and fs[k].text == "?":
                weak.add(p.name)
                k += 1
        if len(parts) < 2:
            self.fail(d.span, "a sync needs at least two processes")
        self.syncs.append(Sync(parts, d.span, weak))

    # -- expressions ------------------------------------------------------------------------------
    def lvalue(self, n: Node) -> str:
        if n.op != "var":
            self.fail(n.span, f"expected a variable, found '{n}'")
        kind = self.arrays.get(n.name)
        if kind is None:
            self.fail(n.span, f"unknown variable '{n.name}'")
        if kind[1] == 1:
            if n.args:
                self.fail(n.span, f"'{n.name}' is not an array")
            return n.name
        if not n.args:
            self.fail(n.span, f"'{n.name}' is an array of {kind[1]}: give an index")
        k = self.constant(n.args[0], "an array index (the engine takes constant indices)")
        if not 0 <= k < kind[1]:
            self.fail(n.args[0].span, f"index {k} is outside '{n.name}' (size {kind[1]})")
        return f"{n.name}[{k}]"

    def mentions_clock(self, n: Node) -> bool:
        if n.op == "var":
            return self.arrays.get(n.name, ("", 0))[0] == "clock" or any(self.mentions_clock(a) for a in n.args)
        return any(self.mentions_clock(a) for a in n.args if isinstance(a, Node))

    def constant(self, n: Node, what: str) -> int:
        if n.op == "int":
            return n.value
        if n.op == "neg":
            return -self.constant(n.args[0], what)
        if n.op in ("+", "-", "*"):
            a, b = self.constant(n.args[0], what), self.constant(n.args[1], what)
            return a + b if n.op == "+" else a - b if n.op == "-" else a * b
        self.fail(n.span, f"unsupported: '{n}' as {what}: expected a constant")

    def clock_bound(self, n: Node, proc: str) -> ClockBound:
        if n.op == "!":
            self.fail(n.span, "unsupported: a negated clock constraint", hint="write the opposite comparison")
        if n.op not in _FLIP:
            self.fail(n.span, f"unsupported clock constraint '{n}'",
                      hint="clock constraints are 'x op c' with op one of < <= == >= > and c a constant")
        left, right, op = n.args[0], n.args[1], n.op
        if any(side.op == "-" and self.mentions_clock(side) for side in (left, right)):
            self.fail(n.span, "unsupported: diagonal clock constraint (a difference of two clocks)",
                      hint="the engine compares one clock with a constant")
        if not (left.op == "var" and self.mentions_clock(left)):
            left, right, op = right, left, _FLIP[op]
        if left.op != "var" or self.mentions_clock(right):
            self.fail(n.span, f"unsupported clock constraint '{n}'", hint="one clock compared with a constant")
        clock = self.lvalue(left)
        bound = self.constant(right, f"the bound of clock {clock}")
        if op in ("<", ">") and self.strict is None:
            self.strict = n.span
        self.own(clock, proc, left.span)
        return ClockBound(clock, op, bound, n.span)

    def invariant(self, n: Node, proc: str) -> list[ClockBound]:
        out = []
        for c in _conjuncts(n):
            if not self.mentions_clock(c):
                self.fail(c.span, "unsupported: an invariant on integer variables",
                          hint="invariants bound clocks from above: 'x <= c'")
            b = self.clock_bound(c, proc)
            if b.op not in ("<", "<="):
                self.fail(c.span, f"unsupported invariant '{c}': an invariant bounds a clock from above",
                          hint="'x <= c' or 'x < c'")
            out.append(b)
        return out

    def own(self, clock: str, proc: str, span: Span) -> None:
        first = self.owner.setdefault(clock, (proc, span))
        if first[0] != proc:
            self.fail(span, f"unsupported: clock {clock} is used by processes {first[0]} and {proc}",
                      hint=f"the engine keeps a clock in one component; {first[0]} uses it at {first[1]}")

    def int_expr(self, n: Node, boolean: bool = False) -> Node:
        """Check an integer expression (no clocks, no / or %, declared variables); flatten array elements."""
        if self.mentions_clock(n):
            self.fail(n.span, f"unsupported: '{n}' mixes clocks into an integer expression",
                      hint="clock constraints are conjuncts 'x op c' of a guard")
        if n.op in ("/", "%"):
            self.fail(n.span, f"unsupported operator '{n.op}'", hint="+, -, * and comparisons are read")
        if n.op == "var":
            return Node("var", [], n.span, name=self.lvalue(n))
        if n.op == "int":
            return n
        return Node(n.op, [self.int_expr(a) for a in n.args], n.span)


def _variables(n: Node) -> bool:
    """``n`` reads a variable (a guard that is not a constant)."""
    return n.op == "var" or any(_variables(a) for a in n.args if isinstance(a, Node))


def _conjuncts(n: Node) -> list[Node]:
    if n.op == "&&":
        return _conjuncts(n.args[0]) + _conjuncts(n.args[1])
    return [n]


def _holds(v: int, op: str, b: int) -> bool:
    return {"<": v < b, "<=": v <= b, "==": v == b, ">=": v >= b, ">": v > b}[op]


def _known(names) -> str:
    names = sorted(names)
    if not names:
        return "none is declared yet: declare it before its use"
    shown = ", ".join(names[:8]) + (", ..." if len(names) > 8 else "")
    return f"declared (before this line): {shown}"


_SHAPES = {
    "system": "system:NAME",
    "process": "process:NAME",
    "event": "event:NAME",
    "clock": "clock:SIZE:NAME",
    "int": "int:SIZE:MIN:MAX:INIT:NAME",
    "location": "location:PROCESS:NAME{attributes}",
    "edge": "edge:PROCESS:SOURCE:TARGET:EVENT{attributes}",
}
