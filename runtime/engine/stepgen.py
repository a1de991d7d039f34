"""What a model's step generator does whatever the target language: scopes, slots, markings, moves, internal runs.

Two generators write the same step: :mod:`runtime.engine.codegen` (Python,
the reference that execution and exploration run) and
:mod:`runtime.native.cstep` (C, for the compiled search).  Both build the
same scopes for atoms and connectors, load and store an atom's slots, test
markings, move tokens with the 1-safety check, and write the eager internal
transitions and the firing of an atom port the same way; :class:`StepEmitter`
holds that once.  A subclass is the language: the methods below that raise
``NotImplementedError`` (names and types, statements, how the step fails).
"""
from __future__ import annotations

from contextlib import AbstractContextManager
from typing import Any, Callable

from runtime.engine.cexpr import default_value
from runtime.engine.emit import Writer
from runtime.engine.errors import ModelError
from runtime.engine.flatten import FlatAtom, FlatSystem
from runtime.model import Transition, source_of
from runtime.model.expressions import Assign, Var

#: Internal transitions fired in a row by one atom before the engine calls it a livelock.
MAX_INTERNAL = 10_000


def describe(t: Transition) -> str:
    """A transition as a user reads it in an error: ``on p from A to B (m.bip:9:5, from ndd.gen:42:3)``.

    The ``.bip`` position when the model was read from text, the description
    line (``@source``) when it was generated from one.
    """
    head = "internal" if t.port is None else f"on {t.port}"
    text = f"{head} from {', '.join(t.sources)} to {', '.join(t.targets)}"
    where = [str(t.span)] if t.span.line > 0 else []
    source = source_of(t.annotations)
    if source:
        where.append(f"from {source}")
    if where:
        text += f" ({', '.join(where)})"
    return text


class StepEmitter:
    """The language-independent half of a step generator, writing to ``self.w``."""

    #: The language's conditions that always and never hold (``condition(None)`` gives the first).
    TRUE, FALSE = "True", "False"
    #: Condition that the caller passed port values to an atom port's firing function.
    HAVE_VALUES = "vals is not None"

    def __init__(self, flat: FlatSystem, w: Writer) -> None:
        self.flat = flat
        self.w = w

    # -- the language --------------------------------------------------------------------------
    def name(self, src: str, type_name: str | None, where: str, assignable: bool = False) -> Any:
        """What a BIP name stands for: its source text, its type (``where`` names it if refused)."""
        raise NotImplementedError

    def scope(self, where: str, constants: dict, in_guard: bool) -> Any:
        """An empty scope of the language's expression translator."""
        raise NotImplementedError

    def condition(self, guard, sc) -> str:
        raise NotImplementedError

    def statements(self, body, sc) -> list[str]:
        """Lines of a block of BIP statements, indented relative to the current block."""
        raise NotImplementedError

    def declare(self, name: str, value: str) -> str:
        """A statement that introduces a local variable of the step's value type."""
        raise NotImplementedError

    def both(self, a: str, b: str) -> str:
        raise NotImplementedError

    def mask_test(self, var: str, mask: int) -> str:
        """Every place of ``mask`` is marked in the marking ``var``."""
        raise NotImplementedError

    def complement(self, mask: int) -> str:
        raise NotImplementedError

    def fail_unsafe(self, fa: FlatAtom, t: Transition, tgt: int) -> str:
        """The statement that stops the step when ``t`` marks an already marked place."""
        raise NotImplementedError

    def internal_function(self, fa: FlatAtom) -> AbstractContextManager:
        raise NotImplementedError

    def internal_failures(self, fa: FlatAtom, ts: list[Transition]) -> tuple[Callable[[list[str]], str], str]:
        """The statements that stop internal transitions: two enabled at once (given their flags), a livelock."""
        raise NotImplementedError

    def bounded(self, stuck: str) -> AbstractContextManager:
        """A loop run at most MAX_INTERNAL times, ``stuck`` when it does not break before."""
        raise NotImplementedError

    def flag(self, name: str, value: str, comment: str) -> None:
        """A local truth value."""
        raise NotImplementedError

    def atom_heading(self, fa: FlatAtom) -> None:
        """What the language writes before an atom's part of ``enabled`` (a comment, or nothing)."""

    def gen_atom_priorities(self, fa: FlatAtom, sc) -> None:
        """The atom's enabled ports filtered by its priorities."""
        raise NotImplementedError

    def any_of(self, flags: list[str]) -> str:
        raise NotImplementedError

    def port_cases(self, pid: int) -> AbstractContextManager:
        """Where the transitions of port ``pid`` are tested one by one before ``e<pid>`` is set."""
        raise NotImplementedError

    def fail_nondet_port(self, fa: FlatAtom, port: str, pid: int, ts: list[Transition], flags: list[str]) -> str:
        """The statement that stops the step when two transitions on one port are enabled at once."""
        raise NotImplementedError

    def port_function(self, fp, fa: FlatAtom) -> AbstractContextManager:
        raise NotImplementedError

    def not_enabled(self, fa: FlatAtom, fp, ts: list[Transition]) -> str:
        """The statement that stops the step when a port is fired with no transition enabled."""
        raise NotImplementedError

    def record(self, fp) -> None:
        """Whatever the step records of a fired port (the Python step's trace of port values)."""

    def call_internal(self, fa: FlatAtom) -> str:
        raise NotImplementedError

    def note(self, t: Transition) -> str | None:
        """The comment on the case of a transition, if the language writes one."""
        return None

    def value(self, value: Any, sc) -> str:
        """A constant as the step stores it."""
        raise NotImplementedError

    def initial_function(self) -> AbstractContextManager:
        raise NotImplementedError

    def initial_atom(self, fa: FlatAtom) -> AbstractContextManager:
        """Where one atom's part of the initial state is written."""
        raise NotImplementedError

    def initial_marking(self, mask: int, targets: list[str]) -> None:
        raise NotImplementedError

    def in_data(self, sc, d):
        """The scope ``sc`` as seen from the initialiser of data ``d``."""
        return sc

    def in_initial(self, sc):
        """The scope ``sc`` as seen from the initial transition's action."""
        return sc

    def conjunction(self, terms: list[str]) -> str:
        raise NotImplementedError

    def connector_where(self, info, mask: int) -> str:
        """How a connector's clause is named in a refusal or an error."""
        return f"connector type {info.type.name}"

    def in_transition(self, sc, t: Transition):
        """The scope ``sc`` as seen from the guard and action of ``t``."""
        return sc

    # -- scopes --------------------------------------------------------------------------------
    def atom_scope(self, fa: FlatAtom, in_enabled: bool):
        """An atom's data: the unpacked state ``a<i>_<x>`` in ``enabled``, the loaded locals ``v_<x>`` elsewhere."""
        sc = self.scope(f"atom {fa.name} ({fa.type.name})", fa.constants, in_guard=in_enabled)
        for d in fa.variables:
            src = f"a{fa.index}_{d.name}" if in_enabled else f"v_{d.name}"
            sc.variables[d.name] = self.name(src, d.type, f"{sc.where}, {d.name}", assignable=not in_enabled)
        return sc

    def connector_scope(self, info, mask: int, ports_rw: bool, with_locals: bool):
        """A clause of a connector type on port values ``pv``; its locals ``lv``, or their initial values."""
        ct = info.type
        sc = self.scope(self.connector_where(info, mask), dict(self.flat.constants), in_guard=not with_locals)
        for k, d in enumerate(ct.data):
            local = self.name(f"lv[{k}]", d.type, f"{sc.where}, {d.name}", assignable=True)
            if with_locals:
                sc.variables[d.name] = local
            else:
                sc.constants[d.name] = (info.local_defaults[k], d.type)
        for i, p in enumerate(ct.params):
            if not mask >> i & 1:
                continue
            pt = self.flat.package.port_type(p.port_type)
            for j, f in enumerate(pt.params if pt else []):
                sc.ports[(p.name, f.name)] = self.name(f"pv[{i}][{j}]", f.type, sc.where, assignable=ports_rw)
        return sc

    def inline_scope(self, src, info):
        """Scope of a rendezvous guard inlined in ``enabled``: port data are the atoms' unpacked variables."""
        sc = self.connector_scope(info, info.all_params, False, False)
        for i, p in enumerate(info.type.params):
            fp = self.flat.ports[src.leaves[i]]
            fa = self.flat.atoms[fp.atom]
            for f, v, ty in zip(fp.fields, fp.decl.data, fp.field_types):
                sc.ports[(p.name, f)] = self.name(f"a{fa.index}_{v}", ty, sc.where)
        return sc

    def priority_scope(self, pr, state: str = "s"):
        """Scope of a compound priority's guard, reading the exported data straight from the state."""
        sc = self.scope(f"priority {pr.name}", pr.constants, in_guard=True)
        for (comp, name), (slot, ty) in pr.data.items():
            sc.ports[(comp, name)] = self.name(f"{state}[{slot}]", ty, sc.where)
        return sc

    def rendezvous_enabled(self, src, info) -> str:
        """A rendezvous source is enabled: its ports are, and the guard of its one clause holds."""
        cond = self.conjunction([f"e{p}" for p in src.leaves])
        spec = info.clauses.get(info.all_params)
        if spec is not None and spec.guard is not None:
            cond = self.conjunction([cond, self.condition(spec.guard, self.inline_scope(src, info))])
        return cond

    # -- atoms ---------------------------------------------------------------------------------
    def load(self, fa: FlatAtom) -> None:
        """The atom's marking into ``m`` and its variables into ``v_<x>``."""
        self.w.stmt(self.declare("m", f"L[{fa.offset}]"))
        for d in fa.variables:
            self.w.stmt(self.declare(f"v_{d.name}", f"L[{fa.slot(d.name)}]"))

    def store(self, fa: FlatAtom) -> None:
        self.w.stmt(f"L[{fa.offset}] = m")
        for d in fa.variables:
            self.w.stmt(f"L[{fa.slot(d.name)}] = v_{d.name}")

    def marked(self, fa: FlatAtom, t: Transition, var: str) -> str:
        """The source places of ``t`` are marked in ``var`` (a transition naming an unknown place is refused)."""
        for p in t.sources + t.targets:
            if p not in fa.places:
                raise ModelError(f"transition {describe(t)} names unknown place '{p}'", atom=fa.name)
        src = fa.place_mask(t.sources)
        return self.mask_test(var, src) if src else self.TRUE

    def enabled_expr(self, fa: FlatAtom, t: Transition, var: str, sc) -> str:
        guard = self.condition(t.guard, self.in_transition(sc, t))
        mk = self.marked(fa, t, var)
        return mk if guard == self.TRUE else self.both(mk, guard)

    def move(self, fa: FlatAtom, t: Transition, sc) -> None:
        """Marking update with the 1-safety check, then the action."""
        src, tgt = fa.place_mask(t.sources), fa.place_mask(t.targets)
        unsafe = self.fail_unsafe(fa, t, tgt)
        if src:
            self.w.stmt(f"m &= {self.complement(src)}")
        if tgt:
            self.w.if_then(f"m & {tgt}", unsafe)
            self.w.stmt(f"m |= {tgt}")
        self.w.extend(self.statements(t.action, self.in_transition(sc, t)))

    def gen_initial(self) -> None:
        """The initial state: atom by atom, defaults, data initialisers, the initial transition, internal runs."""
        w = self.w
        with self.initial_function():
            for fa in self.flat.atoms:
                t = fa.type
                sc = self.atom_scope(fa, in_enabled=False)
                with self.initial_atom(fa):
                    for d in fa.variables:
                        w.stmt(self.declare(f"v_{d.name}", self.value(default_value(d.type), sc)))
                    for d in fa.variables:
                        if d.init is not None:
                            w.extend(self.statements([Assign(Var(d.name), d.init)], self.in_data(sc, d)))
                    targets = t.initial.targets
                    for p in targets:
                        if p not in fa.places:
                            raise ModelError(f"initial transition names unknown place '{p}'", atom=fa.name)
                    if len(set(targets)) != len(targets):
                        raise ModelError("1-safety violated: the initial transition marks a place twice",
                                         atom=fa.name, places=tuple(targets))
                    self.initial_marking(fa.place_mask(targets), targets)
                    w.extend(self.statements(t.initial.action, self.in_initial(sc)))
                    self.store(fa)
                    if any(tr.internal for tr in t.transitions):
                        w.stmt(self.call_internal(fa))

    def gen_internal(self, fa: FlatAtom) -> None:
        """The atom's eager internal transitions, fired until none is enabled (one enabled at a time)."""
        ts = [t for t in fa.type.transitions if t.internal]
        if not ts:
            return
        w = self.w
        sc = self.atom_scope(fa, in_enabled=False)
        with self.internal_function(fa), w.names():
            self.load(fa)
            nondet, stuck = self.internal_failures(fa, ts)
            flags = [w.fresh("c") for _ in ts]
            with self.bounded(stuck):
                for c, t in zip(flags, ts):
                    self.flag(c, self.enabled_expr(fa, t, "m", sc), describe(t))
                if len(ts) > 1:
                    w.if_then(f"{' + '.join(flags)} > 1", nondet(flags))
                for k, (c, t) in enumerate(zip(flags, ts)):
                    with w.if_(c, first=k == 0):
                        self.move(fa, t, sc)
                w.else_then("break")
            self.store(fa)

    def gen_port(self, fp) -> None:
        """Firing of atom port ``fp``: its one enabled transition, with the port values the connector passes."""
        w = self.w
        fa = self.flat.atoms[fp.atom]
        ts = [t for t in fa.type.transitions if t.port == fp.name]
        sc = self.atom_scope(fa, in_enabled=False)
        with self.port_function(fp, fa):
            self.load(fa)
            gone = self.not_enabled(fa, fp, ts)
            for k, t in enumerate(ts):
                with w.if_(self.enabled_expr(fa, t, "m", sc), first=k == 0, comment=self.note(t)):
                    if fp.decl.data:
                        with w.if_(self.HAVE_VALUES):
                            for j, v in enumerate(fp.decl.data):
                                w.stmt(f"v_{v} = vals[{j}]")
                    self.record(fp)
                    self.move(fa, t, sc)
            if ts:
                w.else_then(gone)
            else:
                w.stmt(gone)
            self.store(fa)
            if any(t.internal for t in fa.type.transitions):
                w.stmt(self.call_internal(fa))

    def gen_atom_enabled(self, fa: FlatAtom) -> None:
        """``e<p>`` for each port of atom ``fa``: a transition on it is enabled (and no higher port's is)."""
        sc = self.atom_scope(fa, in_enabled=True)
        self.atom_heading(fa)
        for name, pid in fa.ports.items():
            self.gen_port_enabled(fa, name, pid, sc)
        if fa.type.priorities:
            self.gen_atom_priorities(fa, sc)

    def gen_port_enabled(self, fa: FlatAtom, port: str, pid: int, sc) -> None:
        """``e<pid>``: a transition on the port is enabled in ``enabled``'s state (two at once stop the step)."""
        w = self.w
        ts = [tr for tr in fa.type.transitions if tr.port == port]
        if not ts:
            self.flag(f"e{pid}", self.FALSE, f"{port}: no transition")
        elif len(ts) == 1:
            self.flag(f"e{pid}", self.enabled_expr(fa, ts[0], f"m{fa.index}", sc), describe(ts[0]))
        else:
            with self.port_cases(pid), w.names():
                flags = [w.fresh("t") for _ in ts]
                for c, tr in zip(flags, ts):
                    self.flag(c, self.enabled_expr(fa, tr, f"m{fa.index}", sc), describe(tr))
                w.if_then(f"{' + '.join(flags)} > 1", self.fail_nondet_port(fa, port, pid, ts, flags))
                w.stmt(f"e{pid} = {self.any_of(flags)}")
