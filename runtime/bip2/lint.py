"""The Verimag compiler's warnings on a valid model: non-determinism, dead transitions, unbound ports.

Each check mirrors one rule of bipc's model validation (docs/bip2.md names
them) and is silenced, as bipc silences it, by ``@SuppressWarning(name)`` on
the element or on a declaration that contains it.  Two transitions on one port
(or both internal) from one place with no guard is an error for bipc; here it
stays a warning, so that the engine can still run such a model and report the
conflict where it happens.
"""
from __future__ import annotations

from runtime.bip2.locator import Locator
from runtime.diagnostics import Reporter
from runtime.model import AtomType, Binary, CompoundType, Const, Expr, Package, Transition, Unary, coverable_places

NONDETERMINISM, DEADCODE, UNBOUND = "nondeterminism", "deadcode", "unboundcomponentport"


def lint(pkg: Package, loc: Locator, rep: Reporter) -> None:
    """Add bipc's warnings on ``pkg`` to ``rep``."""
    for atom in pkg.atom_types:
        quiet = _silenced(pkg.annotations) | _silenced(atom.annotations)
        if NONDETERMINISM not in quiet:
            _nondeterminism(atom, loc, rep)
        if DEADCODE not in quiet:
            for t in dead_transitions(atom):
                if DEADCODE not in _silenced(t.annotations):
                    rep.warning(loc.at(t), f"atom type {atom.name}: transition {_show(t)} cannot be executed "
                                           "(dead code): no run marks its source places")
    kinds = {a.name: a for a in pkg.atom_types} | {c.name: c for c in pkg.compound_types}
    for comp in pkg.compound_types:
        if UNBOUND in _silenced(pkg.annotations) | _silenced(comp.annotations):
            continue
        for inst in comp.components:
            loose = [p for p in _exported(kinds.get(inst.type)) if p not in _bound(comp, inst.name)]
            if loose and UNBOUND not in _silenced(inst.annotations):
                rep.warning(loc.at(inst), f"component '{inst.name}' in compound type {comp.name} has unconnected "
                                          f"port{'s' if len(loose) > 1 else ''} {', '.join(loose)}",
                            hint="bind it with a connector or export it; no interaction can ever use it")


def _silenced(annotations) -> set[str]:
    return {k for a in annotations if a.name == "SuppressWarning" for k in a.arguments}


def _show(t: Transition) -> str:
    head = f"on {t.port}" if t.port else "internal"
    return f"'{head} from {', '.join(t.sources)} to {', '.join(t.targets)}'"


def _nondeterminism(atom: AtomType, loc: Locator, rep: Reporter) -> None:
    """Two transitions on one port from places one of which holds the other's (``checkDuplicatedTriggerPort...``)."""
    for i, later in enumerate(atom.transitions):
        for earlier in atom.transitions[:i]:
            if earlier.port != later.port or not (set(earlier.sources) <= set(later.sources)
                                                  or set(later.sources) <= set(earlier.sources)):
                continue
            what = f"atom type {atom.name}: transitions {_show(earlier)} and {_show(later)}"
            if earlier.guard is None and later.guard is None:
                rep.warning(loc.at(later), f"{what} compete from the same place with no guard (non-determinism)",
                            hint="the Verimag compiler refuses this")
                break
            if NONDETERMINISM not in _silenced(later.annotations):
                rep.warning(loc.at(later), f"{what} may both be enabled from the same place (non-determinism)",
                            hint="make the guards exclusive and say so with @SuppressWarning(nondeterminism)")
                break


def dead_transitions(atom: AtomType) -> list[Transition]:
    """Transitions whose source places no run can mark, guards aside (bipc's ``mayBeCoverable``)."""
    marked = coverable_places(atom.initial.targets if atom.initial else [], atom.transitions)
    return [t for t in atom.transitions if not set(t.sources) <= marked]


def _exported(kind: AtomType | CompoundType | None) -> list[str]:
    if isinstance(kind, AtomType):
        return list(dict.fromkeys(p.export_as or p.name for p in kind.ports if p.exported))
    if isinstance(kind, CompoundType):
        return [p.name for p in kind.ports]
    return []


def _bound(comp: CompoundType, name: str) -> set[str]:
    refs = [r for c in comp.connectors for r in c.ports] + [r for e in comp.ports for r in e.targets]
    return {r.port for r in refs if r.component == name}


def exclusive(g: Expr | None, h: Expr | None) -> bool:
    """Whether guards ``g`` and ``h`` can never hold together, by their shape alone.

    Each is read as a conjunction of literals; they exclude each other when one
    has ``v == a`` and the other ``v == b`` (``a != b``) or ``v != a``, or one
    has ``e`` and the other ``!e``.
    """
    left, right = _conjuncts(g), _conjuncts(h)
    return any(_contradict(a, b) or _contradict(b, a) for a in left for b in right)


def _conjuncts(g: Expr | None) -> list[Expr]:
    if g is None:
        return []
    if isinstance(g, Binary) and g.op == "&&":
        return _conjuncts(g.left) + _conjuncts(g.right)
    return [g]


def _contradict(a: Expr, b: Expr) -> bool:
    if isinstance(b, Unary) and b.op == "!" and b.operand == a:
        return True
    if isinstance(a, Binary) and isinstance(b, Binary) and a.op == "==" and a.left == b.left:
        if isinstance(a.right, Const) and isinstance(b.right, Const):
            return (b.op == "==" and a.right.value != b.right.value) or (b.op == "!=" and a.right == b.right)
    return False
