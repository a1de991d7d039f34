"""Timed BIP2 on the engine: clocks are state slots, time passes between steps, urgency and invariants bound it.

The untimed step (runtime/engine) stays the one semantics: a clock is an
``int`` slot of its atom (its value in its own unit, exact: int or Fraction),
its rate a hidden ``float`` slot that ``x' = e`` assigns.  Letting ``d``
nanoseconds pass adds ``d * rate / unit`` to every clock; which interactions
are enabled after a delay is what ``Engine.enabled`` says of the delayed
state.  Timing constraints are linear in the delay (the validator's rules),
so the delays where an interaction is enabled form an interval whose ends are
among the roots of its clock comparisons: we evaluate the engine at those
roots and between them, and read the interval off (docs/engine.md, "Time").
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Callable

from runtime.bip2.printer import expr as print_expr
from runtime.engine.engine import Engine
from runtime.engine.errors import EngineError, ModelError
from runtime.engine.interaction import Interaction
from runtime.engine.invariants import compile_state_expr
from runtime.model import Assign, AtomType, Binary, Const, DataDecl, If, Package, Rate, Unary, Var
from runtime.model.timing import URGENCIES, Invariant

SECOND = 10**9
_COMPARISONS = ("==", "<", "<=", ">", ">=")


def exact(v):
    """A time or clock value as an int when it is whole (ints are much faster than Fractions)."""
    if type(v) is Fraction and v.denominator == 1:
        return v.numerator
    return v


def _ratio(a, b):
    """a / b, exactly."""
    if type(a) is int and type(b) is int:
        q, r = divmod(a, b)
        return q if not r else Fraction(a, b)
    return exact(Fraction(a) / Fraction(b))


# ---------------------------------------------------------------------------------------------- intervals
@dataclass(frozen=True)
class Window:
    """A set of delays ``[lo, hi]`` from now, in nanoseconds; ``hi`` None is +infinity; ends may be open."""

    lo: Fraction
    hi: Fraction | None
    lo_open: bool = False
    hi_open: bool = False

    def empty(self) -> bool:
        if self.hi is None:
            return False
        return self.hi < self.lo or (self.hi == self.lo and (self.lo_open or self.hi_open))

    def __and__(self, other: "Window") -> "Window":
        lo, lo_open = max((self.lo, self.lo_open), (other.lo, other.lo_open))
        his = [(w.hi, not w.hi_open) for w in (self, other) if w.hi is not None]
        if not his:
            return Window(lo, None, lo_open)
        hi, closed = min(his)
        return Window(lo, hi, lo_open, not closed)

    def contains(self, d) -> bool:
        if d < self.lo or (d == self.lo and self.lo_open):
            return False
        return self.hi is None or d < self.hi or (d == self.hi and not self.hi_open)

    def earliest(self) -> Fraction:
        """The first delay in the window (one nanosecond after an open left end, as the reference engine does)."""
        return self.lo + 1 if self.lo_open else self.lo


ALWAYS = Window(0, None)


def urgent_bound(window: Window, urgency: str) -> Window:
    """How far time may pass because of one enabled interaction: an eager one stops it at the start of its
    window, a delayable one at its end, a lazy one never (the reference engine's ``Interval::urgent``)."""
    if urgency == "eager":
        return Window(0, window.lo)  # up to its start, included even when the window excludes it
    if urgency == "delayable" and window.hi is not None and not window.hi_open:
        return Window(0, window.hi)  # a delayable window open on the right has no last instant
    return ALWAYS


def format_time(ns: Fraction | int | None) -> str:
    """Time as the Verimag reference engine prints it: 1s417ms203us, 0, +INFTY."""
    if ns is None:
        return "+INFTY"
    ns = int(ns)
    if ns == 0:
        return "0"
    sign, ns = ("-", -ns) if ns < 0 else ("", ns)
    parts = []
    for unit, size in (("d", 86400 * SECOND), ("h", 3600 * SECOND), ("min", 60 * SECOND), ("s", SECOND),
                       ("ms", 10**6), ("us", 10**3), ("ns", 1)):
        if ns >= size:
            parts.append(f"{ns // size}{unit}")
            ns %= size
    return sign + "".join(parts)


def format_window(w: Window, now: Fraction) -> str:
    """``[ 1s, 2s [`` in absolute time, as the reference prints intervals."""
    left = "]" if w.lo_open else "["
    right = "[" if w.hi_open and w.hi is not None else "]"
    hi = None if w.hi is None else now + w.hi
    return f"{left} {format_time(now + w.lo)}, {format_time(hi)} {right}"


# ---------------------------------------------------------------------------------------------- the view
def rate_name(atom: AtomType, clock: str) -> str:
    """The hidden variable that holds clock ``clock``'s rate: a name no declaration of the atom uses."""
    taken = {d.name for d in atom.data} | {p.name for p in atom.params} | {c.name for c in atom.clocks}
    name = f"_rate_{clock}"
    while name in taken:
        name += "_"
    return name


def untimed_view(package: Package) -> Package:
    """The package the untimed engine runs: clocks become ``int`` data, rates hidden ``float`` data (1.0), and
    invariants are left to the timed engine."""
    view = copy.deepcopy(package)
    for atom in view.atom_types:
        atom.invariants = []  # checked here, on clocks as well as data
        if not atom.clocks:
            continue
        rates = {c.name: rate_name(atom, c.name) for c in atom.clocks}
        atom.data += [DataDecl("int", c.name, Const(0)) for c in atom.clocks]
        atom.data += [DataDecl("float", rates[c.name], Const(1.0)) for c in atom.clocks]
        if atom.initial is not None:
            atom.initial.action = _rates_as_data(atom.initial.action, rates)
        for t in atom.transitions:
            t.action = _rates_as_data(t.action, rates)
    return view


def _rates_as_data(stmts, rates: dict[str, str]) -> list:
    out = []
    for s in stmts:
        if isinstance(s, Rate):
            out.append(Assign(Var(rates[s.clock]), s.value))
        elif isinstance(s, If):
            out.append(If(s.cond, tuple(_rates_as_data(s.then, rates)), tuple(_rates_as_data(s.orelse, rates))))
        else:
            out.append(s)
    return out


def _clock_comparisons(e, clocks: set[str]) -> list[Binary]:
    """The comparisons of ``e`` that read a clock: the only places where time changes a guard's value."""
    found: list[Binary] = []

    def reads(node) -> bool:
        if isinstance(node, Var):
            return node.name in clocks
        if isinstance(node, Unary):
            return reads(node.operand)
        if isinstance(node, Binary):
            return reads(node.left) or reads(node.right)
        return False

    def walk(node) -> None:
        if isinstance(node, Binary):
            if node.op in _COMPARISONS and reads(node):
                found.append(node)
            else:
                walk(node.left)
                walk(node.right)
        elif isinstance(node, Unary):
            walk(node.operand)

    if e is not None:
        walk(e)
    return found


# ---------------------------------------------------------------------------------------------- per atom
@dataclass
class _Constraint:
    """A guard-like condition of one atom: active when ``mask`` places are marked; ``diffs`` its clock comparisons."""

    mask: int
    holds: Callable[[tuple], bool]
    diffs: list[Callable[[tuple], Any]]
    text: str = ""


@dataclass
class _TimedTransition:
    port: str | None
    sources: int
    urgency: int
    guard: _Constraint
    resume: _Constraint | None


@dataclass
class _AtomTiming:
    index: int
    name: str
    offset: int
    clocks: list[tuple[int, int, int]]  # (slot, rate slot, nanoseconds per unit)
    transitions: list[_TimedTransition] = field(default_factory=list)
    invariants: list[tuple[Invariant, _Constraint]] = field(default_factory=list)
    initial_resume: _Constraint | None = None


class TimedEngine:
    """A timed model on the engine: ``TimedEngine(package, root, externs)``.

    ``engine`` is the untimed engine of :func:`untimed_view`; :meth:`delay`,
    :meth:`windows` and :meth:`schedule` add time on top of its
    ``enabled``/``fire``.  Run it with :func:`runtime.engine.timed_run.run_timed`.
    """

    def __init__(self, package: Package, root: str = "System()", externs: Any = None) -> None:
        self.package = package
        self.engine = Engine(untimed_view(package), root, externs)
        if self.engine.extern is not None:
            raise EngineError(f"extern port {next(iter(self.engine.extern.ports))}: timed runs do not take events "
                              "pushed from outside yet (events carry no time here)")
        flat = self.engine.flat
        self.port_owner = {p.path: (p.atom, p.name) for p in flat.ports}
        self.atoms: list[_AtomTiming] = []
        for fa in flat.atoms:
            a = fa.type
            clocks = {c.name for c in a.clocks}
            timing = _AtomTiming(fa.index, fa.name, fa.offset,
                                 [(fa.slot(c.name), fa.slot(rate_name(self._source_atom(a), c.name)), c.nanoseconds)
                                  for c in a.clocks])
            for t in a.transitions:
                guard = self._constraint(fa, fa.place_mask(t.sources), t.guard, clocks)
                resume = self._constraint(fa, 0, t.resume.guard, clocks) if t.resume is not None else None
                timing.transitions.append(_TimedTransition(t.port, fa.place_mask(t.sources),
                                                           URGENCIES.index(t.urgency or "lazy"), guard, resume))
            for inv in self._source_atom(a).invariants:  # the untimed view has none
                mask = fa.place_mask(inv.places) if inv.places else 0
                timing.invariants.append((inv, self._constraint(fa, mask, inv.guard, clocks)))
            if a.initial is not None and a.initial.resume is not None:
                timing.initial_resume = self._constraint(fa, 0, a.initial.resume.guard, clocks)
            self.atoms.append(timing)
        self.timed_atoms = [t for t in self.atoms if t.clocks or t.invariants]

    def _source_atom(self, atom: AtomType) -> AtomType:
        return next(a for a in self.package.atom_types if a.name == atom.name)

    def _compile(self, fa, e) -> Callable[[tuple], Any]:
        return compile_state_expr(self.engine.flat, self.engine.namespace, fa, e)

    def _constraint(self, fa, mask: int, e, clocks: set[str]) -> _Constraint:
        if e is None:
            return _Constraint(mask, lambda s: True, [], "true")
        diffs = [self._compile(fa, Binary("-", c.left, c.right)) for c in _clock_comparisons(e, clocks)]
        return _Constraint(mask, self._compile(fa, e), diffs, print_expr(e))

    # -- time ---------------------------------------------------------------------------------------
    def delay(self, state: tuple, d) -> tuple:
        """``state`` after ``d`` nanoseconds: every clock advanced by ``d * rate / unit`` (exact; ints when whole)."""
        if not d:
            return state
        s = list(state)
        for a in self.timed_atoms:
            for slot, rate_slot, unit in a.clocks:
                rate = s[rate_slot]
                step = _ratio(d, unit) if rate == 1 else Fraction(d) * Fraction(rate) / unit
                s[slot] = exact(s[slot] + step)
        return tuple(s)

    def critical_delays(self, state: tuple, constraints: list[tuple[int, _Constraint]]) -> list:
        """The delays (> 0) where one of the clock comparisons of ``constraints`` changes value."""
        later = self.delay(state, SECOND)
        roots = set()
        for _atom, c in constraints:
            for diff in c.diffs:
                f0, f1 = diff(state), diff(later)
                slope = f1 - f0
                if slope:
                    root = _ratio(-f0 * SECOND, slope)
                    if root > 0:
                        roots.add(root)
        return sorted(roots)

    def relevant(self, state: tuple, resuming: frozenset[int] = frozenset()) -> list[tuple[int, _Constraint]]:
        """Guards of transitions whose source places are marked, and invariants in force, with their atom."""
        out = []
        for a in self.timed_atoms:
            if a.index in resuming:
                continue
            marking = state[a.offset]
            out += [(a.index, t.guard) for t in a.transitions if marking & t.sources == t.sources and t.guard.diffs]
            out += [(a.index, c) for inv, c in a.invariants if inv.in_force(marking, c.mask) and c.diffs]
        return out

    @staticmethod
    def samples(points: list[Fraction]) -> list[Fraction]:
        """0, every critical point, a point between each two, and one beyond the last (which stands for +inf)."""
        pts = [0] + [p for p in points if p > 0]
        out = []
        for i, p in enumerate(pts):
            out.append(p)
            nxt = pts[i + 1] if i + 1 < len(pts) else p + SECOND
            out.append(exact((p + nxt) / 2) if nxt - p < 2 else p + (nxt - p) // 2)  # any instant strictly between
        return out

    @staticmethod
    def window_of(flags: list[bool], samples: list[Fraction]) -> Window | None:
        """The first run of delays where ``flags`` hold, as a window (samples alternate point, between)."""
        try:
            first = flags.index(True)
        except ValueError:
            return None
        last = first
        while last + 1 < len(flags) and flags[last + 1]:
            last += 1
        if first % 2 == 0:
            lo, lo_open = samples[first], False
        else:
            lo, lo_open = samples[first - 1], True
        if last == len(flags) - 1:
            return Window(lo, None, lo_open)
        if last % 2 == 0:
            return Window(lo, samples[last], lo_open, False)
        return Window(lo, samples[last + 1], lo_open, True)

    def urgency(self, state: tuple, inter: Interaction) -> int:
        """The strongest urgency among the transitions the interaction's ports may fire (lazy = 0)."""
        best = 0
        for path in inter.ports:
            atom, port = self.port_owner[path]
            a = self.atoms[atom]
            marking = state[a.offset]
            for t in a.transitions:
                if t.port == port and marking & t.sources == t.sources:
                    best = max(best, t.urgency)
        return best

    def invariants_broken(self, state: tuple, skip: frozenset[int] = frozenset()) -> list[str]:
        """``atom.invariant`` of every invariant in force that does not hold at ``state``."""
        out = []
        for a in self.timed_atoms:
            if a.index in skip:
                continue
            for inv, c in a.invariants:
                if inv.in_force(state[a.offset], c.mask) and not c.holds(state):
                    out.append(f"{a.name}.{inv.name}")
        return out

    def schedule(self, state: tuple, resuming: frozenset[int] = frozenset()) -> "Schedule":
        """The enabled interactions with the delays where each may fire, and how far time may pass.

        Samples are evaluated in increasing delay and only up to the bound on time found so far: nothing
        beyond it can fire from this state.
        """
        samples = self.samples(self.critical_delays(state, self.relevant(state, resuming)))
        invariants = [c for a in self.timed_atoms if a.index not in resuming
                      for inv, c in a.invariants if inv.in_force(state[a.offset], c.mask)]
        flags: dict[Interaction, list[bool]] = {}
        held: list[list[bool]] = [[] for _ in invariants]
        urgency: dict[Interaction, int] = {}
        wait, n = ALWAYS, 0
        for k, d in enumerate(samples):
            if wait.hi is not None and d > wait.hi:
                break
            at = self.delay(state, d)
            for inter in self.engine.enabled(at):
                if resuming and self._touches(inter, resuming):
                    continue
                if inter not in flags:
                    flags[inter] = [False] * k
                    urgency[inter] = self.urgency(state, inter)
                flags[inter].append(True)
            for f in flags.values():
                if len(f) == k:
                    f.append(False)
            for c, h in zip(invariants, held):
                h.append(bool(c.holds(at)))
            n = k + 1
            wait = self._wait(flags, urgency, held, samples[:n])
        cut = samples[:n]
        windows = {i: w for i, f in flags.items() if (w := self.window_of(f, cut)) is not None}
        candidates = {i: w & wait for i, w in windows.items() if not (w & wait).empty()}
        return Schedule(candidates, wait, windows)

    def _wait(self, flags, urgency, held, samples) -> Window:
        wait = ALWAYS
        for inter, f in flags.items():
            w = self.window_of(f, samples)
            if w is not None:
                wait = wait & urgent_bound(w, URGENCIES[urgency[inter]])
        for h in held:
            w = self.window_of(h, samples)
            wait = wait & (w if w is not None and w.lo == 0 and not w.lo_open else Window(0, 0, False, True))
        return wait

    def _touches(self, inter: Interaction, atoms: frozenset[int]) -> bool:
        return any(self.port_owner[p][0] in atoms for p in inter.ports)

    def resume_window(self, state: tuple, atoms: dict[int, _Constraint]) -> Window:
        """Delays at which every atom of ``atoms`` may resume (its resume guard holds)."""
        constraints = [(i, c) for i, c in atoms.items()]
        samples = self.samples(self.critical_delays(state, constraints))
        at = [self.delay(state, d) for d in samples]
        w = ALWAYS
        for _i, c in constraints:
            got = self.window_of([c.holds(s) for s in at], samples)
            w = w & (got if got is not None else Window(0, 0, False, True))
        return w

    def fired_resumes(self, state: tuple, inter: Interaction) -> dict[int, _Constraint]:
        """The atoms whose transition fired by ``inter`` at ``state`` has a ``resume``, with its guard."""
        out = {}
        for path in inter.ports:
            atom, port = self.port_owner[path]
            a = self.atoms[atom]
            marking = state[a.offset]
            for t in a.transitions:
                if t.port == port and marking & t.sources == t.sources and t.resume is not None \
                        and t.guard.holds(state):
                    out[atom] = t.resume
        return out


@dataclass
class Schedule:
    """At one state: ``candidates`` (interaction -> delays where it may fire within ``wait``), ``wait`` (how far
    time may pass), ``windows`` (each enabled interaction's own delays)."""

    candidates: dict[Interaction, Window]
    wait: Window
    windows: dict[Interaction, Window]

    def time_lock(self) -> bool:
        return not self.candidates and self.wait.hi is not None


class TimeSafetyViolation(ModelError):
    """Time went past a deadline: an action took longer than a timing constraint allowed (exit 7 in Verimag)."""
