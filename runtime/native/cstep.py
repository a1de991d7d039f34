"""C source for one model's step and search, generated from the same flat system as the Python step.

The generated functions mirror :mod:`runtime.engine.codegen` one to one, and
what both write the same way is :mod:`runtime.engine.stepgen`'s (this is its C half):
``in<i>`` eager internal transitions of atom ``i``, ``ap<p>`` firing of
atom port ``p``, ``f<k>`` firing of source ``k``, ``enabled`` (atom ports,
atom priorities, connectors, lone ports, then compound priorities) and the
codel odometer of :mod:`runtime.explore.choices`.  Atom and compound
priority tables are computed by the Python step's own
:class:`~runtime.engine.support.AtomPriorities` and
:class:`~runtime.engine.support.Priorities`, one entry per combination of
their guards.  The search itself is fixed C text (``search.c``) included
after the model.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path

from runtime.engine import defines
from runtime.engine.emit import CWriter
from runtime.engine.errors import ModelError
from runtime.engine.flatten import FlatAtom
from runtime.engine.stepgen import MAX_INTERNAL, StepEmitter, describe
from runtime.explore.choices import Choice
from runtime.explore.layout import Slot
from runtime.native.cexpr import (
    CName,
    CScope,
    Externs,
    Unsupported,
    c_type,
    condition,
    intern,
    literal,
    statements,
    stored,
)
from runtime.native.ctree import TreeGen, node_pm, node_pm_of, nodes
from runtime.native.ctree import width as offer_width
from runtime.native.observers import gen_observers
from runtime.native.numbering import Numbering, TooMany
from runtime.native.por import gen_por


def at(sc: CScope, what: str) -> CScope:
    """The same scope, its place in the model made precise (for refusals)."""
    return replace(sc, where=f"{sc.where}, {what}")


SEARCH_C = Path(__file__).with_name("search.c")
#: Guards of atom or compound priorities past which the tables would be too large.
MAX_GUARDED = 10
#: Past this many words, the closures of compound priorities are computed as guard combinations are met.
MAX_REACH_WORDS = 1 << 16
#: Ports of a connector with triggers or sub-connectors: its interactions are masks of 32 bits (a rendezvous has
#: one interaction, whatever its ports: runtime.native.numbering).
MAX_PARAMS = 32
#: Ports of a flat connector up to which its largest interactions are a table rather than computed.
MAX_TABLE = 12
#: Bits of an int field without a declared domain at first (zig-zag: -8..7); doubled when a value outgrows it.
START_BITS = 4

# error codes shared with search.c
E_NONDET, E_UNSAFE, E_STUCK, E_NOTENABLED, E_ARITH, E_CYCLE, E_DOMAIN, E_WIDEN, E_CHOICES, E_FULL = range(1, 11)


@dataclass
class CModel:
    """The generated C text and what Python needs to read the compiled search's answers."""

    source: str
    width: int
    bits: int = 0
    label_ids: dict[int, int] = field(default_factory=dict)  # interaction index -> label id (static ones)
    labels: list[str] = field(default_factory=list)
    numbering: Numbering | None = None  # how the search numbers interactions (the parent links' via)
    floats: list[int] = field(default_factory=list)  # state slots holding the bits of a double
    strings: dict[int, list[str]] = field(default_factory=dict)  # state slot -> its strings by number


class CGen(StepEmitter):
    """Builds the C text of one state space's step; ``generate()`` returns a :class:`CModel`."""

    TRUE, FALSE = "1", "0"
    HAVE_VALUES = "vals"

    def __init__(self, space, choices: dict[str, Choice], widths: dict[int, int], monitors=(),
                 wide_numbers: bool = False) -> None:
        super().__init__(space.engine.flat, CWriter())
        self.wide_numbers = wide_numbers
        self.space = space
        self.widths = widths
        self.monitors = list(monitors)
        self.engine = space.engine
        self.sources = space.engine.sources
        self.infos = space.engine.infos
        self.slots: list[Slot] = space.slots
        self.choices = list(choices.values())
        budget = space.environment.budget
        self.externs = Externs({name: k for k, name in enumerate(choices)},
                               list(space.services) if budget is not None else None)
        self.type_index = {name: k for k, name in enumerate(self.infos)}
        self.maxf = max([len(fp.fields) for fp in self.flat.ports] + [1]
                        + [offer_width(s.tree) for s in self.sources if s.kind == "generic"])

    # -- the language: C ----------------------------------------------------------------------
    def name(self, src: str, type_name: str | None, where: str, assignable: bool = False) -> CName:
        return CName(src, c_type(type_name, where), assignable=assignable)

    def scope(self, where: str, constants: dict, in_guard: bool) -> CScope:
        return CScope(where, self.externs, constants=constants, in_guard=in_guard)

    def condition(self, guard, sc: CScope) -> str:
        return condition(guard, sc)

    def statements(self, body, sc: CScope) -> list[str]:
        return statements(body, sc, "")

    def declare(self, name: str, value: str) -> str:
        return f"V {name} = {value}"

    def both(self, a: str, b: str) -> str:
        return f"({a} && {b})"

    def mask_test(self, var: str, mask: int) -> str:
        return f"(({var} & {mask}) == {mask})"

    def complement(self, mask: int) -> str:
        return f"~(V){mask}"

    def fail_unsafe(self, fa: FlatAtom, t, tgt: int) -> str:
        return f"fail({E_UNSAFE}, {fa.index})"

    def internal_function(self, fa: FlatAtom):
        return self.w.block(f"static void in{fa.index}(V *L)", f"eager internal transitions of {fa.name}")

    def internal_failures(self, fa: FlatAtom, ts):
        return (lambda flags: f"fail({E_NONDET}, {fa.index})"), f"fail({E_STUCK}, {fa.index})"

    @contextmanager
    def bounded(self, stuck: str):
        self.w("int n;")
        with self.w.block("for (n = 0; n < MAXINT; n++)"):
            yield
        self.w.if_then("n == MAXINT", stuck)

    def flag(self, name: str, value: str, comment: str) -> None:
        self.w(f"int {name} = {value};")

    def any_of(self, flags: list[str]) -> str:
        return " || ".join(flags)

    @contextmanager
    def port_cases(self, pid: int):
        self.w(f"int e{pid};")
        with self.w.block(""):
            yield

    def fail_nondet_port(self, fa: FlatAtom, port: str, pid: int, ts, flags: list[str]) -> str:
        return f"fail({E_NONDET}, {pid})"

    def port_function(self, fp, fa: FlatAtom):
        return self.w.block(f"static void ap{fp.id}(V *L, const V *vals)", f"port {fp.path}")

    def not_enabled(self, fa: FlatAtom, fp, ts) -> str:
        return f"fail({E_NOTENABLED}, {fp.id})"

    def call_internal(self, fa: FlatAtom) -> str:
        return f"in{fa.index}(L)"

    def value(self, value, sc: CScope) -> str:
        return stored(value, sc.where, self.externs.strings)

    def initial_function(self):
        return self.w.block("static void initial(V *L)")

    def initial_atom(self, fa: FlatAtom):
        return self.w.block("")

    def initial_marking(self, mask: int, targets: list[str]) -> None:
        self.w.stmt(self.declare("m", str(mask)))

    def in_data(self, sc: CScope, d) -> CScope:
        return at(sc, f"data {d.name}" + (f" ({d.span})" if d.span.line > 0 else ""))

    def in_initial(self, sc: CScope) -> CScope:
        return at(sc, "initial transition")

    def conjunction(self, terms: list[str]) -> str:
        return " && ".join(terms)

    def connector_where(self, info, mask: int) -> str:
        where = f"connector type {info.type.name}"
        spec = info.clauses.get(mask)
        if spec is not None:
            where += f", on {' '.join(spec.ports)}" + (f" ({spec.span})" if spec.span.line > 0 else "")
        return where

    def in_transition(self, sc: CScope, t) -> CScope:
        return at(sc, f"transition {describe(t)}")

    # -- the whole file -------------------------------------------------------------------------
    def generate(self) -> CModel:
        fl = self.flat
        self.value_types = {}
        for s in self.slots:
            if s.kind == "value":
                fa = next(a for a in fl.atoms if a.name == s.atom)
                decl = next(d for d in fa.variables if d.name == s.name)
                self.value_types[s.index] = c_type(decl.type, f"atom {fa.name} ({fa.type.name}), data {s.name}")
        self.check_port_types()
        self.trees = {src.index: TreeGen(self, src) for src in self.sources if src.kind == "generic"}
        for src in self.sources:
            if src.kind != "rendezvous" and len(src.leaves) > MAX_PARAMS:
                raise Unsupported(
                    f"connector {src.connector.path}: {len(src.leaves)} ports, more than the {MAX_PARAMS} "
                    "bits of the compiled step's interaction masks"
                )
        nsrc = len(self.sources)
        try:
            self.numbering = Numbering.of(self.sources, self.wide_numbers)
        except TooMany as exc:
            raise Unsupported(str(exc)) from None
        self.base = fl.state_size + (len(self.space.services) if self.externs.services is not None else 0)
        self.width = self.base + len(self.monitors)
        for m, (mon, _) in enumerate(self.monitors):
            self.slots = self.slots + [Slot(self.base + m, "marking", None, f"observer {mon.name}",
                                            places=max(1, (mon.states - 1).bit_length()))]
        w = self.w
        w(f"/* Step and search of package {fl.package.name}, root {fl.root}: generated by runtime.native.cstep. */")
        w("#include <stdint.h>")
        w(f"#define E {fl.state_size}")
        w(f"#define W {self.width}")
        w(f"#define NSRC {nsrc}")
        w(f"#define MAXF {self.maxf}")
        w(f"#define NSLOTS {len(self.slots)}")
        w(f"#define MAXINT {MAX_INTERNAL}")
        w(f"#define NSERV {len(self.space.services) if self.externs.services is not None else 0}")
        w(self.numbering.c_define())
        w('#include "prelude.h"')
        w(self.numbering.c_offsets())
        self.gen_choices()
        for fa in fl.atoms:
            self.gen_internal(fa)
        for fp in fl.ports:
            self.gen_port(fp)
        self.gen_initial()
        for name, info in self.infos.items():
            self.gen_clauses(name, info)
        for tree in self.trees.values():
            tree.gen_offers()
        for src in self.sources:
            self.gen_fire(src)
        self.gen_fire_table()
        model = CModel("", self.width, numbering=self.numbering)
        self.gen_labels(model)
        self.gen_priorities()
        self.gen_blocked()
        self.gen_enabled()
        gen_observers(w, self.monitors, self.sources, fl, self.base)
        gen_por(w, self.sources, fl, self.prio, self.monitors, enabled=self.externs.services is None)
        intern(self.externs.strings, "")  # every string variable starts as ""
        self.gen_slots()  # last: string fields are as wide as the strings met
        model.bits = self.bits
        names = sorted(self.externs.strings, key=self.externs.strings.get)
        model.floats = [i for i, t in self.value_types.items() if t == "float"]
        model.strings = {i: names for i, t in self.value_types.items() if t == "string"}
        w('#include "search.c"')
        model.source = w.source()
        return model

    def gen_choices(self) -> None:
        n = max(len(self.choices), 1)
        doms = []
        for k, c in enumerate(self.choices):
            vals = []
            for v in c.values:
                if not isinstance(v, int):
                    raise Unsupported(f"choice extern {c.name}: non-integer outcomes are explored in Python only")
                vals.append(literal(v, c.name)[0])
            self.w(f"static const V DOM{k}[] = {{{', '.join(vals)}}};")
            doms.append((f"DOM{k}", len(vals)))
        self.w(f"static const V *const DOMV[{n}] = {{{', '.join(d for d, _ in doms) or '0'}}};")
        self.w(f"static const int DOMN[{n}] = {{{', '.join(str(m) for _, m in doms) or '0'}}};")
        self.w('#include "odometer.h"')

    # -- atoms ----------------------------------------------------------------------------------
    # -- connectors -----------------------------------------------------------------------------
    def gen_clauses(self, name: str, info) -> None:
        """``k<T>_<mask>_g/u/d``: guard, up and down of each ``on`` clause of connector type T."""
        w = self.w
        k = self.type_index[name]
        for mask, spec in info.clauses.items():
            if spec.guard is not None:
                sc = self.connector_scope(info, mask, False, False)
                w(f"static int k{k}_{mask}_g(V pv[][MAXF]) {{ return {condition(spec.guard, sc)}; }}")
            for part, body, rw in (("u", spec.up, False), ("d", spec.down, True)):
                if body:
                    sc = self.connector_scope(info, mask, rw, True)
                    with w.block(f"static void k{k}_{mask}_{part}(V pv[][MAXF], V *lv)"):
                        w.extend(self.statements(body, sc))

    def locals_init(self, info) -> str:
        vals = [stored(v, f"connector type {info.type.name}", self.externs.strings) for v in info.local_defaults]
        return f"V lv[{max(len(vals), 1)}] = {{{', '.join(vals) or '0'}}};"

    def gen_fire(self, src) -> None:
        """``f<k>(L, mask)``: fire interaction ``mask`` of source ``k`` on the state ``L`` (a single one's: 0)."""
        w = self.w
        fl = self.flat
        if src.kind == "generic":
            self.trees[src.index].gen_fire()
            return
        with w.block(f"static void f{src.index}(V *L, uint32_t mask)"):
            if src.kind == "port":
                w(f"(void)mask; ap{src.port.id}(L, 0);")
                return
            info = self.infos[src.connector.type.name]
            k = self.type_index[src.connector.type.name]
            w(f"V pv[{len(src.leaves)}][MAXF];")
            for i, p in enumerate(src.leaves):
                for j, slot in enumerate(fl.ports[p].slots):
                    w(f"pv[{i}][{j}] = L[{slot}];")
            if info.clauses:
                w(self.locals_init(info))
                w("(void)lv;")
                clauses = info.clauses.items()
                if src.kind == "rendezvous":  # its one interaction: every parameter, no mask to switch on
                    clauses = [(m, spec) for m, spec in clauses if m == info.all_params]
                else:
                    w("switch (mask) {")
                for mask, spec in clauses:
                    calls = [f"k{k}_{mask}_{part}(pv, lv);" for part, body in (("u", spec.up), ("d", spec.down))
                             if body]
                    if calls:
                        w(" ".join(calls) if src.kind == "rendezvous" else f"case {mask}: {' '.join(calls)} break;")
                if src.kind != "rendezvous":
                    w("default: break;")
                    w("}")
            for i, p in enumerate(src.leaves):
                if src.kind == "rendezvous":
                    w(f"ap{p}(L, pv[{i}]);")
                else:
                    w.if_then(f"mask & {1 << i}", f"ap{p}(L, pv[{i}])")
            w("(void)mask;")

    def gen_fire_table(self) -> None:
        self.w(
            f"static void (*const FIRE[NSRC])(V *, uint32_t) = {{{', '.join(f'f{s.index}' for s in self.sources)}}};"
        )

    # -- slots: reset of dead variables, domains, packing --------------------------------------------
    def slot_width(self, k: int, s: Slot) -> int:
        if s.never_live:
            return 0  # never live: always the default, no bits
        if s.kind == "marking":
            return max(s.places, 1)
        if s.kind == "bool":
            return 1
        if s.domain is not None:
            return max((s.domain[1] - s.domain[0]).bit_length(), 1)
        if s.kind == "value":
            return 64 if self.value_types[s.index] == "float" else max((len(self.externs.strings) - 1).bit_length(), 1)
        return self.widths.get(k, START_BITS)

    def default(self, s: Slot) -> str:
        """What a dead variable is reset to, as the C state stores it."""
        return stored(s.default if s.default is not None else 0, s.title, self.externs.strings)

    def check_port_types(self) -> None:
        """A port field and the variable it binds hold the same kind of word (a float's bits, a string's number)."""
        for fp in self.flat.ports:
            fa = self.flat.atoms[fp.atom]
            types = {d.name: d.type for d in fa.variables}
            for f, v, ty in zip(fp.fields, fp.decl.data, fp.field_types):
                kinds = {"float" if t == "float" else "string" if t == "string" else "word" for t in (ty, types.get(v))}
                if len(kinds) > 1:
                    raise Unsupported(f"port {fp.path}: field {f} of type {ty} binds {v} of type {types.get(v)}")

    def gen_slots(self) -> None:
        """Straight-line ``pack`` and ``unpack`` (runtime.explore.codec's fields), widths fixed in the text, and
        ``canon``, the words ``unpack(pack(L))`` gives, written straight from ``L``.

        Ints without a declared domain are zig-zag coded in a field of ``widths[k]`` bits; a value that does
        not fit stops the step with E_WIDEN and the slot's position, and the caller regenerates wider.
        """
        w = self.w
        fields, bit = [], 0
        for k, s in enumerate(self.slots):
            width = self.slot_width(k, s)
            fields.append((k, s, width, bit))
            bit += width
        self.bits = bit
        words = max((bit + 63) // 64, 1)
        w(f"#define NW {words}")
        w(f"static const int WIDTHS[NSLOTS > 0 ? NSLOTS : 1] = {{{', '.join(str(f[2]) for f in fields) or '0'}}};")
        with w.block("static void pack(const V *L, uint64_t *o)"):
            w("uint64_t u; V x;")
            for i in range(words):
                w(f"o[{i}] = 0;")
            for k, s, width, off in fields:
                if width:
                    self.pack_slot(k, s, width, off)
        with w.block("static void unpack(const uint64_t *o, V *L)"):
            w("uint64_t u;")
            for k, s, width, off in fields:
                self.unpack_slot(s, width, off)
        # unpack(pack(L)) without the fields in between: what a caller that wants words, not packed states, needs
        with w.block("static void canon(const V *L, V *o)"):
            w("uint64_t u; V x;")
            for k, s, width, off in fields:
                self.canon_slot(k, s, width)
            w("(void)u; (void)x;")

    def slot_value(self, k: int, s: Slot, width: int) -> None:
        """Slot ``s`` (the ``k``-th) read into ``x``, checked and reset if dead; ``u``: its field's bits."""
        w = self.w
        w(f"x = L[{s.index}];")
        if s.domain is not None:
            w.if_then(f"x < {s.domain[0]} || x > {s.domain[1]}", f"fail({E_DOMAIN}, {k})")
        if s.live is not None:
            w.if_then(f"!({s.live_test(lambda m: f'L[{m}]')})", f"x = {self.default(s)}")
        if s.domain is not None:
            w(f"u = (uint64_t)(x - ({s.domain[0]}));")
        elif s.kind in ("marking", "bool"):
            w("u = (uint64_t)x;")
        elif s.kind == "value":
            if self.value_types[s.index] == "float":
                w(f"if (isnan(F(x))) fail({E_ARITH}, 4);  /* the Python explorer never meets a NaN state again */")
            w("u = (uint64_t)x;")
        else:
            w("u = ((uint64_t)x << 1) ^ (uint64_t)(x >> 63);")
            if width < 64:
                w.if_then(f"u >> {width}", f"fail({E_WIDEN}, {k})")

    def pack_slot(self, k: int, s: Slot, width: int, off: int) -> None:
        """Slot ``s`` (the ``k``-th) checked, reset if dead, coded and or-ed into its field at bit ``off``."""
        w = self.w
        self.slot_value(k, s, width)
        word, sh = divmod(off, 64)
        w(f"o[{word}] |= u << {sh};" if sh else f"o[{word}] |= u;")
        if sh and sh + width > 64:
            w(f"o[{word + 1}] |= u >> {64 - sh};")

    def canon_slot(self, k: int, s: Slot, width: int) -> None:
        """Slot ``s`` (the ``k``-th) checked and reset if dead, as ``pack`` then ``unpack`` leave it."""
        if not width:
            self.w(f"o[{s.index}] = {self.default(s)};")
            return
        self.slot_value(k, s, width)
        self.w(f"o[{s.index}] = x;")

    def unpack_slot(self, s: Slot, width: int, off: int) -> None:
        """Slot ``s`` decoded from its field at bit ``off`` (its default when it has no bits)."""
        w = self.w
        if not width:
            w(f"L[{s.index}] = {self.default(s)};")
            return
        word, sh = divmod(off, 64)
        expr = f"(o[{word}] >> {sh})" if sh else f"o[{word}]"
        if sh and sh + width > 64:
            expr = f"({expr} | (o[{word + 1}] << {64 - sh}))"
        mask = f" & UINT64_C({(1 << width) - 1})" if width < 64 else ""
        w(f"u = {expr}{mask};")
        if s.domain is not None:
            w(f"L[{s.index}] = (V)u + ({s.domain[0]});")
        elif s.kind in ("marking", "bool", "value"):
            w(f"L[{s.index}] = (V)u;")
        else:
            w(f"L[{s.index}] = (V)(u >> 1) ^ -(V)(u & 1);")

    # -- labels -----------------------------------------------------------------------------------
    def gen_labels(self, model: CModel) -> None:
        """Label ids: one per distinct label of the interactions whose label does not depend on the mask."""
        ids: dict[str, int] = {}
        static = []
        for src in self.sources:
            named = src.kind == "port" or src.kind == "rendezvous" or (src.connector.named and not src.alternatives)
            inter = self.engine._make(src.index, src.full)
            label = inter.label
            if label not in ids:
                ids[label] = len(ids)
                model.labels.append(label)
            static.append(f"{{{ids[label]}, {1 if named else 0}, {0 if named else src.full}u}}")
        self.w(f"#define NLABELS {len(ids)}")
        self.w(f"static const LabelDesc LABELS[NSRC] = {{{', '.join(static)}}};")

    # -- priorities -----------------------------------------------------------------------------
    def gen_priorities(self) -> None:
        """Atom priority closures and compound priority reach sets, per combination of their guards."""
        from runtime.engine import support

        ns = self.engine.namespace
        for fa in self.flat.atoms:
            ap = ns.get(f"_aprio{fa.index}")
            if ap is None:
                continue
            n = len(ap.ports)
            g = len(ap.guard_bit)
            if g > MAX_GUARDED or n > 32:
                raise Unsupported(f"atom {fa.name}: {g} guarded priorities over {n} ports; the compiled tables take "
                                  f"at most {MAX_GUARDED} guarded ones over 32 ports")
            rows, cyc = [], []
            for active in range(1 << g):
                try:
                    ap._compute(0, active)
                    row = []
                    for p in range(n):
                        higher = 0
                        for q in range(n):
                            if q != p and not ap._compute((1 << p) | (1 << q), active) >> p & 1:
                                higher |= 1 << q
                        row.append(str(higher))
                    cyc.append("0")
                except ModelError:
                    row = ["0"] * n
                    cyc.append("1")
                rows.append("{" + ", ".join(row) + "}")
            self.w(f"static const uint32_t APH{fa.index}[{1 << g}][{n}] = {{{', '.join(rows)}}};")
            self.w(f"static const uint8_t APX{fa.index}[{1 << g}] = {{{', '.join(cyc)}}};")
        prio = ns.get("_prio")
        self.prio = prio.__self__ if prio is not None else None
        if self.prio is None:
            return
        pr: support.Priorities = self.prio
        nr = len(pr.rules)
        words = (nr + 63) // 64
        self.w(f"#define NRULES {nr}")
        self.w(f"#define NRW {words}")
        self.dynamic_reach = len(pr.guards) > MAX_GUARDED or (nr * words << len(pr.guards)) > MAX_REACH_WORDS
        if self.dynamic_reach:
            self.gen_reach_cache(pr, words)
        else:
            rows, cyc = [], []
            for key in range(1 << len(pr.guards)):
                bits = tuple(bool(key >> k & 1) for k in range(len(pr.guards)))
                try:
                    reach = pr._reach(bits)
                    cyc.append("0")
                except ModelError:
                    reach = [0] * nr
                    cyc.append("1")
                rows.append("{" + ", ".join(_words(r, words) for r in reach) + "}")
            self.w(f"static const uint64_t PREACH[{1 << len(pr.guards)}][{nr}][NRW] = {{{', '.join(rows)}}};")
            self.w(f"static const uint8_t PCYC[{1 << len(pr.guards)}] = {{{', '.join(cyc)}}};")
        # guard functions of compound priorities, reading exported data from the state
        for k, (r, _) in enumerate(pr.guards):
            fp = self.flat.priorities[r]
            self.w(f"static int pg{k}(const V *s) {{ return {condition(fp.guard, self.priority_scope(fp))}; }}")
        # low/high rule masks of each source's interactions: parts are [(connector id, mask)]
        for src in self.sources:
            for side, name in ((1, "lo"), (2, "hi")):
                terms = []
                if src.kind == "rendezvous":  # one interaction: which rules it is in is known now
                    pms = {node.connector.id: node_pm_of(node, src.full) for node in nodes(src.tree)}
                    for i, rule in enumerate(pr.rules):
                        if any(_in_rule(pms[c], pm, side) for c, pm in rule[side] if c in pms):
                            terms.append(f"o[{i >> 6}] |= UINT64_C({1 << (i & 63)});")
                elif src.tree is not None:
                    pms = {node.connector.id: node_pm(node) for node in nodes(src.tree)}
                    for i, rule in enumerate(pr.rules):
                        conds = [(f"({pms[c]} & {pm}u) == {pm}u" + ("" if pm else f" && {pms[c]}")
                                  if side == 2 or pm == 0 else f"({pms[c]} & ~{pm}u) == 0u && {pms[c]}")
                                 for c, pm in rule[side] if c in pms]
                        if conds:
                            terms.append(f"if ({' || '.join(conds)}) o[{i >> 6}] |= UINT64_C({1 << (i & 63)});")
                self.w(f"static void {name}{src.index}(uint32_t mask, uint64_t *o) {{ (void)mask; (void)o; "
                       f"{' '.join(terms)} }}")
        for name in ("lo", "hi"):
            self.w(f"static void (*const {name.upper()}T[NSRC])(uint32_t, uint64_t *) = "
                   f"{{{', '.join(f'{name}{s.index}' for s in self.sources)}}};")

    def gen_blocked(self) -> None:
        """``blocked<k>(m, pv)``: the guard of interaction ``m`` of a flat connector source is false.

        Also ``maxa<k>(em)``: the largest interaction within the enabled ports ``em`` (defines.max_allowed),
        a table up to MAX_TABLE ports, computed from the define tree past that.
        """
        for src in self.sources:
            if src.kind != "flat":
                continue
            self.gen_max_allowed(src)
            info = self.infos[src.connector.type.name]
            k = self.type_index[src.connector.type.name]
            cases = " ".join(f"case {m}: return !k{k}_{m}_g(pv);" for m, spec in info.clauses.items()
                             if spec.guard is not None)
            if cases:
                self.w(f"static int blocked{src.index}(uint32_t m, V pv[][MAXF]) "
                       f"{{ switch (m) {{ {cases} default: return 0; }} }}")

    def gen_max_allowed(self, src) -> None:
        tree = self.infos[src.connector.type.name].tree
        n = len(src.leaves)
        if n <= MAX_TABLE:
            table = ", ".join(str(defines.max_allowed(tree, em)) for em in range(1 << n))
            self.w(f"static uint32_t maxa{src.index}(uint32_t em) {{ static const uint32_t T[] = {{{table}}}; "
                   "return T[em]; }")
            return
        with self.w.block(f"static uint32_t maxa{src.index}(uint32_t em)"), self.w.names():
            self.w(f"return {max_allowed_c(tree, self.w)};")

    # -- enabled ----------------------------------------------------------------------------------
    def gen_enabled(self) -> None:
        """``enabled(s, isrc, imask)``: atom ports, then each source's maximal interactions, then priorities."""
        w = self.w
        fl = self.flat
        w(f"static TL uint8_t PEN[{max(len(fl.ports), 1)}]; /* ports enabled in their atom: the reduction's view */")
        with w.block("static int enabled(const V *s, uint32_t *isrc, uint32_t *imask)"):
            w("int n = 0;")
            for fa in fl.atoms:
                w(f"const V m{fa.index} = s[{fa.offset}]; (void)m{fa.index};")
                for d in fa.variables:
                    w(f"const V a{fa.index}_{d.name} = s[{fa.slot(d.name)}]; (void)a{fa.index}_{d.name};")
            for fa in fl.atoms:
                self.gen_atom_enabled(fa)
            for fp in fl.ports:
                w(f"PEN[{fp.id}] = (uint8_t)e{fp.id};")
            if self.trees:
                w(f"const uint8_t EP[{max(len(fl.ports), 1)}] = "
                  f"{{{', '.join(f'(uint8_t)e{fp.id}' for fp in fl.ports)}}};")
            for src in self.sources:
                self.gen_source_enabled(src)
            if self.prio is not None:
                with w.block("if (n)"):
                    self.gen_compound_priorities()
            w("return n;")

    def gen_reach_cache(self, pr, words: int) -> None:
        """Rule closures computed when a combination of guards is first met, kept per thread (many guards).

        ``reach_of(key)`` returns the closure of the rules active under the guard
        values ``key`` (``NGW`` words), or NULL when they form a cycle; the static
        table of every combination would be exponential in the guards.
        """
        nr, ng = len(pr.rules), len(pr.guards)
        gw = max(1, (ng + 63) // 64)
        edges = ", ".join(_words(sum(1 << y for y in pr.edges[r]), words) for r in range(nr))
        guarded = sum(1 << r for r, _ in pr.guards)
        w = self.w
        w(f"#define NGW {gw}")
        w(f"static const uint64_t PEDGE[NRULES][NRW] = {{{edges}}};")
        w(f"static const uint64_t PFIXED[NRW] = {_words(((1 << nr) - 1) & ~guarded, words)};")
        w(f"static const int PGRULE[{max(1, ng)}] = {{{', '.join(str(r) for r, _ in pr.guards) or '0'}}};")
        w("typedef struct { uint64_t key[NGW]; uint8_t cyc; uint64_t reach[NRULES][NRW]; } PReach;")
        w("static TL PReach **PCACHE; static TL uint64_t PCAP, PUSED;")
        with w.block("static PReach *reach_compute(const uint64_t *key)"):
            w("PReach *e = (PReach *)calloc(1, sizeof(PReach));")
            w("if (!e) fail(E_FULL, 0);")
            w("memcpy(e->key, key, sizeof(e->key));")
            w("uint64_t active[NRW];")
            w("for (int x = 0; x < NRW; x++) active[x] = PFIXED[x];")
            w(f"for (int k = 0; k < {ng}; k++) if (key[k >> 6] >> (k & 63) & 1) "
              "active[PGRULE[k] >> 6] |= UINT64_C(1) << (PGRULE[k] & 63);")
            with w.block("for (int r = 0; r < NRULES; r++)"):
                w("if (!(active[r >> 6] >> (r & 63) & 1)) continue;")
                w("uint64_t *seen = e->reach[r], todo[NRW] = {0};")
                w("seen[r >> 6] |= UINT64_C(1) << (r & 63); todo[r >> 6] |= UINT64_C(1) << (r & 63);")
                with w.block("for (int more = 1; more;)"):
                    w("more = 0;")
                    with w.block("for (int y = 0; y < NRULES; y++)"):
                        w("if (!(todo[y >> 6] >> (y & 63) & 1)) continue;")
                        w("todo[y >> 6] &= ~(UINT64_C(1) << (y & 63));")
                        with w.block("for (int x = 0; x < NRW; x++)"):
                            w("uint64_t next = PEDGE[y][x] & active[x];")
                            w("if (x == (r >> 6) && (next >> (r & 63) & 1)) e->cyc = 1;")
                            w("next &= ~seen[x]; seen[x] |= next; todo[x] |= next; more |= next != 0;")
            w("return e;")
        with w.block("static uint64_t reach_hash(const uint64_t *key)"):  # FNV-1a over the guard words
            w("uint64_t h = 1469598103934665603ull;")
            w("for (int x = 0; x < NGW; x++) h = (h ^ key[x]) * 1099511628211ull;")
            w("return h;")
        with w.block("static PReach *reach_of(const uint64_t *key)"):
            w("uint64_t h = reach_hash(key);")
            with w.block("if (PUSED * 2 >= PCAP)"):
                w("uint64_t cap = PCAP ? PCAP * 2 : 64;")
                w("PReach **t = (PReach **)calloc(cap, sizeof(PReach *));")
                w("if (!t) fail(E_FULL, 0);")
                w("for (uint64_t i = 0; i < PCAP; i++) if (PCACHE[i]) {")
                w("    uint64_t j = reach_hash(PCACHE[i]->key) & (cap - 1);")
                w("    while (t[j]) j = (j + 1) & (cap - 1);")
                w("    t[j] = PCACHE[i]; }")
                w("free(PCACHE); PCACHE = t; PCAP = cap;")
            w("uint64_t j = h & (PCAP - 1);")
            with w.block("while (PCACHE[j])"):
                w("if (!memcmp(PCACHE[j]->key, key, sizeof(PCACHE[j]->key))) return PCACHE[j];")
                w("j = (j + 1) & (PCAP - 1);")
            w("PCACHE[j] = reach_compute(key); PUSED++;")
            w("return PCACHE[j];")

    def gen_compound_priorities(self) -> None:
        """Drop the interactions low in a compound priority whose high side (reached through the rules) is enabled."""
        w = self.w
        if self.dynamic_reach:
            w("uint64_t key[NGW] = {0};")
            for k in range(len(self.prio.guards)):
                w(f"if (pg{k}(s)) key[{k >> 6}] |= UINT64_C({1 << (k & 63)});")
            w("const PReach *pr = reach_of(key);")
            w.if_then("pr->cyc", f"fail({E_CYCLE}, -1)")
            reach = "pr->reach[r][x]"
        else:
            key = " | ".join(f"(pg{k}(s) ? {1 << k} : 0)" for k in range(len(self.prio.guards))) or "0"
            w(f"int key = {key};")
            w.if_then("PCYC[key]", f"fail({E_CYCLE}, -1)")
            reach = "PREACH[key][r][x]"
        w("uint64_t high[NRW] = {0}, blocked[NRW] = {0};")
        w("int any = 0;")
        w("for (int i = 0; i < n; i++) HIT[isrc[i]](imask[i], high);")
        w("for (int x = 0; x < NRW; x++) any |= high[x] != 0;")
        with w.block("if (any)"):
            w("int b = 0;")
            w("for (int r = 0; r < NRULES; r++)")
            w("    for (int x = 0; x < NRW; x++)")
            w(f"        if ({reach} & high[x]) {{ blocked[r >> 6] |= UINT64_C(1) << (r & 63); b = 1; break; }}")
            with w.block("if (b)"):
                w("int k = 0;")
                with w.block("for (int i = 0; i < n; i++)"):
                    w("uint64_t low[NRW] = {0};")
                    w("int hit = 0;")
                    w("LOT[isrc[i]](imask[i], low);")
                    w("for (int x = 0; x < NRW; x++) hit |= (low[x] & blocked[x]) != 0;")
                    w("if (!hit) { isrc[k] = isrc[i]; imask[k] = imask[i]; k++; }")
                w("n = k;")

    def gen_atom_priorities(self, fa: FlatAtom, sc: CScope) -> None:
        """The atom's ports filtered by its priorities: the table of the guards' combination (APH, APX)."""
        w = self.w
        t = fa.type
        ap = self.engine.namespace[f"_aprio{fa.index}"]
        order = ap.ports
        guarded = sorted(ap.guard_bit, key=lambda r: ap.guard_bit[r])
        guards = [condition(t.priorities[r].guard, sc) for r in guarded]
        raw = " | ".join(f"((uint32_t)e{fa.ports[p]} << {i})" for i, p in enumerate(order))
        act = " | ".join(f"(({g}) ? {1 << k} : 0)" for k, g in enumerate(guards)) or "0"
        with w.block(""):
            w(f"uint32_t r = {raw};")
            with w.block("if (r)"):
                w(f"int act = {act};")
                w.if_then(f"APX{fa.index}[act]", f"fail({E_CYCLE}, {fa.index})")
                w("uint32_t out = r;")
                w(f"for (int p = 0; p < {len(order)}; p++) if (r & APH{fa.index}[act][p]) out &= ~(1u << p);")
                for i, p in enumerate(order):
                    w(f"e{fa.ports[p]} = (out >> {i}) & 1;")

    def gen_source_enabled(self, src) -> None:
        """The part of ``enabled`` that adds the maximal enabled interactions of one source."""
        w = self.w
        fl = self.flat
        if src.kind == "port":
            w(f"if (e{src.port.id}) {{ isrc[n] = {src.index}; imask[n] = 0; n++; }}")
            return
        if src.kind == "generic":
            self.trees[src.index].gen_enabled()
            return
        info = self.infos[src.connector.type.name]
        if src.kind == "rendezvous":
            w(f"if ({self.rendezvous_enabled(src, info)}) {{ isrc[n] = {src.index}; imask[n] = 0; n++; }}")
            return
        enabled = [f"e{p}" for p in src.leaves]
        nparams = len(src.leaves)
        with w.block(""):
            w(f"uint32_t em = {' | '.join(f'((uint32_t){e} << {i})' for i, e in enumerate(enabled))};")
            guarded = {mask: spec for mask, spec in info.clauses.items() if spec.guard is not None}
            if guarded:
                with w.block("if (em)"):
                    w(f"V pv[{nparams}][MAXF];")
                    for i, p in enumerate(src.leaves):
                        fp = fl.ports[p]
                        fa = fl.atoms[fp.atom]
                        for j, v in enumerate(fp.decl.data):
                            w(f"pv[{i}][{j}] = a{fa.index}_{v};")
                    w(f"n = maximal_enabled(maxa{src.index}, em, {nparams}, pv, blocked{src.index}, "
                      f"{src.index}, isrc, imask, n);")
            elif defines.is_flat(info.tree):
                w(f"if (em & {defines.triggers(info.tree)}) {{ isrc[n] = {src.index}; imask[n] = em; n++; }}")
            else:
                w(f"uint32_t k = maxa{src.index}(em);")
                w(f"if (k) {{ isrc[n] = {src.index}; imask[n] = k; n++; }}")


def _in_rule(part: int, pm: int, side: int) -> bool:
    """Whether a connector taking part with parameters ``part`` matches a rule's ``(connector, pm)`` on ``side``.

    The C conditions above, evaluated for an interaction known in advance: high (2) or ``*`` (pm 0): every
    parameter of pm takes part (and something does); low: nothing outside pm takes part.
    """
    if side == 2 or pm == 0:
        return (part & pm) == pm and (pm != 0 or part != 0)
    return (part & ~pm) == 0 and part != 0


def _words(value: int, words: int) -> str:
    """A set of rules as a C initialiser of ``words`` 64-bit words."""
    return "{" + ", ".join(f"UINT64_C({value >> (64 * k) & ((1 << 64) - 1)})" for k in range(words)) + "}"


def max_allowed_c(node, w: CWriter) -> str:
    """C statements computing :func:`defines.max_allowed` of ``node`` within ``em``; returns the result's name."""
    if node[0] == "p":
        name = w.fresh("t")
        w(f"uint32_t {name} = em & {node[1]}u;")
        return name
    subs = [(max_allowed_c(sub, w), trig) for sub, trig in node[1]]
    union = " | ".join(t for t, _ in subs)
    if any(trig for _, trig in subs):
        cond = " || ".join(t for t, trig in subs if trig)
    else:
        cond = " && ".join(t for t, _ in subs)
    name = w.fresh("t")
    w(f"uint32_t {name} = ({cond}) ? ({union}) : 0u;")
    return name


def generate(space, choices: dict[str, Choice], widths: dict[int, int] | None = None, monitors=(),
             wide_numbers: bool = False) -> CModel:
    """The C text of a state space's step and search (raises :class:`Unsupported` with the reason).

    ``widths`` gives the field of some int slots (by position in the layout) wider than START_BITS;
    ``monitors`` are ``(Monitor, statics)`` safety observers stepped with every interaction;
    ``wide_numbers``: 64-bit interaction numbers even when the model's fit in 32 bits.
    """
    gen = CGen(space, choices, dict(widths or {}), monitors, wide_numbers)
    return gen.generate()
