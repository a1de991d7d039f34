"""Connectors in Promela: an interaction's guard along its connector tree, and its up/down data transfer."""
from __future__ import annotations

from typing import Any

from runtime.engine.plan import TreeNode
from runtime.export.promela_base import Name, PromelaError, Scope, literal
from runtime.export.promela_expr import ExprWriter
from runtime.model.expressions import Assign, If, Var


class ConnectorWriter(ExprWriter):
    """Guards and data transfer of interactions, through nested connectors."""

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
