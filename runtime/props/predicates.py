"""State predicates bound to a model: ``atom @ PLACE`` and ``atom.var OP value`` as functions of a state.

Names are checked against the flat system (atom instances, their places and
variables), with ``file:line:column`` errors for unknown ones.  The variables a
property reads are reported so that the explorer keeps them exact (no
dead-variable reset on them).
"""
from __future__ import annotations

import operator
from typing import Callable

from runtime.diagnostics import Diagnostic
from runtime.engine.flatten import FlatSystem
from runtime.props.formulas import PAnd, PAt, PCmp, PConst, PNot, POr, Pred

OPS = {"==": operator.eq, "!=": operator.ne, "<": operator.lt, "<=": operator.le, ">": operator.gt,
       ">=": operator.ge}


def _close(name: str, options: list[str]) -> str:
    import difflib
    near = difflib.get_close_matches(name, options, n=1)
    return f" (did you mean {near[0]}?)" if near else ""


def split_path(flat: FlatSystem, path: str) -> tuple[object, str] | None:
    """``NDD.GoTo.control.done`` -> (atom ``NDD.GoTo.control``, ``done``): the longest atom-name prefix wins."""
    atoms = {a.name: a for a in flat.atoms}
    parts = path.split(".")
    for k in range(len(parts) - 1, 0, -1):
        head = ".".join(parts[:k])
        if head in atoms:
            return atoms[head], ".".join(parts[k:])
    return None


def variables_read(flat: FlatSystem, p: Pred) -> set[tuple[str, str]]:
    """``(atom, variable)`` pairs a predicate reads (unresolvable names are skipped; binding reports them)."""
    out: set[tuple[str, str]] = set()
    if isinstance(p, PCmp):
        got = split_path(flat, p.path)
        if got is not None:
            out.add((got[0].name, got[1]))
    elif isinstance(p, PNot):
        out |= variables_read(flat, p.operand)
    elif isinstance(p, (PAnd, POr)):
        out |= variables_read(flat, p.left) | variables_read(flat, p.right)
    return out


def atoms_read(flat: FlatSystem, p: Pred | None) -> set[int]:
    """Indexes of the atoms a predicate reads (places and variables); every atom where a name does not resolve."""
    if isinstance(p, PAt):
        return {a.index for a in flat.atoms if a.name == p.atom}
    if isinstance(p, PCmp):
        got = split_path(flat, p.path)
        return {got[0].index} if got else {a.index for a in flat.atoms}
    if isinstance(p, PNot):
        return atoms_read(flat, p.operand)
    if isinstance(p, (PAnd, POr)):
        return atoms_read(flat, p.left) | atoms_read(flat, p.right)
    return set()


def bind(flat: FlatSystem, p: Pred, problems: list[Diagnostic]) -> Callable[[tuple], bool]:
    """A function of an engine state for the predicate; unknown names are appended to ``problems``."""
    atoms = {a.name: a for a in flat.atoms}
    if isinstance(p, PConst):
        return (lambda s: True) if p.value else (lambda s: False)
    if isinstance(p, PAt):
        fa = atoms.get(p.atom)
        if fa is None:
            problems.append(Diagnostic(p.span, f"no atom named {p.atom}{_close(p.atom, list(atoms))}"))
            return lambda s: False
        if p.place not in fa.places:
            problems.append(Diagnostic(p.span, f"atom {p.atom} ({fa.type.name}) has no place {p.place}; places: "
                                               f"{', '.join(fa.places)}"))
            return lambda s: False
        slot, bit = fa.offset, 1 << fa.places.index(p.place)
        return lambda s: bool(s[slot] & bit)
    if isinstance(p, PCmp):
        got = split_path(flat, p.path)
        if got is None:
            problems.append(Diagnostic(p.span, f"{p.path} names no variable of an atom (write atom.variable, "
                                               f"e.g. {flat.atoms[0].name}.x){_close(p.path, list(atoms))}"
                                       if flat.atoms else f"{p.path} names no variable"))
            return lambda s: False
        fa, var = got
        names = [d.name for d in fa.variables]
        if var not in names:
            problems.append(Diagnostic(p.span, f"atom {fa.name} ({fa.type.name}) has no variable {var}"
                                               + (f"; variables: {', '.join(names)}" if names else "")))
            return lambda s: False
        slot = fa.slot(var)
        op = OPS[p.op]
        value = p.value
        return lambda s: bool(op(s[slot], value))
    if isinstance(p, PNot):
        f = bind(flat, p.operand, problems)
        return lambda s: not f(s)
    if isinstance(p, PAnd):
        left, right = bind(flat, p.left, problems), bind(flat, p.right, problems)
        return lambda s: left(s) and right(s)
    if isinstance(p, POr):
        left, right = bind(flat, p.left, problems), bind(flat, p.right, problems)
        return lambda s: left(s) or right(s)
    raise TypeError(f"not a predicate: {p!r}")
