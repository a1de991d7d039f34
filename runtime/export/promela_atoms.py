"""Atom ports in Promela: enabledness macros (atom priorities folded in) and firing one transition."""
from __future__ import annotations

from runtime.engine.flatten import FlatAtom
from runtime.export.promela_base import MAX_PATHS, PromelaError, Scope, literal
from runtime.export.promela_expr import ExprWriter


class AtomWriter(ExprWriter):
    """Port macros, firing an atom port, eager internal transitions and dead-variable resets."""

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
        if len(out) == 1:  # a port with no transition: never enabled, so never fired (Promela has no empty if)
            out = [f"{ind}skip;"]
        else:
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
        by_slot = {a.offset: a.index for a in self.flat.atoms}  # marking slot -> atom
        for s in self.slots:
            if s.live is None or s.atom is None or (s.never_live and self.hidden):
                continue
            flags = [m for _, flag, settable in s.void for m in [flag] + [p for alt in settable for p, _ in alt]]
            if any(by_slot[m] in atoms for m in [s.marking, *(m for m, _ in s.alive), *flags]):
                name = self.names[s.index]
                if s.never_live:
                    out.append(f"{ind}{name} = {literal(s.default)};")
                else:
                    test = s.live_test(lambda m: f"m{by_slot[m]}", value=lambda k: self.names[k])
                    out.append(f"{ind}{name} = (({test}) != 0 -> {name} : {literal(s.default)});")
        if not self.hidden:
            out.extend(f"{ind}{t} = 0;" for t in temps)
        return out
