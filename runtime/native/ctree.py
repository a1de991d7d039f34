"""C text for connectors with sub-connectors (the engine's ``generic`` sources), as runtime.engine.support runs them.

Enabledness mirrors :func:`~runtime.engine.support.generic_enabled`: each
node of the connector tree offers, bottom-up, every interaction of its
sub-tree whose guard holds, with the values its ``up`` computes for its
exported port; maximal progress then keeps the maximal leaf masks, in
increasing order.  Firing mirrors :func:`~runtime.engine.support.fire_tree`:
``up`` bottom-up (the first alternative of a parameter that takes part is
the one used), ``down`` top first, exported values copied down into the
sub-connectors, then the atom ports in the order ``down`` reaches them.
Offers live in arrays whose sizes are fixed in the text: a tree that could
offer more than :data:`MAX_OFFERS` interactions in one state is refused.
"""
from __future__ import annotations

from contextlib import ExitStack
from math import prod

from runtime.engine import defines
from runtime.engine.plan import TreeNode
from runtime.native.cexpr import Unsupported, literal

#: Interactions a connector tree may offer in one state (the arrays the C step allocates on its stack).
MAX_OFFERS = 4096


def nodes(root: TreeNode) -> list[TreeNode]:
    """The nodes of a tree, the root first (pre-order); a node's number is its position."""
    out = [root]
    for alts in root.params:
        for a in alts:
            if a.node is not None:
                out.extend(nodes(a.node))
    return out


def bound(node: TreeNode) -> int:
    """Most interactions ``node`` can offer in one state: every allowed parameter set, every combination."""
    rows = [sum(1 if a.node is None else bound(a.node) for a in alts) for alts in node.params]
    total = 0
    for pm in defines.subsets(node.info.tree, node.info.all_params):
        total += prod(rows[i] for i in range(len(rows)) if pm >> i & 1)
    return total


def width(root: TreeNode) -> int:
    """Values an offer carries: the widest export of the tree's nodes."""
    return max([len(n.info.export_idx) for n in nodes(root)] + [1])


def node_pm(node: TreeNode) -> str:
    """C expression of the parameter mask with which ``node`` takes part in interaction ``mask`` (plan.parts)."""
    terms = []
    for i, alts in enumerate(node.params):
        m = 0
        for a in alts:
            m |= a.mask
        terms.append(f"((mask & {m}u) ? {1 << i}u : 0u)")
    return "(" + " | ".join(terms) + ")" if terms else "0u"


def node_pm_of(node: TreeNode, mask: int) -> int:
    """The parameter mask :func:`node_pm` computes for interaction ``mask``, computed now."""
    out = 0
    for i, alts in enumerate(node.params):
        if any(mask & a.mask for a in alts):
            out |= 1 << i
    return out


class TreeGen:
    """The offers functions and the firing function of one generic source."""

    def __init__(self, gen, src) -> None:
        self.gen = gen
        self.src = src
        self.flat = gen.flat
        self.nodes = nodes(src.tree)
        self.number = {id(n): k for k, n in enumerate(self.nodes)}
        total = bound(src.tree)
        if total > MAX_OFFERS:
            raise Unsupported(f"connector {src.connector.path}: its sub-connectors can offer {total:,} interactions "
                              f"in one state, more than the compiled step's {MAX_OFFERS:,}")

    def kid(self, node: TreeNode) -> int:
        return self.number[id(node)]

    def type_index(self, node: TreeNode) -> int:
        return self.gen.type_index[node.connector.type.name]

    # -- enabled --------------------------------------------------------------------------------
    def gen_offers(self) -> None:
        """``go<S>_<N>(s, ep, out)``: the interactions node N offers at state s, ports enabled as ``ep`` says."""
        for node in reversed(self.nodes):  # children before parents: C wants them declared first
            self.gen_node_offers(node)

    def gen_node_offers(self, node: TreeNode) -> None:
        """``go<S>_<N>``: the interactions of node N's sub-tree, for each parameter set its define allows."""
        w = self.gen.w
        s, n = self.src.index, self.kid(node)
        info = node.info
        k = self.type_index(node)
        np_ = len(node.params)
        with w.block(f"static int go{s}_{n}(const V *s, const uint8_t *ep, Offer *out)", node.connector.path):
            w("int n = 0;")
            w("uint32_t avail = 0;")
            for i, alts in enumerate(node.params):
                rb = sum(1 if a.node is None else bound(a.node) for a in alts)
                w(f"Offer r{i}[{rb}]; int c{i} = 0;")
                for a in alts:
                    if a.node is None:
                        fp = self.flat.ports[a.port]
                        vals = " ".join(f"r{i}[c{i}].v[{j}] = s[{slot}];" for j, slot in enumerate(fp.slots))
                        w(f"if (ep[{a.port}]) {{ r{i}[c{i}].m = {a.mask}u; {vals} c{i}++; }}")
                    else:
                        w(f"c{i} += go{s}_{self.kid(a.node)}(s, ep, r{i} + c{i});")
                w.if_then(f"c{i}", f"avail |= {1 << i}u")
            w.if_then("!avail", "return 0")
            for pm in defines.subsets(info.tree, info.all_params):
                with w.block(f"if ((avail & {pm}u) == {pm}u)"):
                    self.gen_combinations(info, k, pm, [i for i in range(np_) if pm >> i & 1], np_)
            w("return n;")

    def gen_combinations(self, info, k: int, pm: int, idx: list[int], np_: int) -> None:
        """One offer per combination of the parameters ``idx``' offers whose guard holds, with its exports."""
        w = self.gen.w
        with ExitStack() as loops:
            for i in idx:
                loops.enter_context(w.block(f"for (int x{i} = 0; x{i} < c{i}; x{i}++)"))
            spec = info.clauses.get(pm)
            w(f"V pv[{np_}][MAXF];")
            for i in idx:
                w(f"memcpy(pv[{i}], r{i}[x{i}].v, sizeof pv[{i}]);")
            w(f"uint32_t mask = {' | '.join(f'r{i}[x{i}].m' for i in idx)};")
            if spec is not None and spec.guard is not None:
                w.if_then(f"!k{k}_{pm}_g(pv)", "continue")
            w(self.gen.locals_init(info))
            if spec is not None and spec.up:
                w(f"k{k}_{pm}_u(pv, lv);")
            w("out[n].m = mask;")
            for j, e in enumerate(info.export_idx):
                w(f"out[n].v[{j}] = lv[{e}];")
            w("n++; (void)lv;")

    def gen_enabled(self) -> None:
        """The part of ``enabled`` that lists this source's maximal interactions (``EP``: ports enabled)."""
        w = self.gen.w
        s = self.src.index
        with w.block(""):
            w(f"Offer G[{bound(self.src.tree)}];")
            w(f"uint32_t M[{bound(self.src.tree)}];")
            w(f"int ng = go{s}_0(s, EP, G);")
            w("int nm = maximal_offers(G, ng, M);")
            with w.block("for (int i = 0; i < nm; i++)"):
                w.if_then("n >= MAXI", "fail(E_FULL, 0)")
                w(f"isrc[n] = {s}; imask[n] = M[i]; n++;")

    # -- firing ---------------------------------------------------------------------------------
    def gen_fire(self) -> None:
        """``f<S>(L, mask)``: up bottom-up, down top first, then the atom ports of the interaction ``mask``."""
        w = self.gen.w
        with w.block(f"static void f{self.src.index}(V *L, uint32_t mask)", self.src.connector.path):
            for node in self.nodes:
                n = self.kid(node)
                vals = [literal(v, f"connector type {node.info.type.name}")[0] for v in node.info.local_defaults]
                w(f"V pv{n}[{len(node.params)}][MAXF]; V lv{n}[{max(len(vals), 1)}] = {{{', '.join(vals) or '0'}}}; "
                  f"uint32_t pm{n} = 0; (void)pv{n}; (void)lv{n}; (void)pm{n};")
            self.up(self.src.tree, "1")
            self.down(self.src.tree, "1")
            self.fire(self.src.tree, "1")

    @staticmethod
    def alternatives(node: TreeNode, cond: str):
        """``(param, alternative, condition that it is the one used)`` for every alternative of every parameter."""
        for i, alts in enumerate(node.params):
            before = 0
            for a in alts:
                used = f"(mask & {a.mask}u)" + (f" && !(mask & {before}u)" if before else "")
                yield i, a, used if cond == "1" else f"{cond} && {used}"
                before |= a.mask

    def clause_calls(self, node: TreeNode, part: str) -> None:
        n, k = self.kid(node), self.type_index(node)
        cases = [m for m, spec in node.info.clauses.items() if (spec.up if part == "u" else spec.down)]
        if cases:
            body = " ".join(f"case {m}: k{k}_{m}_{part}(pv{n}, lv{n}); break;" for m in cases)
            self.gen.w(f"switch (pm{n}) {{ {body} default: break; }}")

    def up(self, node: TreeNode, cond: str) -> None:
        """``up`` of ``node`` when it takes part (``cond``), after its sub-connectors': port values in, exports out."""
        w = self.gen.w
        for _, a, used in self.alternatives(node, cond):
            if a.node is not None:
                self.up(a.node, used)
        n = self.kid(node)
        with w.block(f"if ({cond})"):
            for i, alts in enumerate(node.params):
                for j, a in enumerate(alts):
                    if a.node is None:
                        copy = " ".join(
                            f"pv{n}[{i}][{f}] = L[{slot}];" for f, slot in enumerate(self.flat.ports[a.port].slots)
                        )
                    else:
                        c = self.kid(a.node)
                        copy = " ".join(f"pv{n}[{i}][{f}] = lv{c}[{e}];" for f, e in enumerate(a.node.info.export_idx))
                    w(f"{'if' if j == 0 else 'else if'} (mask & {a.mask}u) {{ pm{n} |= {1 << i}u; {copy} }}")
            self.clause_calls(node, "u")

    def down(self, node: TreeNode, cond: str) -> None:
        """``down`` of ``node`` when it takes part, then its exported values copied into its sub-connectors."""
        w = self.gen.w
        n = self.kid(node)
        with w.block(f"if ({cond})"):
            self.clause_calls(node, "d")
        for i, a, used in self.alternatives(node, cond):
            if a.node is not None:
                c = self.kid(a.node)
                copy = " ".join(f"lv{c}[{e}] = pv{n}[{i}][{f}];" for f, e in enumerate(a.node.info.export_idx))
                if copy:
                    w(f"if ({used}) {{ {copy} }}")
                self.down(a.node, used)

    def fire(self, node: TreeNode, cond: str) -> None:
        n = self.kid(node)
        for i, a, used in self.alternatives(node, cond):
            if a.node is None:
                self.gen.w.if_then(used, f"ap{a.port}(L, pv{n}[{i}])")
            else:
                self.fire(a.node, used)
