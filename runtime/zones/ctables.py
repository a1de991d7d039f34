"""The clock side of a timed model as the flat table zprogram.c reads (its layout is that file's ``tables_read``).

Expressions become postfix code with the semantics of runtime/zones/model.py's ``value`` (clock bounds,
resets, invariants, observers' bounds) and ``holds`` (compound priorities' guards); one the code cannot say
exactly (a float or a string slot, an operator those functions refuse) is written as -2, and the C side then
hands every state that needs it back to ZoneExplorer.program(), which computes or refuses it.
"""
from __future__ import annotations

from runtime.model import Binary, Const, PortData, Unary, Var

OPS = {"+": 4, "-": 5, "*": 6, "<": 7, "<=": 8, ">": 9, ">=": 10, "==": 11, "!=": 12, "&&": 13, "||": 14}
END, CONST, SLOT, NEG, NOT = 0, 1, 2, 3, 15
CLOCK_OPS = {"<": 0, "<=": 1, ">": 2, ">=": 3, "==": 4}
UNSUPPORTED = -2


class _Refused(Exception):
    pass


class Code:
    """The expression pool: each expression's offset, its code ending with END."""

    def __init__(self, inexact: set[int]) -> None:
        self.words: list[int] = []
        self.inexact = inexact  # slots whose words are not their integer value (floats, strings)

    def value(self, e, fa) -> int:
        """An integer expression of atom ``fa`` (model.value's fragment)."""
        def walk(e, out) -> None:
            if isinstance(e, Const):
                if isinstance(e.value, str):
                    raise _Refused
                out += [CONST, int(e.value)]
            elif isinstance(e, Var):
                if e.name in fa.constants:
                    out += [CONST, int(fa.constants[e.name][0])]
                else:
                    slot = fa.slot(e.name)
                    if slot in self.inexact:
                        raise _Refused
                    out += [SLOT, slot]
            elif isinstance(e, Unary) and e.op == "-":
                walk(e.operand, out)
                out.append(NEG)
            elif isinstance(e, Binary) and e.op in ("+", "-", "*"):
                walk(e.left, out)
                walk(e.right, out)
                out.append(OPS[e.op])
            else:
                raise _Refused
        return self._add(walk, e)

    def condition(self, pr) -> int:
        """A compound priority's guard over exported data (model.holds' fragment)."""
        def walk(e, out) -> None:
            if isinstance(e, Const):
                if not isinstance(e.value, (bool, int)):
                    raise _Refused
                out += [CONST, int(e.value)]
            elif isinstance(e, PortData):
                slot = pr.data[(e.port, e.name)][0]
                if slot in self.inexact:
                    raise _Refused
                out += [SLOT, slot]
            elif isinstance(e, Var) and e.name in pr.constants:
                v = pr.constants[e.name][0]
                if not isinstance(v, (bool, int)):
                    raise _Refused
                out += [CONST, int(v)]
            elif isinstance(e, Unary) and e.op in ("!", "-", "+"):
                walk(e.operand, out)
                if e.op != "+":
                    out.append(NOT if e.op == "!" else NEG)
            elif isinstance(e, Binary) and e.op in OPS:
                walk(e.left, out)
                walk(e.right, out)
                out.append(OPS[e.op])
            else:
                raise _Refused
        return self._add(walk, pr.guard)

    def _add(self, walk, e) -> int:
        out: list[int] = []
        try:
            walk(e, out)
        except (_Refused, KeyError, TypeError, ValueError):
            return UNSUPPORTED
        at = len(self.words)
        self.words += out + [END]
        return at


def _atoms(code: Code, atoms, fa) -> list[int]:
    out = [len(atoms)]
    for a in atoms:
        out += [a.clock, CLOCK_OPS[a.op], code.value(a.rhs, fa)]
    return out


def tables(z, width: int, inexact: set[int]) -> tuple[list[int], dict]:
    """The table of ZoneExplorer ``z``'s model (states of ``width`` words), and the step number of each
    ``(atom, port, place bit)``."""
    model, flat = z.model, z.flat
    code = Code(inexact)
    places: list[int] = []
    for fa in flat.atoms:
        for k in range(len(fa.places)):
            p = model.places.get((fa.index, 1 << k))
            if p is None:
                places += [0, -1, 0, 0, 0]
                continue
            discrete = -1 if p.discrete is None else code.value(p.discrete, fa)
            places += [int(p.ticks), discrete, *_atoms(code, p.atoms, fa), len(p.active), *sorted(p.active),
                       len(p.ceilings)]
            for c, (low, up) in sorted(p.ceilings.items()):
                places += [c, low, up]
    steps, step_ids = [], {}
    for key, st in model.steps.items():
        fa = flat.atoms[key[0]]
        step_ids[key] = len(step_ids)
        steps += _atoms(code, st.atoms, fa) + [len(st.resets)]
        for c, e in st.resets:
            steps += [c, code.value(e, fa)]
    rules = []
    for r, rule in enumerate(model.rules):
        if rule.guard is None:
            rules.append(0)
        elif isinstance(rule.guard, list):
            b = z.diagonal_bounds(rule.guard)
            rules += [1, len(b)] + [int(v) for t in b for v in t]
        else:
            at = code.condition(rule.guard)
            rules += [2, at] if at != UNSUPPORTED else [3]
        rules += [len(z.edges[r]), *z.edges[r]]
    observers = []
    for slot, (atom, (watching, clock, bound)) in enumerate(model.observers.items()):
        fa = flat.atoms[atom]
        observers += [atom, fa.places.index(watching), clock, code.value(bound, fa), slot]
    measures = []
    for atom, (place, clock) in model.measures.items():
        measures += [atom, flat.atoms[atom].places.index(place), clock]
    out = [width, z.n, len(flat.atoms), len(model.timed_atoms), len(model.rules), len(z.tick_rules),
           len(model.observers), len(model.measures), len(step_ids), int(z.local_ceilings), len(code.words),
           *code.words]
    out += [fa.offset for fa in flat.atoms] + [len(fa.places) for fa in flat.atoms]
    out += places
    out += [0] + [atom for atom, _ in model.clocks]
    out += list(model.timed_atoms) + steps + rules + list(z.tick_rules) + observers + measures
    goal = z.goal
    out.append(-1 if goal is None else len(goal))
    for group in goal or []:
        out.append(len(group))
        for offset, mask in group:
            out += [offset, mask]
    return out, step_ids


def interaction_row(z, number: int, index: int, step_ids: dict) -> list[int]:
    """What interaction ``number`` of the compiled step is: its engine index, ports with their steps per place,
    and the compound priorities it is low and high in."""
    _, ports, _ = z.interaction(index)
    out = [index, len(ports)]
    for atom, port in ports:
        fa = z.flat.atoms[atom]
        out += [atom, len(fa.places)] + [step_ids.get((atom, port, 1 << k), -1) for k in range(len(fa.places))]
    low, high = z.rules_of(index)
    return out + [len(low), *low, len(high), *high]
