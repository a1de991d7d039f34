"""What a zone explorer reads from a tick-encoded timed model, and the same model with its clocks taken out.

A timed model (``@timed`` package, genom2bip's time and platform
transformations) counts time with a ``tick`` connector and integer clocks:
atom data annotated ``@clock``.  :func:`analyse` reads, from the flat system:

* each clock's place in a zone (index 1..n) and its first value;
* per atom transition, the clock part of its guard (``clock op expression``
  conjuncts, the expression free of clocks) and the clocks its action resets;
* per atom place, what its ``tick`` transition needs (its guard's clock part:
  a bound time cannot pass) and which clocks advance there (a clock that
  stands still must be one no guard reads before its next reset);
* the compound priorities that make time wait (``tick < H``: H is urgent),
  those whose guard reads clocks (EDF), and those whose high side needs a
  clock (a period that opens at ``t >= ticks``): the zone explorer applies
  these itself;
* observers: the clock condition under which one is in ERROR.

The *erased* package is the model without ``tick``, without clock guards and
resets and without those priorities: the engine explores it as any model
(compiled or in Python), and the zone explorer adds the clocks back, a zone
per discrete state (runtime/zones/search.py).  Anything outside this
fragment raises :class:`Unsupported` with what and where.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field, replace

from runtime.engine.flatten import FlatSystem, flatten
from runtime.model import Annotation, Assign, Binary, Const, If, Package, PortData, Transition, Unary, Var
from runtime.model.expressions import Expr, assigned

CLOCK = "tick_clock"
TICK = "tick"
OPS = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "==": "=="}


class Unsupported(Exception):
    """The model is outside what the zone explorer takes; the message says what and where."""


@dataclass(frozen=True)
class Atom:
    """``clock op rhs`` (rhs a discrete expression of the atom, or a constant): one conjunct of a guard."""

    clock: int  # zone index, 1..n
    op: str
    rhs: Expr


@dataclass(frozen=True)
class Diagonal:
    """``ci - cj op k`` between two clocks (compound priority guards: EDF compares time left)."""

    i: int
    j: int
    op: str
    k: int


@dataclass
class Step:
    """The clock side of one atom transition."""

    atoms: list[Atom] = field(default_factory=list)
    resets: list[tuple[int, Expr]] = field(default_factory=list)


@dataclass
class Place:
    """The clock side of one place of one atom: what time passing needs there and which clocks advance."""

    ticks: bool = False  # a tick transition leaves the place
    atoms: list[Atom] = field(default_factory=list)  # its guard's clock part
    discrete: Expr | None = None  # its guard's discrete part
    advancing: set[int] = field(default_factory=set)
    active: set[int] = field(default_factory=set)  # clocks some guard may read before their next reset
    atoms_read: set[int] = field(default_factory=set)  # clocks read there besides guards (observers, queries)
    ceilings: dict[int, tuple[int, int]] = field(default_factory=dict)  # clock -> (L, U): the largest constants
    # (+1) a guard may bound it with from below and from above before its next reset, from here (Extra_LU)
    capped: dict[int, int] = field(default_factory=dict)  # clock -> k: the tick here stops it at k


@dataclass
class Rule:
    """A compound priority, applied by the zone explorer (the erased package has none)."""

    name: str
    low: tuple  # (connector id, mask) entries of the original flat system
    high: tuple
    guard: object  # None, a list of Diagonal (clocks), or the FlatPriority whose guard reads discrete data


@dataclass
class TimedModel:
    flat: FlatSystem  # of the original model
    erased: Package
    root: str
    clocks: list[tuple[int, str]]  # zone index - 1 -> (atom index, variable)
    initial: dict[int, int]  # clock -> first value
    steps: dict[tuple[int, str, int], Step]  # (atom, port or "" for internal, place bit) -> clock side
    places: dict[tuple[int, int], Place]  # (atom, place bit) -> clock side
    timed_atoms: list[int]  # atoms whose tick port the tick connector binds
    urgent: list[tuple]  # high patterns of tick < H
    rules: list[Rule]  # priorities applied on zones
    observers: dict[int, tuple[str, int, Expr]]  # observer atom -> (watching place, clock, bound): ERROR past it
    ceilings: list[int]  # per zone index (0 first): the largest constant each clock is compared with
    measures: dict[int, tuple[str, int]] = field(default_factory=dict)  # response observer -> (watching place, clock)
    #: Clocks read only for how large they grow (an observer's ``c > bound``, a response time): a zone keeps their
    #: upper bounds only (:func:`runtime.zones.dbm.forget_below`).
    grow_only: list[int] = field(default_factory=list)

    def discrete_reads(self) -> set[tuple[str, str]]:
        """``(atom, variable)`` the clock side reads (bounds such as ``hi``): the erased model must keep them."""
        out = set()

        def names(e, fa) -> None:
            if isinstance(e, Var) and e.name not in fa.constants:
                out.add((fa.name, e.name))
            elif isinstance(e, Binary):
                names(e.left, fa)
                names(e.right, fa)
            elif isinstance(e, Unary):
                names(e.operand, fa)

        for (atom, _, _), step in self.steps.items():
            for a in step.atoms:
                names(a.rhs, self.flat.atoms[atom])
            for _, e in step.resets:
                names(e, self.flat.atoms[atom])
        for (atom, _), place in self.places.items():
            for a in place.atoms:
                names(a.rhs, self.flat.atoms[atom])
            if place.discrete is not None:
                names(place.discrete, self.flat.atoms[atom])
        for atom, (_, _, bound) in self.observers.items():
            names(bound, self.flat.atoms[atom])
        return out

    def clock_of(self, atom: int, var: str) -> int | None:
        for k, (a, v) in enumerate(self.clocks):
            if a == atom and v == var:
                return k + 1
        return None


def _conjuncts(e: Expr | None) -> list[Expr]:
    if e is None:
        return []
    if isinstance(e, Binary) and e.op == "&&":
        return _conjuncts(e.left) + _conjuncts(e.right)
    return [e]


def _conjunction(parts: list[Expr]) -> Expr | None:
    out = None
    for p in parts:
        out = p if out is None else Binary("&&", out, p)
    return out


def _mentions(e: Expr, names: set[str]) -> bool:
    if isinstance(e, Var):
        return e.name in names
    if isinstance(e, Binary):
        return _mentions(e.left, names) or _mentions(e.right, names)
    if isinstance(e, Unary):
        return _mentions(e.operand, names)
    return False


def _split(guard: Expr | None, clocks: dict[str, int], where: str) -> tuple[list[Atom], Expr | None]:
    """A guard's clock conjuncts (``clock op rhs``) and the rest."""
    atoms, rest = [], []
    names = set(clocks)
    for c in _conjuncts(guard):
        if not _mentions(c, names):
            rest.append(c)
            continue
        if isinstance(c, Binary) and c.op in OPS:
            if isinstance(c.left, Var) and c.left.name in names and not _mentions(c.right, names):
                atoms.append(Atom(clocks[c.left.name], c.op, c.right))
                continue
            if isinstance(c.right, Var) and c.right.name in names and not _mentions(c.left, names):
                atoms.append(Atom(clocks[c.right.name], OPS[c.op], c.left))
                continue
        raise Unsupported(f"{where}: the guard part '{c}' is not 'clock op expression'")
    return atoms, _conjunction(rest)


def _advances(action, clock: str) -> bool:
    """The tick action makes ``clock`` one tick older (``c = c + 1``, or capped: ``if (c < k) c = c + 1``)."""
    for s in action:
        if isinstance(s, Assign) and s.target == Var(clock):
            return s.value == Binary("+", Var(clock), Const(1))
        if isinstance(s, If) and any(isinstance(t, Assign) and t.target == Var(clock) for t in s.then):
            return True
    return False


def _resets(action, clocks: dict[str, int], where: str) -> list[tuple[int, Expr]]:
    out = []
    for s in action:
        if isinstance(s, Assign) and isinstance(s.target, Var) and s.target.name in clocks:
            if _mentions(s.value, set(clocks)):
                raise Unsupported(f"{where}: clock {s.target.name} is set from a clock")
            out.append((clocks[s.target.name], s.value))
        elif isinstance(s, If) and assigned([s]) & set(clocks):
            raise Unsupported(f"{where}: a clock is set under a condition")
    return out


def _without_clocks(action, clocks: set[str]) -> list:
    return [s for s in action if not (isinstance(s, Assign) and isinstance(s.target, Var) and s.target.name in clocks)]


def _diagonals(guard: Expr, slot_clock: dict[int, int], data: dict, where: str) -> list[Diagonal]:
    """A compound priority guard over clocks as ``ci - cj op k`` conjuncts (linear terms, two clocks at most)."""
    out = []
    for c in _conjuncts(guard):
        if not (isinstance(c, Binary) and c.op in OPS):
            raise Unsupported(f"{where}: the guard part '{c}' is not a comparison")
        terms: dict[int, int] = {}
        const = [0]

        def walk(e: Expr, sign: int) -> None:
            if isinstance(e, Const) and isinstance(e.value, int) and not isinstance(e.value, bool):
                const[0] += sign * e.value
            elif isinstance(e, PortData) and (e.port, e.name) in data and data[(e.port, e.name)][0] in slot_clock:
                k = slot_clock[data[(e.port, e.name)][0]]
                terms[k] = terms.get(k, 0) + sign
            elif isinstance(e, Binary) and e.op in ("+", "-"):
                walk(e.left, sign)
                walk(e.right, sign if e.op == "+" else -sign)
            else:
                raise Unsupported(f"{where}: '{e}' in a priority guard is neither a clock nor an integer")

        walk(c.left, 1)
        walk(c.right, -1)  # left - right op 0
        terms = {k: v for k, v in terms.items() if v}
        pos = [k for k, v in terms.items() if v == 1]
        neg = [k for k, v in terms.items() if v == -1]
        if len(terms) != len(pos) + len(neg) or len(pos) > 1 or len(neg) > 1:
            raise Unsupported(f"{where}: '{c}' is not a difference of two clocks")
        out.append(Diagonal(pos[0] if pos else 0, neg[0] if neg else 0, c.op, -const[0]))
    return out


def analyse(package: Package, root: str) -> TimedModel:
    """Read the clocks of a timed model and build its erased package (see the module docstring)."""
    flat = flatten(package, root)
    clocks: list[tuple[int, str]] = []
    per_atom: dict[int, dict[str, int]] = {}
    for fa in flat.atoms:
        mine = {}
        for d in fa.variables:
            if any(a.name == CLOCK for a in d.annotations):
                clocks.append((fa.index, d.name))
                mine[d.name] = len(clocks)
        per_atom[fa.index] = mine
    if not clocks:
        raise Unsupported("the model has no @clock data: build it with --timed")
    tick = [fc for fc in flat.connectors if fc.label == TICK]
    if len(tick) != 1:
        raise Unsupported("the model has no single connector labelled 'tick'")
    timed_atoms = sorted({flat.ports[p].atom for p in flat.leaves(tick[0])})

    steps: dict[tuple[int, str, int], Step] = {}
    places: dict[tuple[int, int], Place] = {}
    observers: dict[int, tuple[str, int, Expr]] = {}
    measures: dict[int, tuple[str, int]] = {}
    initial: dict[int, int] = {}
    ceilings = [0] * (len(clocks) + 1)
    consts: dict[tuple, dict[int, int]] = {}  # (atom, place bit, "L" or "U") -> clock -> its guards' largest bound + 1
    dynamic: set[int] = set()
    erased_types = {}
    for fa in flat.atoms:
        mine = per_atom[fa.index]
        t = fa.type
        observer = any(a.name == "observer" for a in t.annotations)
        if any(a.name == "observer" and a.arguments.get("kind") == "response" for a in t.annotations):
            measures[fa.index] = ("WATCH", mine["c"])
        for s in t.initial.action if t.initial else []:
            if isinstance(s, Assign) and isinstance(s.target, Var) and s.target.name in mine:
                initial[mine[s.target.name]] = int(_value(s.value, fa, None))
        for k, p in enumerate(fa.places):
            places[(fa.index, 1 << k)] = Place()
        for tr in t.transitions:
            where = f"atom {fa.name} ({t.name}), transition {tr.port or 'internal'} from {','.join(tr.sources)}"
            if len(tr.sources) != 1:
                if mine:
                    raise Unsupported(f"{where}: a timed atom's transition leaves one place")
                continue
            bit = 1 << fa.places.index(tr.sources[0])
            atoms, rest = _split(tr.guard, mine, where)
            low, up = (consts.setdefault((fa.index, bit, side), {}) for side in "LU")
            for a in atoms:
                v = _static(a.rhs, fa)
                if v is not None:
                    ceilings[a.clock] = max(ceilings[a.clock], int(v) + 1)
                    for side, ops in ((low, (">", ">=", "==")), (up, ("<", "<=", "=="))):
                        if a.op in ops:
                            side[a.clock] = max(side.get(a.clock, 0), int(v) + 1)
                else:
                    dynamic.add(a.clock)  # compared with data: no ceiling is known, never extrapolated
            if tr.port == TICK and fa.index in timed_atoms:
                for st in tr.action:  # a capped clock (``if (c < k) c = c + 1``) tells values apart up to k only
                    if isinstance(st, If) and isinstance(st.cond, Binary) and isinstance(st.cond.left, Var) \
                            and st.cond.left.name in mine:
                        v = _static(st.cond.right, fa)
                        if v is not None:
                            k = mine[st.cond.left.name]
                            places[(fa.index, bit)].capped[k] = int(v)
                            ceilings[k] = max(ceilings[k], int(v))
                            for side in (low, up):
                                side[k] = max(side.get(k, 0), int(v))
                place = places[(fa.index, bit)]
                place.ticks = True
                place.atoms, place.discrete = atoms, rest
                place.advancing = {c for name, c in mine.items() if _advances(tr.action, name)}
                if assigned(tr.action) - set(mine):
                    raise Unsupported(f"{where}: time changes discrete data")
                continue
            if tr.port is None and atoms:
                if not observer:
                    raise Unsupported(f"{where}: an internal transition waits for a clock (make it a port)")
                if len(atoms) != 1 or atoms[0].op not in (">", ">="):
                    raise Unsupported(f"{where}: an observer's error condition is one 'clock > bound'")
                a = atoms[0]
                bound = a.rhs if a.op == ">" else Binary("-", a.rhs, Const(1))
                observers[fa.index] = (tr.sources[0], a.clock, bound)
                continue
            steps[(fa.index, tr.port or "", bit)] = Step(atoms, _resets(tr.action, mine, where))
        erased_types[t.name] = t
    for atom, (watching, clock, *_) in list(observers.items()) + list(measures.items()):  # read there by queries
        places[(atom, 1 << flat.atoms[atom].places.index(watching))].atoms_read.add(clock)
    for k in dynamic:
        ceilings[k] = 0  # 0: no ceiling (the explorer never extrapolates that clock's bounds)
    model = TimedModel(flat, package, root, clocks, initial, steps, places, timed_atoms, [], [], observers, ceilings,
                       measures)
    model.erased, model.urgent, model.rules = _erase(package, flat, model, per_atom, tick[0])
    _no_capped_differences(model)
    _read_by_priorities(flat, model)
    _activity(flat, places, steps, per_atom)
    _local_ceilings(flat, model, per_atom, consts, dynamic)
    model.grow_only = _grow_only(model, dynamic)
    return model


#: The L or U of a clock no guard ahead bounds from that side: below every bound a clock can have (Extra_LU's
#: minus infinity; the constants are kept as the largest bound + 1, so -2 is already below 0 - 1).  A clock above
#: it has no bound left on that side, which is what TChecker's ExtraLU+ does with an absent constant.
NO_BOUND = -2


def _local_ceilings(flat, model: TimedModel, per_atom, consts, dynamic: set[int]) -> None:
    """Per place, each active clock's largest constants a guard may bound it with, from below (L) and from above
    (U), before its next reset (Behrmann, Bouyer, Larsen, Pelanek: Extra_LU with a static guard analysis): zones
    then forget what no guard ahead can tell apart.

    Kept global (the model's ceiling): clocks compared with data, clocks a priority compares with another clock
    (EDF's time left: a diagonal constraint, where a smaller bound would not be sound), and clocks read by
    observers and response times (their values are the answer)."""
    keep = set(dynamic)
    for rule in model.rules:
        if isinstance(rule.guard, list):
            keep |= {k for d in rule.guard for k in (d.i, d.j) if k}
    for place in model.places.values():
        keep |= place.atoms_read
    keep |= {clock for _, clock, _ in model.observers.values()} | {clock for _, clock in model.measures.values()}
    for fa in flat.atoms:
        mine = set(per_atom[fa.index].values()) - keep
        if not mine:
            continue
        local = {(1 << k, side): {c: v for c, v in consts.get((fa.index, 1 << k, side), {}).items() if c in mine}
                 for k in range(len(fa.places)) for side in "LU"}
        edges = []
        for tr in fa.type.transitions:
            if len(tr.sources) != 1:
                continue
            bit = 1 << fa.places.index(tr.sources[0])
            step = model.steps.get((fa.index, tr.port or "", bit))
            reset = {c for c, _ in step.resets} if step is not None else set()
            edges += [(bit, 1 << fa.places.index(t), reset) for t in tr.targets]
        changed = True
        while changed:
            changed = False
            for bit, target, reset in edges:
                for side in "LU":
                    ahead, here = local[(target, side)], local[(bit, side)]
                    for c, v in ahead.items():
                        if c not in reset and here.get(c, 0) < v:
                            here[c] = v
                            changed = True
        for k in range(len(fa.places)):
            place = model.places[(fa.index, 1 << k)]
            low, up = local[(1 << k, "L")], local[(1 << k, "U")]
            place.ceilings = {c: (low.get(c, NO_BOUND), up.get(c, NO_BOUND))
                              for c in (set(low) | set(up)) & place.active}


def _grow_only(model: TimedModel, dynamic: set[int]) -> list[int]:
    """The observers' and response times' clocks that no guard, invariant or priority reads.  From a valuation
    with a larger such clock, every run of one with a smaller value is a run too, on which that clock is larger:
    an observer's ``c > bound`` and the largest value are the same whatever lower bounds it had, so zones need
    not tell them apart (an LU abstraction with no upper-bound constant for that clock)."""
    read = set(dynamic)
    for step in model.steps.values():
        read |= {a.clock for a in step.atoms}
    for place in model.places.values():
        read |= {a.clock for a in place.atoms}
    for rule in model.rules:
        if isinstance(rule.guard, list):
            read |= {k for d in rule.guard for k in (d.i, d.j) if k}
    watched = {clock for _, clock, _ in model.observers.values()} | {clock for _, clock in model.measures.values()}
    return sorted(watched - read)


def _no_capped_differences(model: TimedModel) -> None:
    """A clock its tick caps (``if (c < k) c = c + 1``) stands still at ``k``, which a zone's clock does not: past
    ``k`` its difference with another clock is not the model's, so no priority may compare the two."""
    capped = {k for place in model.places.values() for k in place.capped}
    for rule in model.rules:
        for d in rule.guard if isinstance(rule.guard, list) else []:
            both = [k for k in (d.i, d.j) if k]
            if len(both) == 2 and any(k in capped for k in both):
                atom, var = model.clocks[next(k for k in both if k in capped) - 1]
                raise Unsupported(f"priority {rule.name}: compares {model.flat.atoms[atom].name}.{var}, a clock its "
                                  "tick caps, with another clock (past the cap their difference is not the zones')")


def _read_by_priorities(flat: FlatSystem, model: TimedModel) -> None:
    """A clock a priority guard compares (EDF's time left) is read where its atom can take part in that priority."""
    for rule in model.rules:
        if not isinstance(rule.guard, list):
            continue
        clocks = {k for d in rule.guard for k in (d.i, d.j) if k}
        ports = {p for cid, _ in rule.low + rule.high for p in flat.leaves(flat.connectors[cid])}
        for k in clocks:
            atom = model.clocks[k - 1][0]
            fa = flat.atoms[atom]
            names = {flat.ports[p].name for p in ports if flat.ports[p].atom == atom}
            for tr in fa.type.transitions:
                if tr.port in names and len(tr.sources) == 1:
                    model.places[(atom, 1 << fa.places.index(tr.sources[0]))].atoms_read.add(k)


def _static(e: Expr, fa) -> int | None:
    """The value of a constant expression of the atom (parameters, constants), None when it reads data."""
    try:
        return int(_value(e, fa, None))
    except KeyError:
        return None


def _value(e: Expr, fa, state) -> int:
    """An integer expression of atom ``fa`` on an engine state (data from the state, parameters from the instance)."""
    if isinstance(e, Const):
        return int(e.value)
    if isinstance(e, Var):
        if e.name in fa.constants:
            return int(fa.constants[e.name][0])
        if state is None:
            raise KeyError(e.name)
        return int(state[fa.slot(e.name)])
    if isinstance(e, Unary) and e.op == "-":
        return -_value(e.operand, fa, state)
    if isinstance(e, Binary) and e.op in ("+", "-", "*"):
        a, b = _value(e.left, fa, state), _value(e.right, fa, state)
        return a + b if e.op == "+" else a - b if e.op == "-" else a * b
    raise Unsupported(f"atom {fa.name}: '{e}' is not an integer expression of its data")


def value(e: Expr, fa, state) -> int:
    return _value(e, fa, state)


def holds(pr, state) -> bool:
    """A compound priority's guard over discrete exported data, on an engine state."""

    def ev(e):
        if isinstance(e, Const):
            return e.value
        if isinstance(e, PortData):
            return state[pr.data[(e.port, e.name)][0]]
        if isinstance(e, Var) and e.name in pr.constants:
            return pr.constants[e.name][0]
        if isinstance(e, Unary):
            v = ev(e.operand)
            return (not v) if e.op == "!" else -v if e.op == "-" else v
        if isinstance(e, Binary):
            if e.op == "&&":
                return ev(e.left) and ev(e.right)
            if e.op == "||":
                return ev(e.left) or ev(e.right)
            a, b = ev(e.left), ev(e.right)
            return {"+": a + b, "-": a - b, "*": a * b, "<": a < b, "<=": a <= b, ">": a > b, ">=": a >= b,
                    "==": a == b, "!=": a != b}[e.op]
        raise Unsupported(f"priority {pr.name}: '{e}' in its guard")

    return bool(ev(pr.guard))


def _ahead(here: dict[int, set], out: dict[int, list[tuple[int, set[int]]]], clock) -> dict[int, set]:
    """Per place, what ``here`` holds there or at a place reached before the reset of its ``clock``."""
    ahead = {bit: set(r) for bit, r in here.items()}
    changed = True
    while changed:
        changed = False
        for bit, edges in out.items():
            for target, reset in edges:
                more = {r for r in ahead[target] if clock(r) not in reset} - ahead[bit]
                if more:
                    ahead[bit] |= more
                    changed = True
    return ahead


#: For ``clock op c`` and a clock stopped at k: the comparisons that read the same of k and of any value past it.
_SAME_PAST_CAP = {">=": lambda c, k: c <= k, ">": lambda c, k: c < k, "<": lambda c, k: c <= k,
                  "<=": lambda c, k: c < k, "==": lambda c, k: c < k, "!=": lambda c, k: c < k}


def _cap_kept(fa, bit: int, place: Place, compared: set[tuple], names: dict[str, int]) -> None:
    """A clock its tick stops at k in ``place`` must be read, before its next reset, only where a zone's clock,
    which goes on, reads the same: against constants that do not tell k from what lies past it."""
    for clock, op, c in sorted(compared, key=repr):
        k = place.capped.get(clock)
        if k is None or (c is not None and _SAME_PAST_CAP[op](c, k)):
            continue
        name = next(n for n, i in names.items() if i == clock)
        raise Unsupported(f"atom {fa.name}: clock {name}, which its tick stops at {k} in place "
                          f"{fa.places[bit.bit_length() - 1]}, is then compared ({op}) with "
                          f"{'data' if c is None else c}: past {k} the zones' clock is not the model's")


def _activity(flat, places, steps, per_atom) -> None:
    """Per place, the clocks some guard may read before their next reset (the others are forgotten there)."""
    for fa in flat.atoms:
        mine = set(per_atom[fa.index].values())
        if not mine:
            continue
        out: dict[int, list[tuple[int, set[int]]]] = {}  # place -> (target, resets)
        reads: dict[int, set[int]] = {}
        compares: dict[int, set[tuple]] = {}  # place -> its guards' (clock, op, constant or None for data)
        for k in range(len(fa.places)):
            bit = 1 << k
            p = places[(fa.index, bit)]
            reads[bit] = {a.clock for a in p.atoms} | p.atoms_read
            compares[bit] = {(a.clock, a.op, _static(a.rhs, fa)) for a in p.atoms}
        for tr in fa.type.transitions:
            if len(tr.sources) != 1:
                continue
            bit = 1 << fa.places.index(tr.sources[0])
            step = steps.get((fa.index, tr.port or "", bit))
            if step is None:
                continue
            reads[bit] |= {a.clock for a in step.atoms}
            compares[bit] |= {(a.clock, a.op, _static(a.rhs, fa)) for a in step.atoms}
            for target in tr.targets:
                out.setdefault(bit, []).append((1 << fa.places.index(target), {c for c, _ in step.resets}))
        active = _ahead(reads, out, lambda c: c)
        compared = _ahead(compares, out, lambda c: c[0])
        for bit, a in active.items():
            place = places[(fa.index, bit)]
            _cap_kept(fa, bit, place, compared[bit], per_atom[fa.index])
            place.active = a & mine
            stopped = place.active - place.advancing
            if place.ticks and stopped:
                names = ", ".join(n for n, k in per_atom[fa.index].items() if k in stopped)
                raise Unsupported(f"atom {fa.name}: clock(s) {names} stand still in place "
                                  f"{fa.places[bit.bit_length() - 1]} while a guard may read them")


def _erase(package: Package, flat: FlatSystem, model: TimedModel, per_atom, tick) -> tuple[Package, list, list[Rule]]:
    """The package without tick, clock guards, clock resets, observer errors and the priorities zones apply.

    Only what changes is copied (the types, and of a type with clocks its initial transition and clock
    declarations); the rest is shared with ``package``, which nothing changes in place (a deep copy of whole DALA
    took 0.16 s of every timed check)."""
    erased = copy.copy(package)
    erased.atom_types = [copy.copy(t) for t in package.atom_types]
    erased.compound_types = [copy.copy(ct) for ct in package.compound_types]
    clocks_of_type: dict[str, set[str]] = {}
    for fa in flat.atoms:
        if per_atom[fa.index]:
            clocks_of_type[fa.type.name] = set(per_atom[fa.index])
    for t in erased.atom_types:
        names = clocks_of_type.get(t.name)
        if not names:
            continue
        kept = []
        for tr in t.transitions:
            if tr.port == TICK:
                continue
            atoms, rest = _split(tr.guard, {n: 0 for n in names}, t.name)
            if tr.port is None and atoms:
                continue  # an observer's error: a query of the zone explorer
            kept.append(Transition(tr.port, list(tr.sources), list(tr.targets), rest,
                                   _without_clocks(tr.action, names), annotations=list(tr.annotations),
                                   span=tr.span))
        t.transitions = kept
        if t.initial:
            t.initial = replace(t.initial, action=_without_clocks(t.initial.action, names))
        t.data = [replace(d, annotations=[a for a in d.annotations if a.name != CLOCK]
                          + [Annotation("erased_clock", {})]) if d.name in names else d for d in t.data]
    slot_clock = {flat.atoms[a].slot(v): k + 1 for k, (a, v) in enumerate(model.clocks)}
    rules = []
    for pr in flat.priorities:
        clocked = {k for k, (slot, _) in pr.data.items() if slot in slot_clock}
        if pr.guard is None:
            guard = None
        elif _mentions_data(pr.guard, clocked):
            guard = _diagonals(pr.guard, slot_clock, pr.data, f"priority {pr.name}")
        else:
            guard = pr  # a guard on discrete data: the zone explorer evaluates it on the state
        rules.append(Rule(pr.name, pr.low.entries, pr.high.entries, guard))
    for ct in erased.compound_types:  # every compound priority is the zone explorer's (runtime/zones/search.py)
        ct.priorities = []
    _drop_connector(erased, tick)
    urgent = [r.high for r in rules if any(c == tick.id for c, _ in r.low)]
    return erased, urgent, rules


def _mentions_data(e: Expr, names: set) -> bool:
    if isinstance(e, PortData):
        return (e.port, e.name) in names
    if isinstance(e, Binary):
        return _mentions_data(e.left, names) or _mentions_data(e.right, names)
    if isinstance(e, Unary):
        return _mentions_data(e.operand, names)
    return False


def _drop_connector(package: Package, fc) -> None:
    scope_type = None
    for ct in package.compound_types:
        if any(c.name == fc.path.rsplit(".", 1)[-1] and any(a.name == "label" and a.arguments.get("name") == TICK
                                                             for a in c.annotations) for c in ct.connectors):
            scope_type = ct
    if scope_type is None:
        raise Unsupported("cannot find the tick connector's compound")
    scope_type.connectors = [c for c in scope_type.connectors
                             if not any(a.name == "label" and a.arguments.get("name") == TICK for a in c.annotations)]
