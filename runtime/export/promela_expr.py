"""Expressions and statements of the BIP model in Promela; codel calls become nondeterministic choices."""
from __future__ import annotations

from runtime.engine.flatten import FlatAtom
from runtime.export.promela_base import Name, PromelaBase, PromelaError, Scope, literal
from runtime.model.expressions import Assign, Binary, Call, Const, Do, Expr, If, PortData, Unary, Var


class ExprWriter(PromelaBase):
    """Expressions, guards and actions in one atom's or connector's scope."""

    def atom_scope(self, fa: FlatAtom) -> Scope:
        sc = Scope(f"atom {fa.name}", constants=dict(fa.constants))
        for d in fa.variables:
            slot = fa.slot(d.name)
            sc.variables[d.name] = Name(self.names[slot], d.type)
        return sc

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
