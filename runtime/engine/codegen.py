"""Python source for one model's step, generated once and compiled once (in the spirit of Amaranth's pyrtl).

The module defines ``initial()``, ``enabled(s)`` and ``FIRE`` (one firing
function per source, ``f(s, mask, rec) -> state``).  Atom behaviour is
straight-line code per atom and per port; rendezvous and flat broadcast
connectors are inlined in ``enabled``; nested connectors and priorities call
the helpers of :mod:`runtime.engine.support`.  Names in the generated text:
``m<i>`` marking and ``a<i>_<x>`` variables of atom ``i`` in ``enabled``,
``e<p>`` enabledness of atom port ``p``, ``_ap<p>`` firing of atom port ``p``,
``_in<i>`` eager internal transitions of atom ``i``, ``_f<k>`` firing of
source ``k``.  Comments name atoms, ports and connectors.  What the C step
writes the same way (scopes, atoms' slots, moves, internal transitions, port
firing and enabledness, the initial state) is :mod:`runtime.engine.stepgen`'s;
this module is its Python half.
"""
from __future__ import annotations

from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, field
from typing import Any

from runtime.engine import defines
from runtime.engine.cexpr import Name, Scope, condition, literal, statements
from runtime.engine.emit import PythonWriter
from runtime.engine.errors import ModelError
from runtime.engine.flatten import FlatAtom, FlatSystem
from runtime.engine.plan import ConnectorInfo, Source
from runtime.engine.stepgen import MAX_INTERNAL, StepEmitter, describe
from runtime.model import Transition

__all__ = ["MAX_INTERNAL", "CodeGen", "ErrorSite", "Generated", "describe", "generate"]

@dataclass
class ErrorSite:
    """Static facts about one place in the generated code that may raise a ModelError."""

    message: str
    atom: str
    port: str | None = None
    transitions: list[str] = field(default_factory=list)
    places: list[str] = field(default_factory=list)


@dataclass
class Generated:
    """The generated source and what the engine must put in its namespace."""

    source: str
    errors: list[ErrorSite]
    atom_priorities: dict[int, tuple[list[str], list[tuple[int, int, int]], list[str], list[int]]]
    called: set[str]
    type_index: dict[str, int]


class CodeGen(StepEmitter):
    """Builds the source for one flat system; ``generate()`` returns a :class:`Generated`."""

    def __init__(self, flat: FlatSystem, infos: dict[str, ConnectorInfo], sources: list[Source]) -> None:
        super().__init__(flat, PythonWriter())
        self.infos, self.sources = infos, sources
        self.errors: list[ErrorSite] = []
        self.externs = {f.name: f.return_type for f in flat.package.extern_functions}
        self.called: set[str] = set()
        self.atom_priorities: dict[int, Any] = {}
        self.type_index = {name: k for k, name in enumerate(infos)}

    # -- the language: Python ---------------------------------------------------------------
    def name(self, src: str, type_name: str | None, where: str, assignable: bool = False) -> Name:
        return Name(src, type_name, assignable=assignable)

    def scope(self, where: str, constants: dict, in_guard: bool) -> Scope:
        return Scope(where=where, constants=constants, externs=self.externs, called=self.called)

    def condition(self, guard, sc: Scope) -> str:
        return condition(guard, sc)

    def statements(self, body, sc: Scope) -> list[str]:
        return statements(body, sc, "")

    def declare(self, name: str, value: str) -> str:
        return f"{name} = {value}"

    def both(self, a: str, b: str) -> str:
        return f"{a} and {b}"

    def mask_test(self, var: str, mask: int) -> str:
        return f"({var} & {mask}) == {mask}"

    def complement(self, mask: int) -> str:
        return f"~{mask}"

    def fail_unsafe(self, fa: FlatAtom, t: Transition, tgt: int) -> str:
        site = self.error_site(ErrorSite("1-safety violated: transition marks an already marked place",
                                         fa.name, t.port, [describe(t)], list(fa.places)))
        return f"_unsafe({site}, m & {tgt})"

    def function(self, head: str, doc: str):
        return self.w.function(head, doc)

    def internal_function(self, fa: FlatAtom):
        return self.function(f"_in{fa.index}(L)",
                             f"Eager internal transitions of atom {fa.name} ({fa.type.name}), until none is enabled.")

    def internal_failures(self, fa: FlatAtom, ts: list[Transition]):
        nd = self.error_site(ErrorSite("non-determinism: two internal transitions enabled at once", fa.name,
                                       None, [describe(t) for t in ts]))
        stuck = self.error_site(ErrorSite(f"internal transitions fired {MAX_INTERNAL} times in a row (livelock)",
                                          fa.name, None, [describe(t) for t in ts]))
        return (lambda flags: f"_nondet({nd}, ({''.join(f'{c}, ' for c in flags)}))"), f"_stuck({stuck})"

    @contextmanager
    def bounded(self, stuck: str):
        with self.w.block(f"for _ in range({MAX_INTERNAL})"):
            yield
        self.w.else_then(stuck)

    def flag(self, name: str, value: str, comment: str) -> None:
        self.w(f"{name} = {value}  # {comment}")

    def any_of(self, flags: list[str]) -> str:
        return " or ".join(flags)

    def port_cases(self, pid: int):
        return nullcontext()

    def fail_nondet_port(self, fa: FlatAtom, port: str, pid: int, ts: list[Transition], flags: list[str]) -> str:
        site = self.error_site(ErrorSite("non-determinism: two transitions enabled on the same port",
                                         fa.name, port, [describe(tr) for tr in ts]))
        return f"_nondet({site}, ({''.join(f'{c}, ' for c in flags)}))"

    def port_function(self, fp, fa: FlatAtom):
        return self.function(f"_ap{fp.id}(L, vals, rec)",
                             f"Port {fp.path}: the enabled transition of atom {fa.name} ({fa.type.name}) on {fp.name}.")

    def not_enabled(self, fa: FlatAtom, fp, ts: list[Transition]) -> str:
        gone = self.error_site(ErrorSite("fired a port that has no enabled transition", fa.name, fp.name,
                                         [describe(t) for t in ts]))
        return f"_notenabled({gone})"

    def record(self, fp) -> None:
        values = "".join(f"v_{v}, " for v in fp.decl.data)
        self.w.if_then("rec is not None", f"rec.append(({fp.id}, ({values})))")

    def call_internal(self, fa: FlatAtom) -> str:
        return f"_in{fa.index}(L)"

    def note(self, t: Transition) -> str:
        return describe(t)

    def value(self, value: Any, sc: Scope) -> str:
        return literal(value)

    @contextmanager
    def initial_function(self):
        with self.function("initial()", "The initial state: initial transitions, then eager internal transitions, "
                           "atom by atom."):
            self.w(f"L = [None] * {self.flat.state_size}")
            yield
            self.w("return tuple(L)")

    def initial_atom(self, fa: FlatAtom):
        self.w(f"# atom {fa.name} ({fa.type.name})")
        return nullcontext()

    def initial_marking(self, mask: int, targets: list[str]) -> None:
        self.w(f"m = {mask}  # {', '.join(targets)}")

    def conjunction(self, terms: list[str]) -> str:
        return " and ".join(terms)

    def error_site(self, site: ErrorSite) -> int:
        self.errors.append(site)
        return len(self.errors) - 1

    # -- the whole module ------------------------------------------------------------------
    def generate(self) -> Generated:
        w = self.w
        fl = self.flat
        w(f"# Step of package {fl.package.name}, root {fl.root}: generated by runtime.engine.codegen.")
        w("# State layout (slot: meaning); a marking is a bit mask over the atom's places.")
        for fa in fl.atoms:
            places = ", ".join(f"{p}={1 << i}" for i, p in enumerate(fa.places))
            w(f"#   {fa.offset:4d}: {fa.name} marking ({places})")
            for d in fa.variables:
                w(f"#   {fa.slot(d.name):4d}: {fa.name}.{d.name} ({d.type})")
        w()
        for fa in fl.atoms:
            self.gen_internal(fa)
        for fp in fl.ports:
            self.gen_port(fp)
        self.gen_initial()
        for name, info in self.infos.items():
            self.gen_clauses(name, info)
        for src in self.sources:
            self.gen_fire(src)
        w(f"FIRE = ({''.join(f'_f{s.index}, ' for s in self.sources)})")
        w()
        self.gen_priority_guards()
        self.gen_enabled()
        return Generated(w.source(), self.errors, self.atom_priorities, self.called, self.type_index)

    # -- atoms -------------------------------------------------------------------------------
    # -- connectors --------------------------------------------------------------------------
    def gen_clauses(self, name: str, info: ConnectorInfo) -> None:
        """Guard, up and down of each ``on`` clause of a connector type, on port values ``pv`` and locals ``lv``."""
        w = self.w
        k = self.type_index[name]
        table = []
        for mask, spec in info.clauses.items():
            on = " ".join(spec.ports)
            fns = []
            if spec.guard is not None:
                sc = self.connector_scope(info, mask, False, False)  # guards run before up: locals are initial
                with w.block(f"def _k{k}_{mask}_g(pv)", f"{name}: on {on} provided"):
                    w(f"return {condition(spec.guard, sc)}")
                fns.append(f"_k{k}_{mask}_g")
            else:
                fns.append("None")
            for part, body, ports_rw in (("u", spec.up, False), ("d", spec.down, True)):
                if body:
                    sc = self.connector_scope(info, mask, ports_rw, True)
                    what = f"{name}: on {on} {'up' if part == 'u' else 'down'}"
                    with w.block(f"def _k{k}_{mask}_{part}(pv, lv)", what):
                        w.extend(self.statements(body, sc))
                    fns.append(f"_k{k}_{mask}_{part}")
                else:
                    fns.append("None")
            table.append(f"{mask}: ({', '.join(fns)})")
        w(f"_K{k} = {{{', '.join(table)}}}  # connector type {name}: clauses by parameter mask")
        guarded = [f"{mask}: _k{k}_{mask}_g" for mask, spec in info.clauses.items() if spec.guard is not None]
        w(f"_G{k} = {{{', '.join(guarded)}}}")
        w()

    def port_values(self, fp, L: str = "L") -> str:
        return "[" + ", ".join(f"{L}[{s}]" for s in fp.slots) + "]"

    def gen_fire(self, src: Source) -> None:
        """``_f<k>(s, mask, rec)``: the state after interaction ``mask`` of source ``k``."""
        w = self.w
        fl = self.flat
        if src.kind == "port":
            with self.function(f"_f{src.index}(s, mask, rec)", f"Lone port {src.port.path}."):
                w("L = list(s)")
                w(f"_ap{src.port.id}(L, None, rec)")
                w("return tuple(L)")
            return
        fc = src.connector
        args = ", ".join(str(r) for r in fc.instance.ports)
        with self.function(f"_f{src.index}(s, mask, rec)", f"Connector {fc.path}: {fc.type.name}({args})."):
            w("L = list(s)")
            if src.kind == "generic":
                w(f"_fire_tree(_S{src.index}, L, mask, rec)")
                w("return tuple(L)")
                return
            info = self.infos[fc.type.name]
            k = self.type_index[fc.type.name]
            vals = ", ".join(self.port_values(fl.ports[p]) for p in src.leaves)
            w(f"pv = [{vals}]  # {', '.join(fl.ports[p].path for p in src.leaves)}")
            if info.clauses:
                w(f"lv = {literal(list(info.local_defaults))}")
                key = info.all_params if src.kind == "rendezvous" else "mask"
                w(f"_g, _u, _d = _K{k}.get({key}, _NONE)")
                w.if_then("_u is not None", "_u(pv, lv)")
                w.if_then("_d is not None", "_d(pv, lv)")
            for i, p in enumerate(src.leaves):
                if src.kind == "rendezvous":
                    w(f"_ap{p}(L, pv[{i}], rec)")
                else:
                    w.if_then(f"mask & {1 << i}", f"_ap{p}(L, pv[{i}], rec)")
            w("return tuple(L)")

    def gen_priority_guards(self) -> None:
        """``_pg<r>(s)``: guard of compound priority ``r``, reading exported data straight from the state."""
        w = self.w
        for r, pr in enumerate(self.flat.priorities):
            if pr.guard is None:
                continue
            with w.block(f"def _pg{r}(s)", f"priority {pr.text}"):
                w(f"return {condition(pr.guard, self.priority_scope(pr))}")
            w()

    # -- enabled -----------------------------------------------------------------------------
    def gen_enabled(self) -> None:
        """``enabled(s)``: atom ports, then each source's interactions, then compound priorities."""
        w = self.w
        fl = self.flat
        with w.block("def enabled(s)"):
            w('"""Enabled interactions at state s: maximal ports, connectors, lone ports, then priorities."""')
            self.gen_ports_enabled()
            if any(s.kind == "generic" for s in self.sources):
                w(f"E = ({''.join(f'e{p.id}, ' for p in fl.ports)})")
            w("out = []")
            for src in self.sources:
                self.gen_source_enabled(src)
            w("return _prio(out, s)" if fl.priorities else "return out")

    def gen_ports_enabled(self) -> None:
        """The state's atoms unpacked, then ``e<p>`` for every atom port (after the atoms' own priorities)."""
        names = []
        for fa in self.flat.atoms:
            names.append(f"m{fa.index}")
            names.extend(f"a{fa.index}_{d.name}" for d in fa.variables)
        if names:
            self.w(f"{', '.join(names)}, = s")
        for fa in self.flat.atoms:
            self.gen_atom_enabled(fa)

    def generate_ready(self) -> Generated:
        """A module with ``ready(s)``: per atom port, whether the atom offers it at ``s`` (why an interaction is
        not enabled: which of its ports are missing).  Generated on demand, beside the step."""
        with self.w.block("def ready(s)"):
            self.w('"""Per atom port (flat port order): a transition on it is enabled at state s."""')
            self.gen_ports_enabled()
            self.w(f"return ({''.join(f'e{p.id}, ' for p in self.flat.ports)})")
        return Generated(self.w.source(), self.errors, self.atom_priorities, self.called, self.type_index)

    def atom_heading(self, fa: FlatAtom) -> None:
        places = ", ".join(f"{p}={1 << i}" for i, p in enumerate(fa.places))
        self.w(f"# atom {fa.name} ({fa.type.name}): {places}")

    def gen_atom_priorities(self, fa: FlatAtom, sc: Scope) -> None:
        """The atom's ports filtered by its priorities (``_aprio<i>``, memoised in support.AtomPriorities)."""
        w = self.w
        t = fa.type
        order = list(fa.ports)
        rules: list[tuple[int, int, int]] = []
        texts: list[str] = []
        guarded: list[int] = []
        guards: list[str] = []
        for r, pr in enumerate(t.priorities):
            texts.append(f"priority {pr.name} {pr.low} < {pr.high}")
            for side in (pr.low, pr.high):
                if side != "*" and side not in fa.ports:
                    raise ModelError(f"priority {pr.name} names unknown port '{side}'", atom=fa.name)
            if pr.low == "*" and pr.high == "*":
                raise ModelError(f"priority {pr.name}: '*' on both sides", atom=fa.name)
            lows = [i for i, p in enumerate(order) if p != pr.high] if pr.low == "*" else [order.index(pr.low)]
            highs = [i for i, p in enumerate(order) if p != pr.low] if pr.high == "*" else [order.index(pr.high)]
            for lo in lows:
                for hi in highs:
                    rules.append((lo, hi, r))
            if pr.guard is not None:
                guarded.append(r)
                guards.append(condition(pr.guard, sc))
        self.atom_priorities[fa.index] = (order, rules, texts, guarded)
        raw = " | ".join(f"e{fa.ports[p]} << {i}" for i, p in enumerate(order))
        act = " | ".join(f"({g}) << {k}" for k, g in enumerate(guards)) or "0"
        w(f"_r = {raw}")
        with w.block("if _r"):
            w(f"_r = _aprio{fa.index}(_r, {act})  # atom priorities of {fa.name}")
            for i, p in enumerate(order):
                w(f"e{fa.ports[p]} = (_r & {1 << i}) != 0")

    def gen_source_enabled(self, src: Source) -> None:
        """The part of ``enabled`` that appends the maximal enabled interactions of one source to ``out``."""
        w = self.w
        fl = self.flat
        if src.kind == "port":
            with w.block(f"if e{src.port.id}", f"lone port {src.port.path}"):
                w(f"out.append(_I{src.index}_1)")
            return
        fc = src.connector
        args = ", ".join(str(r) for r in fc.instance.ports)
        w(f"# connector {fc.path}: {fc.type.name}({args})")

        def found(mask: str) -> str:
            return f"out.append(_IC{src.index}.get({mask}) or _mk({src.index}, {mask}))"

        if src.kind == "generic":
            with w.block(f"for _k in _generic(_S{src.index}, s, E)"):
                w(found("_k"))
            return
        info = self.infos[fc.type.name]
        k = self.type_index[fc.type.name]
        if src.kind == "rendezvous":
            w.if_then(self.rendezvous_enabled(src, info), f"out.append(_I{src.index}_{src.full})")
            return
        enabled = [f"e{p}" for p in src.leaves]
        w(f"em = {' | '.join(f'{e} << {i}' if i else e for i, e in enumerate(enabled))}")
        if any(spec.guard is not None for spec in info.clauses.values()):
            vals = ", ".join(self.inline_values(fl.ports[p]) for p in src.leaves)
            with w.block("if em"):
                w(f"pv = [{vals}]")
                with w.block(f"for _k in _maximal_enabled(_T{k}, em, lambda m: m in _G{k} and not _G{k}[m](pv))"):
                    w(found("_k"))
        elif defines.is_flat(info.tree):
            w.if_then(f"em & {defines.triggers(info.tree)}", found("em"))
        else:
            w(f"_k = _max_allowed(_T{k}, em)")
            w.if_then("_k", found("_k"))

    def inline_values(self, fp) -> str:
        fa = self.flat.atoms[fp.atom]
        return "[" + ", ".join(f"a{fa.index}_{v}" for v in fp.decl.data) + "]"


def generate(flat: FlatSystem, infos: dict[str, ConnectorInfo], sources: list[Source]) -> Generated:
    """Generate the step module's source for a flat system."""
    return CodeGen(flat, infos, sources).generate()
