"""The BIP model as a Promela model for SPIN: one guarded ``atomic`` step per interaction over the flat state.

Layout: one global per state slot (markings as bit fields, variables with the
narrowest type their values need), macros for the enabledness of every atom
port (atom priorities folded in), of every interaction (guard along its
connector tree), after maximal progress, and after compound priorities; then
one process looping over ``atomic { go_k -> effect_k }``.  An effect runs the
connectors' ``up``/``down`` on hidden temporaries, fires each atom's
transition (the one enabled before the transfer), its eager internal
transitions, and resets the dead variables exactly as the explorer does, so
both tools count the same states.  Codel calls become ``if :: x = 0 :: x = 1 ... fi``.
Each effect prints ``@@i <index>`` and each codel choice ``@@o <position>``:
a SPIN trail replayed with ``pan -r -S`` is translated back into our labels.

Not translated (refused with a message): floats, strings, extern functions
bound to Python code, choice externs in guards.  Model errors the engine
detects (non-determinism, 1-safety, livelock) are not checked in Promela.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from runtime.engine.flatten import FlatAtom
from runtime.engine.plan import TreeNode
from runtime.explore.choices import Choice, ExploreError
from runtime.explore.layout import Slot
from runtime.explore.space import StateSpace
from runtime.export.interactions import Static, all_interactions, rule_edges
from runtime.model.expressions import Assign, Binary, Call, Const, Do, Expr, If, PortData, Unary, Var

#: Most simple paths through guarded priority rules before the translation gives up.
MAX_PATHS = 10_000


class PromelaError(ExploreError):
    """The model uses something Promela cannot express (or this translation does not)."""


@dataclass
class Name:
    text: str
    type: str | None


@dataclass
class Scope:
    """How names read in one context: atom variables, port data (or exported data), constants."""

    where: str
    variables: dict[str, Name] = field(default_factory=dict)
    ports: dict[tuple[str, str], Name] = field(default_factory=dict)
    constants: dict[str, tuple[Any, str]] = field(default_factory=dict)


@dataclass
class Monitor:
    """A safety observer compiled into the steps: a deterministic automaton over interactions.

    ``delta[k]`` maps a monitor state to the next one for interaction ``k``;
    ``bad`` are the states where the property is violated (``check`` then
    must hold, a Promela expression over the state, e.g. an invariant's
    predicate; ``false`` for ``never`` and ``precedes``).
    """

    name: str
    states: int
    delta: list[dict[int, int]]
    accepting: set[int]
    check: str = "false"
    initial: int = 0
    pred: Any = None  # the predicate F of [R] {F}, translated by the writer once names are known


def literal(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    raise PromelaError(f"Promela has no value like {value!r} (only integers and booleans)")


def int_type(lo: int, hi: int) -> str:
    if 0 <= lo and hi <= 255:
        return "byte"
    if -32768 <= lo and hi <= 32767:
        return "short"
    return "int"


class PromelaWriter:
    """Builds the Promela text for a state space's model (its layout, reduction, environment, initial states)."""

    def __init__(self, space: StateSpace, monitors: list[Monitor] | None = None, hidden: bool = True) -> None:
        self.space = space
        self.hidden = hidden  # SPIN's multi-core mode refuses hidden variables: reset them after each step instead
        self.engine = space.engine
        self.flat = space.engine.flat
        self.slots: list[Slot] = space.slots
        self.monitors = monitors or []
        self.choices: dict[str, Choice] = {}
        for name, fn in self._bound_choices().items():
            self.choices[name] = fn
        self.names: dict[int, str] = {}
        self.types: dict[int, str] = {}
        self.temps: list[tuple[str, str]] = []
        self.lines: list[str] = []
        self.statics: list[Static] = all_interactions(self.engine)

    # -- what the explorer bound --------------------------------------------------------------------------
    def _bound_choices(self) -> dict[str, Choice]:
        from runtime.explore.choices import codel_choices
        return codel_choices(self.engine.package)

    # -- names and types ------------------------------------------------------------------------------------
    def temp(self, type_: str) -> str:
        name = f"t_{len(self.temps)}"
        self.temps.append((name, type_))
        return name

    def _declare_slots(self) -> None:
        ranges = self._int_ranges()
        for s in self.slots:
            if s.kind == "marking":
                fa = next(a for a in self.flat.atoms if a.offset == s.index)
                self.names[s.index] = f"m{fa.index}"
                self.types[s.index] = f"unsigned : {max(s.places, 1)}"
            elif s.kind == "requests":
                self.names[s.index] = f"r{s.index - self.space.width}"
                self.types[s.index] = "byte"
            else:
                fa = next(a for a in self.flat.atoms if a.name == s.atom)
                self.names[s.index] = f"a{fa.index}_{s.name}"
                if s.kind == "bool":
                    self.types[s.index] = "bool"
                elif s.kind == "int":
                    rng = s.domain or ranges.get(s.index)
                    self.types[s.index] = int_type(*rng) if rng else "int"
                else:
                    raise PromelaError(f"variable {s.title} is not an int or a bool: Promela cannot hold it")

    def _int_ranges(self) -> dict[int, tuple[int, int]]:
        """Int variables only ever assigned constants or codel outcomes: the range of those values."""
        written_by_connectors = set()
        for fc in self.flat.connectors:
            for spec in fc.type.interactions:
                for st in spec.down:
                    if isinstance(st, Assign) and isinstance(st.target, PortData):
                        written_by_connectors.add((fc.id, st.target.port))
        open_ports = set()
        for fc in self.flat.connectors:
            for (cid, pname) in written_by_connectors:
                if cid != fc.id:
                    continue
                k = next(i for i, p in enumerate(fc.type.params) if p.name == pname)
                for alt in fc.params[k]:
                    if hasattr(alt, "port"):
                        fp = self.flat.ports[alt.port]
                        open_ports.update((fp.atom, v) for v in fp.decl.data)
        out: dict[int, tuple[int, int]] = {}
        for fa in self.flat.atoms:
            for d in fa.variables:
                if d.type != "int" or (fa.index, d.name) in open_ports:
                    continue
                values = self._assigned_values(fa, d.name)
                if values is not None:
                    out[fa.slot(d.name)] = (min(values), max(values))
        return out

    def _assigned_values(self, fa: FlatAtom, var: str) -> set[int] | None:
        values: set[int] = {0}
        decl = next(d for d in fa.variables if d.name == var)
        bodies = [fa.type.initial.action] + [t.action for t in fa.type.transitions]
        if decl.init is not None:
            bodies.append([Assign(Var(var), decl.init)])

        def walk(stmts) -> bool:
            for st in stmts:
                if isinstance(st, Assign) and isinstance(st.target, Var) and st.target.name == var:
                    v = st.value
                    if isinstance(v, Const) and isinstance(v.value, int) and not isinstance(v.value, bool):
                        values.add(v.value)
                    elif isinstance(v, Var) and v.name in fa.constants and isinstance(fa.constants[v.name][0], int):
                        values.add(int(fa.constants[v.name][0]))
                    elif isinstance(v, Call) and v.function in self.choices:
                        values.update(int(x) for x in self.choices[v.function].values)
                    else:
                        return False
                elif isinstance(st, If):
                    if not walk(st.then) or not walk(st.orelse):
                        return False
            return True

        return values if all(walk(b) for b in bodies) else None

    def atom_scope(self, fa: FlatAtom) -> Scope:
        sc = Scope(f"atom {fa.name}", constants=dict(fa.constants))
        for d in fa.variables:
            slot = fa.slot(d.name)
            sc.variables[d.name] = Name(self.names[slot], d.type)
        return sc

    # -- expressions -----------------------------------------------------------------------------------------
    def expr(self, e: Expr, sc: Scope) -> tuple[str, str | None]:
        if isinstance(e, Const):
            v = e.value
            return literal(v), "bool" if isinstance(v, bool) else "int"
        if isinstance(e, Var):
            if e.name in sc.variables:
                n = sc.variables[e.name]
                return n.text, n.type
            if e.name in sc.constants:
                v, t = sc.constants[e.name]
                return literal(v), t
            raise PromelaError(f"{sc.where}: unknown name {e.name}")
        if isinstance(e, PortData):
            n = sc.ports.get((e.port, e.name))
            if n is None:
                raise PromelaError(f"{sc.where}: unknown port data {e.port}.{e.name}")
            return n.text, n.type
        if isinstance(e, Unary):
            s, t = self.expr(e.operand, sc)
            return f"({e.op}{s})", "bool" if e.op == "!" else t
        if isinstance(e, Binary):
            ls, lt = self.expr(e.left, sc)
            rs, rt = self.expr(e.right, sc)
            t = "bool" if e.op in ("&&", "||", "==", "!=", "<", "<=", ">", ">=") else "int"
            return f"({ls} {e.op} {rs})", t
        if isinstance(e, Call):
            return self.call_expr(e, sc), "bool"
        raise PromelaError(f"{sc.where}: cannot translate {e!r}")

    def call_expr(self, e: Call, sc: Scope) -> str:
        if e.function == "request_pending":
            k = self._service(e)
            return "true" if k is None else f"(r{k} < {self.space.environment.budget})"
        if e.function in self.choices:
            raise PromelaError(f"{sc.where}: codel {e.function} is called in a guard; only actions may branch")
        raise PromelaError(f"{sc.where}: extern function {e.function} is bound to Python code, which Promela cannot "
                           "call (only codels with declared outcomes and the request externs translate)")

    def _service(self, e: Call) -> int | None:
        if self.space.environment.budget is None:
            return None
        if not e.args or not isinstance(e.args[0], Const):
            raise PromelaError(f"{e.function} needs a constant service name to translate")
        return self.space.environment.slot(e.args[0].value)

    def cond(self, e: Expr | None, sc: Scope) -> str:
        return "true" if e is None else self.expr(e, sc)[0]

    # -- statements -------------------------------------------------------------------------------------------
    def hoist(self, e: Expr, sc: Scope, out: list[str], ind: str) -> Expr:
        """Replace codel calls in ``e`` by temporaries chosen nondeterministically (in evaluation order)."""
        if isinstance(e, Call):
            args = tuple(self.hoist(a, sc, out, ind) for a in e.args)
            if e.function in self.choices:
                choice = self.choices[e.function]
                t = self.temp("int")
                options = " ".join(f':: {t} = {literal(v)}; printf("@@o {k}\\n")'
                                   for k, v in enumerate(choice.values))
                out.append(f"{ind}if {options} fi;")
                sc.variables[t] = Name(t, "int")
                return Var(t)
            return Call(e.function, args)
        if isinstance(e, Unary):
            return Unary(e.op, self.hoist(e.operand, sc, out, ind))
        if isinstance(e, Binary):
            return Binary(e.op, self.hoist(e.left, sc, out, ind), self.hoist(e.right, sc, out, ind))
        return e

    def stmts(self, body, sc: Scope, ind: str) -> list[str]:
        out: list[str] = []
        for st in body:
            if isinstance(st, Assign):
                value = self.hoist(st.value, sc, out, ind)
                target = self.expr(st.target, sc)[0]
                out.append(f"{ind}{target} = {self.expr(value, sc)[0]};")
            elif isinstance(st, If):
                cond = self.hoist(st.cond, sc, out, ind)
                then = self.stmts(st.then, sc, ind + "   ") or [f"{ind}   skip;"]
                orelse = self.stmts(st.orelse, sc, ind + "   ") or [f"{ind}   skip;"]
                out.append(f"{ind}if")
                out.append(f"{ind}:: {self.expr(cond, sc)[0]} ->")
                out.extend(then)
                out.append(f"{ind}:: else ->")
                out.extend(orelse)
                out.append(f"{ind}fi;")
            elif isinstance(st, Do):
                call = st.call
                if call.function == "take_request":
                    k = self._service(call)
                    if k is not None:
                        out.append(f"{ind}r{k}++;")
                elif call.function == "request_pending":
                    pass
                else:
                    self.hoist(call, sc, out, ind)
            else:
                raise PromelaError(f"{sc.where}: cannot translate {st!r}")
        return out

    # -- atoms ------------------------------------------------------------------------------------------------
    def marked(self, fa: FlatAtom, places) -> str:
        mask = fa.place_mask(list(places))
        return f"(m{fa.index} & {mask}) == {mask}" if mask else "true"

    def raw_port(self, fa: FlatAtom, port: str) -> str:
        sc = self.atom_scope(fa)
        terms = []
        for t in fa.type.transitions:
            if t.port == port:
                g = self.cond(t.guard, sc)
                terms.append(f"({self.marked(fa, t.sources)}{'' if g == 'true' else ' && ' + g})")
        return " || ".join(terms) or "false"

    def port_macros(self) -> list[str]:
        """``rp<p>``: a transition on port p is enabled; ``pe<p>``: and no higher port of its atom is."""
        lines = []
        for fa in self.flat.atoms:
            for port, pid in fa.ports.items():
                lines.append(f"#define rp{pid} ({self.raw_port(fa, port)})  /* {fa.name}.{port} */")
            sc = self.atom_scope(fa)
            rules = []
            order = list(fa.ports)
            for pr in fa.type.priorities:
                lows = [p for p in order if p != pr.high] if pr.low == "*" else [pr.low]
                highs = [p for p in order if p != pr.low] if pr.high == "*" else [pr.high]
                g = self.cond(pr.guard, sc)
                for lo in lows:
                    for hi in highs:
                        rules.append((lo, hi, g))
            for port, pid in fa.ports.items():
                above = self._above(port, rules)
                if above:
                    blocked = " || ".join(f"({g} && rp{fa.ports[q]})" if g != "true" else f"rp{fa.ports[q]}"
                                          for q, g in above)
                    lines.append(f"#define pe{pid} (rp{pid} && !({blocked}))")
                else:
                    lines.append(f"#define pe{pid} rp{pid}")
        return lines

    def _above(self, port: str, rules: list[tuple[str, str, str]]) -> list[tuple[str, str]]:
        """Ports above ``port`` through chains of atom priorities, each with the conjunction of their guards."""
        out: list[tuple[str, str]] = []
        count = [0]

        def walk(p: str, guards: tuple[str, ...], seen: frozenset[str]) -> None:
            for lo, hi, g in rules:
                if lo == p and hi not in seen:
                    count[0] += 1
                    if count[0] > MAX_PATHS:
                        raise PromelaError("too many chains of atom priorities to translate")
                    gs = guards + ((g,) if g != "true" else ())
                    out.append((hi, " && ".join(f"({x})" for x in gs) or "true"))
                    walk(hi, gs, seen | {hi})

        walk(port, (), frozenset({port}))
        return out

    def fire_port(self, fa: FlatAtom, port: str, vals: list[str] | None, ind: str) -> list[str]:
        """The port's transition (chosen before the transfer), port values written, then internal transitions."""
        sc = self.atom_scope(fa)
        fp = self.flat.ports[fa.ports[port]]
        out = [f"{ind}if"]
        for t in fa.type.transitions:
            if t.port != port:
                continue
            g = self.cond(t.guard, sc)
            out.append(f"{ind}:: {self.marked(fa, t.sources)}{'' if g == 'true' else ' && ' + g} ->")
            if vals is not None:
                for var, v in zip(fp.decl.data, vals):
                    out.append(f"{ind}   {sc.variables[var].text} = {v};")
            out.extend(self.move(fa, t, sc, ind + "   "))
        out.append(f"{ind}fi;")
        internal = [t for t in fa.type.transitions if t.internal]
        if internal:
            out.append(f"{ind}do")
            for t in internal:
                g = self.cond(t.guard, sc)
                out.append(f"{ind}:: {self.marked(fa, t.sources)}{'' if g == 'true' else ' && ' + g} ->")
                out.extend(self.move(fa, t, sc, ind + "   "))
            out.append(f"{ind}:: else -> break")
            out.append(f"{ind}od;")
        return out

    def move(self, fa: FlatAtom, t, sc: Scope, ind: str) -> list[str]:
        src, tgt = fa.place_mask(t.sources), fa.place_mask(t.targets)
        m = f"m{fa.index}"
        out = [f"{ind}{m} = ({m} & {~src & ((1 << len(fa.places)) - 1)}) | {tgt};"]
        out.extend(self.stmts(t.action, sc, ind))
        return out

    def resets(self, atoms: set[int], temps: list[str], ind: str) -> list[str]:
        out = []
        for s in self.slots:
            if s.live is None or s.atom is None or (s.live == 0 and self.hidden):
                continue
            fa = next(a for a in self.flat.atoms if a.name == s.atom)
            if fa.index in atoms:
                name = self.names[s.index]
                if s.live == 0:
                    out.append(f"{ind}{name} = {literal(s.default)};")
                else:
                    out.append(f"{ind}{name} = ((m{fa.index} & {s.live}) != 0 -> {name} : {literal(s.default)});")
        if not self.hidden:
            out.extend(f"{ind}{t} = 0;" for t in temps)
        return out

    # -- connectors ---------------------------------------------------------------------------------------------
    def _clause(self, node: TreeNode, pm: int):
        return node.info.clauses.get(pm)

    def _layout(self, node: TreeNode, mask: int) -> tuple[int, list[tuple[int, Any]]]:
        """Parameter mask of the node in interaction ``mask``, and (param index, alternative) taking part."""
        pm = 0
        chosen = []
        for i, alts in enumerate(node.params):
            for a in alts:
                if a.mask & mask:
                    pm |= 1 << i
                    chosen.append((i, a))
                    break
        return pm, chosen

    def guard(self, node: TreeNode, mask: int) -> tuple[str, dict[int, list[str]]]:
        """Guard of the node (and its sub-nodes) in interaction ``mask``, and the exported values (expressions)."""
        pm, chosen = self._layout(node, mask)
        ct = node.info.type
        sc = Scope(f"connector {node.connector.path}", constants=dict(self.flat.constants))
        terms = []
        for i, a in chosen:
            pname = ct.params[i].name
            ptype = self.flat.package.port_type(ct.params[i].port_type)
            fields_ = [f.name for f in ptype.params] if ptype else []
            if a.node is None:
                fp = self.flat.ports[a.port]
                values = [self.names[s] for s in fp.slots]
            else:
                sub_guard, exported = self.guard(a.node, mask)
                if sub_guard != "true":
                    terms.append(sub_guard)
                values = exported
            for f, v in zip(fields_, values):
                sc.ports[(pname, f)] = Name(v, None)
        spec = self._clause(node, pm)
        for k, d in enumerate(ct.data):
            sc.variables[d.name] = Name(literal(node.info.local_defaults[k]), d.type)
        if spec is not None and spec.guard is not None:
            terms.append(self.cond(spec.guard, sc))
        exported: list[str] = []
        if ct.export is not None:
            env = {d.name: literal(node.info.local_defaults[k]) for k, d in enumerate(ct.data)}
            if spec is not None and spec.up:
                env = self.symbolic(spec.up, sc, env)
            exported = [env[v] for v in ct.export.data]
        return " && ".join(f"({t})" for t in terms) or "true", exported

    def symbolic(self, body, sc: Scope, env: dict[str, str]) -> dict[str, str]:
        """Values of connector locals after ``up``, as expressions (if/else become conditional expressions)."""
        for st in body:
            local = Scope(sc.where, dict(sc.variables), dict(sc.ports), dict(sc.constants))
            for name, text in env.items():
                local.variables[name] = Name(f"({text})", None)
            if isinstance(st, Assign) and isinstance(st.target, Var):
                env = {**env, st.target.name: self.expr(st.value, local)[0]}
            elif isinstance(st, If):
                c = self.cond(st.cond, local)
                a = self.symbolic(st.then, sc, env)
                b = self.symbolic(st.orelse, sc, env)
                env = {k: a[k] if a[k] == b[k] else f"({c} -> {a[k]} : {b[k]})" for k in env}
            else:
                raise PromelaError(f"{sc.where}: only assignments and if/else translate in 'up' of a nested connector")
        return env

    def transfer(self, node: TreeNode, mask: int, ind: str, out: list[str]) -> dict[int, list[str]]:
        """Statements running ``up`` bottom-up and ``down`` top first; returns the values each leaf port receives."""
        received: dict[int, list[str]] = {}

        def up(n: TreeNode) -> tuple:
            pm, chosen = self._layout(n, mask)
            ct = n.info.type
            spec = self._clause(n, pm)
            sc = Scope(f"connector {n.connector.path}", constants=dict(self.flat.constants))
            for k, d in enumerate(ct.data):
                t = self.temp("bool" if d.type == "bool" else "int")
                out.append(f"{ind}{t} = {literal(n.info.local_defaults[k])};")
                sc.variables[d.name] = Name(t, d.type)
            kids = []
            for i, a in chosen:
                pname = ct.params[i].name
                ptype = self.flat.package.port_type(ct.params[i].port_type)
                fields_ = [f.name for f in ptype.params] if ptype else []
                if a.node is None:
                    fp = self.flat.ports[a.port]
                    temps = []
                    for slot, ty in zip(fp.slots, fp.field_types):
                        t = self.temp("bool" if ty == "bool" else "int")
                        out.append(f"{ind}{t} = {self.names[slot]};")
                        temps.append(t)
                    kids.append((i, a, None, temps))
                else:
                    child = up(a.node)
                    ex = [child[1].variables[v].text for v in a.node.info.type.export.data]
                    temps = []
                    for src in ex:
                        t = self.temp("int")
                        out.append(f"{ind}{t} = {src};")
                        temps.append(t)
                    kids.append((i, a, child, temps))
                for f, t in zip(fields_, temps):
                    sc.ports[(pname, f)] = Name(t, None)
            if spec is not None and spec.up:
                out.extend(self.stmts(spec.up, sc, ind))
            return n, sc, spec, kids

        def down(frame) -> None:
            n, sc, spec, kids = frame
            if spec is not None and spec.down:
                out.extend(self.stmts(spec.down, sc, ind))
            for _, a, child, temps in kids:
                if child is None:
                    received[a.port] = temps
                else:
                    ex = [child[1].variables[v].text for v in a.node.info.type.export.data]
                    for t, target in zip(temps, ex):
                        out.append(f"{ind}{target} = {t};")
                    down(child)

        down(up(node))
        return received

    def _has_transfer(self, node: TreeNode) -> bool:
        if any(s.up or s.down for s in node.info.clauses.values()):
            return True
        return any(a.node is not None and self._has_transfer(a.node) for alts in node.params for a in alts)

    # -- the whole model ------------------------------------------------------------------------------------------
    def write(self) -> str:
        self._declare_slots()
        st = self.statics
        body: list[str] = []
        en, mp = [], []
        for s in st:
            if s.source.kind == "port":
                en.append(f"pe{s.source.port.id}")
            else:
                ports = " && ".join(f"pe{s.source.leaves[i]}" for i in range(len(s.source.leaves)) if s.mask >> i & 1)
                g, _ = self.guard(s.source.tree, s.mask)
                en.append(ports + ("" if g == "true" else f" && {g}"))
        for k, s in enumerate(st):
            mp.append(f"en{k}" + "".join(f" && !en{j}" for j in s.supersets))
        go = self._priorities(st)
        for k, s in enumerate(st):
            body.append(f"   :: atomic {{ go{k} ->  /* {s.label} */")
            body.append(f'      printf("@@i {s.index}\\n");')
            touched: set[int] = set()
            first_temp = len(self.temps)
            if s.source.kind == "port":
                fp = s.source.port
                fa = self.flat.atoms[fp.atom]
                touched.add(fa.index)
                body.extend(self.fire_port(fa, fp.name, None, "      "))
            else:
                received = None
                if self._has_transfer(s.source.tree):
                    received = self.transfer(s.source.tree, s.mask, "      ", body)
                for i, pid in enumerate(s.source.leaves):
                    if s.mask >> i & 1:
                        fp = self.flat.ports[pid]
                        fa = self.flat.atoms[fp.atom]
                        touched.add(fa.index)
                        vals = received.get(pid) if received is not None else None
                        body.extend(self.fire_port(fa, fp.name, vals, "      "))
            body.extend(self.resets(touched, [t for t, _ in self.temps[first_temp:]], "      "))
            body.extend(self.monitor_steps(k, "      "))
            body.append("   }")
        out = self.header()
        out.extend(self.declarations())
        out.append("")
        out.append("/* enabledness of atom ports (atom priorities folded in) */")
        out.extend(self.port_macros())
        out.append("")
        out.append("/* interactions: ports and guards (en), maximal progress (mp), compound priorities (go) */")
        for k, s in enumerate(st):
            out.append(f"#define en{k} ({en[k]})  /* {s.label} */")
        for k in range(len(st)):
            out.append(f"#define mp{k} ({mp[k]})")
        for k in range(len(st)):
            out.append(f"#define go{k} ({go[k]})")
        out.append("")
        out.append("active proctype system() {")
        out.extend(self.initial_choice())
        out.extend(self.monitor_start())
        out.append("   do")
        out.extend(body or ["   :: atomic { false -> skip }  /* no interaction at all: a deadlock */"])
        out.append("   od")
        out.append("}")
        return "\n".join(out) + "\n"

    def _priorities(self, st: list[Static]) -> list[str]:
        rules = self.flat.priorities
        if not rules:
            return [f"mp{k}" for k in range(len(st))]
        edges = rule_edges(self.engine)
        guards = []
        for pr in rules:
            if pr.guard is None:
                guards.append("true")
                continue
            sc = Scope(f"priority {pr.name}", constants=dict(pr.constants))
            for (comp, name), (slot, ty) in pr.data.items():
                sc.ports[(comp, name)] = Name(self.names[slot], ty)
            guards.append(self.cond(pr.guard, sc))
        highs = []
        for r in range(len(rules)):
            js = [f"mp{j}" for j, s in enumerate(st) if s.high >> r & 1]
            highs.append(" || ".join(js) or "false")
        reach: list[str] = []
        for r in range(len(rules)):
            terms = []
            count = [0]

            def walk(x: int, gs: tuple[str, ...], seen: frozenset[int]) -> None:
                count[0] += 1
                if count[0] > MAX_PATHS:
                    raise PromelaError("too many chains of compound priorities to translate")
                cond = " && ".join(f"({g})" for g in gs if g != "true")
                terms.append(f"({cond} && ({highs[x]}))" if cond else f"({highs[x]})")
                for y in edges[x]:
                    if y not in seen:
                        walk(y, gs + (guards[y],), seen | {y})

            walk(r, (guards[r],), frozenset({r}))
            reach.append(" || ".join(terms))
        out = []
        for k, s in enumerate(st):
            blocking = [reach[r] for r in range(len(rules)) if s.low >> r & 1]
            out.append(f"mp{k}" + (f" && !({' || '.join(blocking)})" if blocking else ""))
        return out

    def header(self) -> list[str]:
        fl = self.flat
        return [
            f"/* Promela model of BIP package {fl.package.name}, root {fl.root}.",
            "   Generated by genom2bip (runtime.export.promela): one atomic step per interaction.",
            f"   {len(self.statics)} interactions, {len(fl.atoms)} atoms; dead variables "
            f"{'reset as by the explorer' if any(s.live is not None for s in self.slots) else 'kept'}.",
            "   printf markers @@i (interaction index) and @@o (codel outcome) let trails be read back. */",
            "",
        ]

    def declarations(self) -> list[str]:
        init = self.space.state(self.space.initial_ids[0]) if len(self.space.initial_ids) == 1 else None
        out = []
        for s in self.slots:
            name = self.names[s.index]
            ty = self.types[s.index]
            hidden = "hidden " if s.live == 0 and self.hidden else ""
            if hidden and ty in ("bool", "bit"):
                ty = "byte"  # SPIN cannot hide a bit
            value = "" if init is None else f" = {literal(init[s.index])}"
            comment = f"  /* {s.title} */"
            if ty.startswith("unsigned") and not hidden:
                out.append(f"{hidden}unsigned {name} : {ty.split(':')[1].strip()}{value};{comment}")
            else:
                out.append(f"{hidden}{ty} {name}{value};{comment}")
        for m in self.monitors:
            out.append(f"byte mon_{m.name} = {m.initial};  /* observer of property {m.name} */")
        for name, ty in self.temps:
            out.append(f"{'hidden ' if self.hidden else ''}{'byte' if ty == 'bool' else 'int'} {name};")
        return out

    def initial_choice(self) -> list[str]:
        if len(self.space.initial_ids) == 1:
            return []
        out = ["   /* several initial states (codels called by initial transitions) */", "   atomic {", "   if"]
        for sid in self.space.initial_ids:
            state = self.space.state(sid)
            assigns = "; ".join(f"{self.names[s.index]} = {literal(state[s.index])}" for s in self.slots)
            out.append(f"   :: {assigns}")
        out.append("   fi }")
        return out

    def _check(self, m: Monitor) -> str:
        if m.pred is None:
            return m.check
        from runtime.export.monitors import promela_pred
        return promela_pred(m.pred, self)

    def monitor_start(self) -> list[str]:
        """Observers whose property already applies to the initial state (R matches the empty path)."""
        out = []
        for m in self.monitors:
            if m.initial in m.accepting:
                out.append(f"   assert({self._check(m)});  /* property {m.name} in the initial state */")
        return out

    def monitor_steps(self, k: int, ind: str) -> list[str]:
        out = []
        for m in self.monitors:
            moves = m.delta[k]
            var = f"mon_{m.name}"
            if not moves:
                continue
            options = " ".join(f":: {var} == {a} -> {var} = {b}" for a, b in sorted(moves.items()) if a != b)
            if options:
                out.append(f"{ind}if {options} :: else -> skip fi;")
            bad = " || ".join(f"{var} == {q}" for q in sorted(m.accepting))
            if bad:
                out.append(f'{ind}assert(!({bad}) || ({self._check(m)}));')
        return out


def write_promela(space: StateSpace, monitors: list[Monitor] | None = None, hidden: bool = True) -> str:
    """The Promela text of the space's model (same layout, reduction and environment as the explorer).

    ``hidden=False`` declares temporaries as ordinary variables reset after
    each step (SPIN's multi-core mode does not accept hidden ones).
    """
    return PromelaWriter(space, monitors, hidden).write()
