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


from runtime.explore.space import StateSpace
from runtime.export.interactions import Static, rule_edges
from runtime.export.promela_atoms import AtomWriter
from runtime.export.promela_base import MAX_PATHS, Monitor, Name, PromelaError, Scope, literal
from runtime.export.promela_connectors import ConnectorWriter


class PromelaWriter(AtomWriter, ConnectorWriter):
    """Builds the Promela text for a state space's model (its layout, reduction, environment, initial states).

    Expressions (:mod:`.promela_expr`), atom ports (:mod:`.promela_atoms`) and
    connectors (:mod:`.promela_connectors`) are written by classes of their own;
    this class lays out the whole model, its priorities and its monitors.
    """

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
            hidden = "hidden " if s.never_live and self.hidden else ""
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
    refuse_untranslatable(space)
    return PromelaWriter(space, monitors, hidden).write()


def refuse_untranslatable(space: StateSpace) -> None:
    """A PromelaError for a model the translation does not take, said before SPIN is looked for or run."""
    if space.engine.invariants:
        raise PromelaError("the Promela translation does not check atom invariants: verify with --engine compiled "
                           "or python")
