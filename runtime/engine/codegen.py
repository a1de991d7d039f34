"""Python source for one model's step, generated once and compiled once (in the spirit of Amaranth's pyrtl).

The module defines ``initial()``, ``enabled(s)`` and ``FIRE`` (one firing
function per source, ``f(s, mask, rec) -> state``).  Atom behaviour is
straight-line code per atom and per port; rendezvous and flat broadcast
connectors are inlined in ``enabled``; nested connectors and priorities call
the helpers of :mod:`runtime.engine.support`.  Names in the generated text:
``m<i>`` marking and ``a<i>_<x>`` variables of atom ``i`` in ``enabled``,
``e<p>`` enabledness of atom port ``p``, ``_ap<p>`` firing of atom port ``p``,
``_in<i>`` eager internal transitions of atom ``i``, ``_f<k>`` firing of
source ``k``.  Comments name atoms, ports and connectors.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from runtime.engine import defines
from runtime.engine.cexpr import Name, Scope, condition, default_value, literal, statements
from runtime.engine.errors import ModelError
from runtime.engine.flatten import FlatAtom, FlatSystem
from runtime.engine.plan import ConnectorInfo, Source
from runtime.model import AtomType, Transition, source_of

#: Internal transitions fired in a row by one atom before the engine calls it a livelock.
MAX_INTERNAL = 10_000


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


class _Writer:
    def __init__(self) -> None:
        self.lines: list[str] = []

    def __call__(self, line: str = "") -> None:
        self.lines.append(line)

    def extend(self, lines: list[str]) -> None:
        self.lines.extend(lines)


class CodeGen:
    """Builds the source for one flat system; ``generate()`` returns a :class:`Generated`."""

    def __init__(self, flat: FlatSystem, infos: dict[str, ConnectorInfo], sources: list[Source]) -> None:
        self.flat, self.infos, self.sources = flat, infos, sources
        self.w = _Writer()
        self.errors: list[ErrorSite] = []
        self.externs = {f.name: f.return_type for f in flat.package.extern_functions}
        self.called: set[str] = set()
        self.atom_priorities: dict[int, Any] = {}
        self.type_index = {name: k for k, name in enumerate(infos)}

    # -- scopes ----------------------------------------------------------------------------
    def atom_scope(self, fa: FlatAtom, in_enabled: bool) -> Scope:
        sc = Scope(where=f"atom {fa.name} ({fa.type.name})", constants=fa.constants, externs=self.externs,
                   called=self.called)
        for d in fa.variables:
            src = f"a{fa.index}_{d.name}" if in_enabled else f"v_{d.name}"
            sc.variables[d.name] = Name(src, d.type, assignable=not in_enabled)
        return sc

    def connector_scope(self, info: ConnectorInfo, mask: int, ports_assignable: bool, locals_as: str) -> Scope:
        ct = info.type
        sc = Scope(where=f"connector type {ct.name}", constants=dict(self.flat.constants), externs=self.externs,
                   called=self.called)
        for k, d in enumerate(ct.data):
            if locals_as == "lv":
                sc.variables[d.name] = Name(f"lv[{k}]", d.type, assignable=True)
            else:
                sc.constants[d.name] = (info.local_defaults[k], d.type)
        for i, p in enumerate(ct.params):
            if not mask >> i & 1:
                continue
            pt = self.flat.package.port_type(p.port_type)
            for j, f in enumerate(pt.params if pt else []):
                sc.ports[(p.name, f.name)] = Name(f"pv[{i}][{j}]", f.type, assignable=ports_assignable)
        return sc

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
        return Generated("\n".join(w.lines) + "\n", self.errors, self.atom_priorities, self.called, self.type_index)

    # -- atoms -------------------------------------------------------------------------------
    def load(self, fa: FlatAtom, indent: str) -> None:
        self.w(f"{indent}m = L[{fa.offset}]")
        for d in fa.variables:
            self.w(f"{indent}v_{d.name} = L[{fa.slot(d.name)}]")

    def store(self, fa: FlatAtom, indent: str) -> None:
        self.w(f"{indent}L[{fa.offset}] = m")
        for d in fa.variables:
            self.w(f"{indent}L[{fa.slot(d.name)}] = v_{d.name}")

    def marked(self, fa: FlatAtom, t: Transition, var: str) -> str:
        for p in t.sources + t.targets:
            if p not in fa.places:
                raise ModelError(f"transition {describe(t)} names unknown place '{p}'", atom=fa.name)
        src = fa.place_mask(t.sources)
        return f"({var} & {src}) == {src}" if src else "True"

    def enabled_expr(self, fa: FlatAtom, t: Transition, var: str, scope: Scope) -> str:
        guard = condition(t.guard, scope)
        mk = self.marked(fa, t, var)
        return mk if guard == "True" else f"{mk} and {guard}"

    def move(self, fa: FlatAtom, t: Transition, indent: str, scope: Scope) -> None:
        """Marking update with the 1-safety check, then the action."""
        src, tgt = fa.place_mask(t.sources), fa.place_mask(t.targets)
        site = self.error_site(ErrorSite("1-safety violated: transition marks an already marked place",
                                         fa.name, t.port, [describe(t)], list(fa.places)))
        if src:
            self.w(f"{indent}m &= ~{src}")
        if tgt:
            self.w(f"{indent}if m & {tgt}:")
            self.w(f"{indent}    _unsafe({site}, m & {tgt})")
            self.w(f"{indent}m |= {tgt}")
        self.w.extend(statements(t.action, scope, indent))

    def gen_internal(self, fa: FlatAtom) -> None:
        ts = [t for t in fa.type.transitions if t.internal]
        if not ts:
            return
        w = self.w
        sc = self.atom_scope(fa, in_enabled=False)
        w(f"def _in{fa.index}(L):")
        w(f'    """Eager internal transitions of atom {fa.name} ({fa.type.name}), until none is enabled."""')
        self.load(fa, "    ")
        nd = self.error_site(ErrorSite("non-determinism: two internal transitions enabled at once", fa.name,
                                       None, [describe(t) for t in ts]))
        stuck = self.error_site(ErrorSite(f"internal transitions fired {MAX_INTERNAL} times in a row (livelock)",
                                          fa.name, None, [describe(t) for t in ts]))
        w(f"    for _ in range({MAX_INTERNAL}):")
        for k, t in enumerate(ts):
            w(f"        c{k} = {self.enabled_expr(fa, t, 'm', sc)}  # {describe(t)}")
        if len(ts) > 1:
            w(f"        if {' + '.join(f'c{k}' for k in range(len(ts)))} > 1:")
            w(f"            _nondet({nd}, ({''.join(f'c{k}, ' for k in range(len(ts)))}))")
        for k, t in enumerate(ts):
            w(f"        {'if' if k == 0 else 'elif'} c{k}:")
            self.move(fa, t, "            ", sc)
        w("        else:")
        w("            break")
        w("    else:")
        w(f"        _stuck({stuck})")
        self.store(fa, "    ")
        w()

    def gen_port(self, fp) -> None:
        w = self.w
        fa = self.flat.atoms[fp.atom]
        ts = [t for t in fa.type.transitions if t.port == fp.name]
        sc = self.atom_scope(fa, in_enabled=False)
        w(f"def _ap{fp.id}(L, vals, rec):")
        w(f'    """Port {fp.path}: the enabled transition of atom {fa.name} ({fa.type.name}) on {fp.name}."""')
        self.load(fa, "    ")
        gone = self.error_site(ErrorSite("fired a port that has no enabled transition", fa.name, fp.name,
                                         [describe(t) for t in ts]))
        for k, t in enumerate(ts):
            w(f"    {'if' if k == 0 else 'elif'} {self.enabled_expr(fa, t, 'm', sc)}:  # {describe(t)}")
            if fp.decl.data:
                w("        if vals is not None:")
                for j, v in enumerate(fp.decl.data):
                    w(f"            v_{v} = vals[{j}]")
                w("        if rec is not None:")
                w(f"            rec.append(({fp.id}, ({''.join(f'v_{v}, ' for v in fp.decl.data)})))")
            else:
                w("        if rec is not None:")
                w(f"            rec.append(({fp.id}, ()))")
            self.move(fa, t, "        ", sc)
        if ts:
            w("    else:")
            w(f"        _notenabled({gone})")
        else:
            w(f"    _notenabled({gone})")
        self.store(fa, "    ")
        if any(t.internal for t in fa.type.transitions):
            w(f"    _in{fa.index}(L)")
        w()

    def gen_initial(self) -> None:
        w = self.w
        w("def initial():")
        w('    """The initial state: initial transitions, then eager internal transitions, atom by atom."""')
        w(f"    L = [None] * {self.flat.state_size}")
        for fa in self.flat.atoms:
            t = fa.type
            sc = self.atom_scope(fa, in_enabled=False)
            w(f"    # atom {fa.name} ({t.name})")
            for d in fa.variables:
                w(f"    v_{d.name} = {literal(default_value(d.type))}")
            for d in fa.variables:
                if d.init is not None:
                    w.extend(statements([_assign(d.name, d.init)], sc, "    "))
            targets = t.initial.targets
            for p in targets:
                if p not in fa.places:
                    raise ModelError(f"initial transition names unknown place '{p}'", atom=fa.name)
            if len(set(targets)) != len(targets):
                raise ModelError("1-safety violated: the initial transition marks a place twice", atom=fa.name,
                                 places=tuple(targets))
            w(f"    m = {fa.place_mask(targets)}  # {', '.join(targets)}")
            w.extend(statements(t.initial.action, sc, "    "))
            self.store(fa, "    ")
            if any(tr.internal for tr in t.transitions):
                w(f"    _in{fa.index}(L)")
        w("    return tuple(L)")
        w()

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
                sc = self.connector_scope(info, mask, False, "const")  # guards run before up: locals are initial
                w(f"def _k{k}_{mask}_g(pv):  # {name}: on {on} provided")
                w(f"    return {condition(spec.guard, sc)}")
                fns.append(f"_k{k}_{mask}_g")
            else:
                fns.append("None")
            for part, body, ports_rw in (("u", spec.up, False), ("d", spec.down, True)):
                if body:
                    sc = self.connector_scope(info, mask, ports_rw, "lv")
                    w(f"def _k{k}_{mask}_{part}(pv, lv):  # {name}: on {on} {'up' if part == 'u' else 'down'}")
                    w.extend(statements(body, sc, "    "))
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
        w = self.w
        fl = self.flat
        if src.kind == "port":
            fp = src.port
            w(f"def _f{src.index}(s, mask, rec):")
            w(f'    """Lone port {fp.path}."""')
            w("    L = list(s)")
            w(f"    _ap{fp.id}(L, None, rec)")
            w("    return tuple(L)")
            w()
            return
        fc = src.connector
        args = ", ".join(str(r) for r in fc.instance.ports)
        w(f"def _f{src.index}(s, mask, rec):")
        w(f'    """Connector {fc.path}: {fc.type.name}({args})."""')
        w("    L = list(s)")
        if src.kind == "generic":
            w(f"    _fire_tree(_S{src.index}, L, mask, rec)")
            w("    return tuple(L)")
            w()
            return
        info = self.infos[fc.type.name]
        k = self.type_index[fc.type.name]
        vals = ", ".join(self.port_values(fl.ports[p]) for p in src.leaves)
        w(f"    pv = [{vals}]  # {', '.join(fl.ports[p].path for p in src.leaves)}")
        if info.clauses:
            w(f"    lv = {literal(list(info.local_defaults))}")
            if src.kind == "rendezvous":
                w(f"    _g, _u, _d = _K{k}.get({info.all_params}, _NONE)")
            else:
                w(f"    _g, _u, _d = _K{k}.get(mask, _NONE)")
            w("    if _u is not None:")
            w("        _u(pv, lv)")
            w("    if _d is not None:")
            w("        _d(pv, lv)")
        for i, p in enumerate(src.leaves):
            if src.kind == "rendezvous":
                w(f"    _ap{p}(L, pv[{i}], rec)")
            else:
                w(f"    if mask & {1 << i}:")
                w(f"        _ap{p}(L, pv[{i}], rec)")
        w("    return tuple(L)")
        w()

    def gen_priority_guards(self) -> None:
        """``_pg<r>(s)``: guard of compound priority ``r``, reading exported data straight from the state."""
        w = self.w
        for r, pr in enumerate(self.flat.priorities):
            if pr.guard is None:
                continue
            sc = Scope(where=f"priority {pr.name}", constants=pr.constants, externs=self.externs, called=self.called)
            for (comp, name), (slot, ty) in pr.data.items():
                sc.ports[(comp, name)] = Name(f"s[{slot}]", ty)
            w(f"def _pg{r}(s):  # priority {pr.text}")
            w(f"    return {condition(pr.guard, sc)}")
            w()

    # -- enabled -----------------------------------------------------------------------------
    def gen_enabled(self) -> None:
        w = self.w
        fl = self.flat
        w("def enabled(s):")
        w('    """Enabled interactions at state s: maximal ports, connectors, lone ports, then priorities."""')
        names = []
        for fa in fl.atoms:
            names.append(f"m{fa.index}")
            names.extend(f"a{fa.index}_{d.name}" for d in fa.variables)
        if names:
            w(f"    {', '.join(names)}, = s")
        for fa in fl.atoms:
            self.gen_atom_enabled(fa)
        if any(s.kind == "generic" for s in self.sources):
            w(f"    E = ({''.join(f'e{p.id}, ' for p in fl.ports)})")
        w("    out = []")
        for src in self.sources:
            self.gen_source_enabled(src)
        if fl.priorities:
            w("    return _prio(out, s)")
        else:
            w("    return out")

    def gen_atom_enabled(self, fa: FlatAtom) -> None:
        w = self.w
        t: AtomType = fa.type
        sc = self.atom_scope(fa, in_enabled=True)
        places = ", ".join(f"{p}={1 << i}" for i, p in enumerate(fa.places))
        w(f"    # atom {fa.name} ({t.name}): {places}")
        for name, pid in fa.ports.items():
            ts = [tr for tr in t.transitions if tr.port == name]
            if not ts:
                w(f"    e{pid} = False  # {name}: no transition")
            elif len(ts) == 1:
                w(f"    e{pid} = {self.enabled_expr(fa, ts[0], f'm{fa.index}', sc)}  # {describe(ts[0])}")
            else:
                for k, tr in enumerate(ts):
                    w(f"    t{k} = {self.enabled_expr(fa, tr, f'm{fa.index}', sc)}  # {describe(tr)}")
                site = self.error_site(ErrorSite("non-determinism: two transitions enabled on the same port",
                                                 fa.name, name, [describe(tr) for tr in ts]))
                flags = "".join(f"t{k}, " for k in range(len(ts)))
                w(f"    if {' + '.join(f't{k}' for k in range(len(ts)))} > 1:")
                w(f"        _nondet({site}, ({flags}))")
                w(f"    e{pid} = {' or '.join(f't{k}' for k in range(len(ts)))}")
        if t.priorities:
            self.gen_atom_priorities(fa, sc)

    def gen_atom_priorities(self, fa: FlatAtom, sc: Scope) -> None:
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
        w(f"    _r = {raw}")
        w("    if _r:")
        w(f"        _r = _aprio{fa.index}(_r, {act})  # atom priorities of {fa.name}")
        for i, p in enumerate(order):
            w(f"        e{fa.ports[p]} = (_r & {1 << i}) != 0")

    def gen_source_enabled(self, src: Source) -> None:
        w = self.w
        fl = self.flat
        if src.kind == "port":
            w(f"    if e{src.port.id}:  # lone port {src.port.path}")
            w(f"        out.append(_I{src.index}_1)")
            return
        fc = src.connector
        args = ", ".join(str(r) for r in fc.instance.ports)
        w(f"    # connector {fc.path}: {fc.type.name}({args})")
        if src.kind == "generic":
            w(f"    for _k in _generic(_S{src.index}, s, E):")
            w(f"        out.append(_IC{src.index}.get(_k) or _mk({src.index}, _k))")
            return
        info = self.infos[fc.type.name]
        k = self.type_index[fc.type.name]
        enabled = [f"e{p}" for p in src.leaves]
        if src.kind == "rendezvous":
            spec = info.clauses.get(info.all_params)
            cond = " and ".join(enabled)
            if spec is not None and spec.guard is not None:
                sc = self.inline_scope(src, info)
                cond += f" and {condition(spec.guard, sc)}"
            w(f"    if {cond}:")
            w(f"        out.append(_I{src.index}_{src.full})")
            return
        w(f"    em = {' | '.join(f'{e} << {i}' if i else e for i, e in enumerate(enabled))}")
        if any(spec.guard is not None for spec in info.clauses.values()):
            vals = ", ".join(self.inline_values(fl.ports[p]) for p in src.leaves)
            w("    if em:")
            w(f"        pv = [{vals}]")
            w(f"        for _k in _maximal_enabled(_T{k}, em, lambda m: m in _G{k} and not _G{k}[m](pv)):")
            w(f"            out.append(_IC{src.index}.get(_k) or _mk({src.index}, _k))")
        elif defines.is_flat(info.tree):
            w(f"    if em & {defines.triggers(info.tree)}:")
            w(f"        out.append(_IC{src.index}.get(em) or _mk({src.index}, em))")
        else:
            w(f"    _k = _max_allowed(_T{k}, em)")
            w("    if _k:")
            w(f"        out.append(_IC{src.index}.get(_k) or _mk({src.index}, _k))")

    def inline_values(self, fp) -> str:
        fa = self.flat.atoms[fp.atom]
        return "[" + ", ".join(f"a{fa.index}_{v}" for v in fp.decl.data) + "]"

    def inline_scope(self, src: Source, info: ConnectorInfo) -> Scope:
        """Scope of a rendezvous guard inlined in ``enabled``: port data are the atoms' unpacked variables."""
        sc = self.connector_scope(info, info.all_params, False, "const")
        for i, p in enumerate(info.type.params):
            fp = self.flat.ports[src.leaves[i]]
            fa = self.flat.atoms[fp.atom]
            for f, v, ty in zip(fp.fields, fp.decl.data, fp.field_types):
                sc.ports[(p.name, f)] = Name(f"a{fa.index}_{v}", ty)
        return sc


def _assign(name: str, value):
    from runtime.model.expressions import Assign, Var
    return Assign(Var(name), value)


def generate(flat: FlatSystem, infos: dict[str, ConnectorInfo], sources: list[Source]) -> Generated:
    """Generate the step module's source for a flat system."""
    return CodeGen(flat, infos, sources).generate()
