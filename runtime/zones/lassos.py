"""Lassos of a finished zone search: cycles through states that all watch a request, in which time passes.

They show a response time without bound.  The search's nodes are read as arrays (:class:`Graph`, from the C
search's tables or from the Python search's nodes), so that a search of hundreds of thousands of nodes is walked
in numpy and plain integers; Node objects are made only for the steps of the lassos found.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Graph:
    """The search's tree and steps as arrays: per node its parent, whether it is covered and by whom, whether time
    may have passed in its step, whether its zone is kept; per edge (``frm``, ``target``, ``ref``): ref >= 0 is
    the node stored by the step, ref < 0 the step ``-ref - 1`` into a zone another node covers."""

    parent: np.ndarray
    covered: np.ndarray
    by: np.ndarray
    grown: np.ndarray
    zoned: np.ndarray
    frm: np.ndarray
    target: np.ndarray
    ref: np.ndarray
    step_grown: np.ndarray
    node: object  # k -> Node
    step: object  # s -> Node (a step into a covered zone)


@dataclass
class Edges:
    """What every watch reads of the edges: their ends' representatives, whether time passes in each step, and
    the edges sorted by (from, into) representatives (stably: in the order met within each pair)."""

    ru: np.ndarray
    rt: np.ndarray
    grown: np.ndarray
    key: np.ndarray
    order: np.ndarray


def edges_of(g: Graph, rep: np.ndarray) -> Edges:
    """The graph's :class:`Edges`, covered nodes standing for their representatives ``rep``."""
    ref = g.ref
    real = ref >= 0
    grown = np.where(real, g.grown[np.where(real, ref, 0)],
                     g.step_grown[np.where(real, 0, -ref - 1)] if len(g.step_grown) else False)
    ru, rt = rep[g.frm], rep[g.target]
    key = ru.astype(np.int64) * len(g.parent) + rt
    return Edges(ru, rt, grown.astype(bool), key, np.argsort(key, kind="stable").astype(_index(len(key))))


def _index(n: int):
    """The narrowest integer type that numbers ``n`` things: the arrays of a search's edges are its largest."""
    return np.int32 if n < 2 ** 31 else np.int64


def python_graph(z) -> Graph:
    """The Graph of a search kept in Python (ZoneExplorer.nodes and out)."""
    nodes = z.nodes
    steps, frm, target, ref = [], [], [], []
    for k, edges in enumerate(z.out):
        for t, step in edges:
            frm.append(k)
            target.append(t)
            if step is nodes[t]:
                ref.append(t)
            else:
                ref.append(-len(steps) - 1)
                steps.append(step)
    return Graph(np.array([n.parent for n in nodes], dtype=np.int64), np.array([n.covered for n in nodes], bool),
                 np.array([n.by for n in nodes], dtype=np.int64), np.array([n.grown for n in nodes], bool),
                 np.array([n.stored is not None for n in nodes], bool), np.array(frm, dtype=np.int64),
                 np.array(target, dtype=np.int64), np.array(ref, dtype=np.int64),
                 np.array([s.grown for s in steps], bool), nodes.__getitem__, steps.__getitem__)


def find(z, watch: np.ndarray, limit: int = 200):
    """Lassos through nodes where ``watch`` (one bool per node) holds: see runtime/zones/search.py's lassos."""
    g, rep, shape, edges = _prepared(z)
    yield from _tree_lassos(g, watch, limit, shape, edges)
    yield from _graph_lassos(g, watch, rep, edges)


def _prepared(z) -> tuple[Graph, np.ndarray, tuple, Edges]:
    """The search's graph, representatives, tree shape and edges: the same for every watch (one per response
    observer), kept on the explorer while its nodes stay those of the same search."""
    got = z.lasso_graph
    if got is not None and got[0] is z.nodes and got[1] == len(z.nodes):
        return got[2:]
    g = z.graph()
    n = len(g.parent)
    rep = np.where(g.covered & (g.by >= 0), g.by, np.arange(n, dtype=_index(n)))  # covered by one stored after it
    while True:  # to the end of each chain of covers, halving the rest of every chain each round
        nxt = rep[rep]
        if np.array_equal(nxt, rep):
            break
        rep = nxt
    shape = _shape(g.parent)
    z.lasso_graph = (z.nodes, len(z.nodes), g, rep, shape + (_path_sums(g.parent, shape[3], g.grown),),
                     edges_of(g, rep))
    return z.lasso_graph[2:]


def _path_sums(parent: np.ndarray, levels: list[np.ndarray], values: np.ndarray) -> np.ndarray:
    """Per node, the sum of ``values`` from its root down to it (itself included), a level at a time."""
    out = values.astype(np.int64)
    for level in levels[1:]:
        out[level] += out[parent[level]]
    return out


def _shape(parent: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[np.ndarray]]:
    """Depths in the search's tree, entry and exit numbers of a depth-first walk (an ancestor test: ``a`` is an
    ancestor of ``u`` or ``u`` itself iff enter[a] <= enter[u] and leave[u] <= leave[a]), and the nodes of each
    depth.  In numpy, a level at a time: a parent is stored before its children."""
    n = len(parent)
    parent = np.asarray(parent, dtype=np.int64)
    has = parent >= 0
    depth, up = has.astype(np.int64), np.where(has, parent, np.arange(n))
    while True:  # pointer jumping: depth[u] counts the steps up to its root
        far = up[up]
        if np.array_equal(far, up):
            break
        depth += np.where(up != far, depth[up], 0)
        up = far
    order = np.argsort(depth, kind="stable")
    cuts = np.flatnonzero(np.diff(depth[order])) + 1
    levels = np.split(order, cuts) if n else []
    size = np.ones(n, dtype=np.int64)
    for level in reversed(levels[1:]):  # subtree sizes, deepest first
        np.add.at(size, parent[level], size[level])
    enter = np.zeros(n, dtype=np.int64)
    for level in levels:  # children after their parent, each after the subtrees of its siblings stored before it
        level = level[np.argsort(parent[level], kind="stable")]  # siblings side by side
        p = parent[level]
        group = np.where(p >= 0, p, -1)
        before = np.cumsum(size[level]) - size[level]  # sizes of the level's nodes before each (level is sorted)
        first = np.r_[0, np.flatnonzero(np.diff(group)) + 1]
        start = np.repeat(before[first], np.diff(np.r_[first, len(level)]))
        enter[level] = np.where(p >= 0, enter[np.maximum(p, 0)] + 1, 0) + before - start
    return depth, enter, enter + size, levels


def _tree(g: Graph, watch: np.ndarray, shape: tuple):
    """Depths in the search's tree, the depth each watching run starts at, entry and exit numbers of a depth-first
    walk (the ancestor test), from the shape computed once rather than walking up from every state."""
    depth, enter, leave, levels = shape[:4]
    parent = g.parent
    top = depth.copy()
    for level in levels[1:]:  # top[u] = top[parent] while both watch, a level at a time
        p = parent[level]
        on = watch[level] & watch[p]
        top[level[on]] = top[p[on]]
    return depth, top, enter, leave


def _tree_lassos(g: Graph, watch: np.ndarray, limit: int, shape: tuple, edges: Edges):
    if not len(g.frm):
        return
    depth, top, enter, leave = _tree(g, watch, shape)
    # the edges between watching nodes, the others left at once (each test in place: these are most of the edges)
    e = np.flatnonzero(watch[g.frm] & watch[edges.rt]).astype(_index(len(g.frm)))
    u, t, ref, a = g.frm[e], g.target[e], g.ref[e], edges.rt[e]
    real = ref >= 0
    ok = ~(real & g.zoned[np.where(real, ref, 0)] & (a == t))  # not into a zone of its own: the tree goes on there
    ok &= depth[a] >= top[u]
    ok &= enter[a] <= enter[u]
    ok &= leave[u] <= leave[a]
    # time passes in the step or down the tree from the entry (the chain below): else a cycle in zero time, where
    # no request waits for ever
    passes = shape[4]
    ok &= edges.grown[e] | (passes[u] > passes[a])
    parent = g.parent
    found, done = [], -1
    for i in np.flatnonzero(ok).tolist():
        k0, entry, r = int(u[i]), int(a[i]), int(ref[i])
        if k0 == done:
            continue
        if len(found) >= limit:
            break
        chain, k = [], k0
        while k != entry:
            chain.append(k)
            k = int(parent[k])
        step = g.node(r) if r >= 0 else g.step(-r - 1)
        found.append((len(chain) + 1, entry, [g.node(c) for c in reversed(chain)] + [step]))
        done = k0
    for _, entry, loop in sorted(found, key=lambda f: f[0]):
        yield entry, loop


def _numbered(n: int, *ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The nodes (of ``n``) among ``ends``, in order, and per node its number among them: ``np.unique`` with its
    inverse, by marking rather than sorting (the ends are tens of millions of edges' on a large search)."""
    mark = np.zeros(n, dtype=bool)
    for e in ends:
        mark[e] = True
    names = np.flatnonzero(mark)
    local = np.zeros(n, dtype=_index(n))
    local[names] = np.arange(len(names))
    return names, local


def _graph_lassos(g: Graph, watch: np.ndarray, rep: np.ndarray, edges: Edges | None = None):
    """Cycles of the graph where a covered node stands for the node covering it, among nodes that watch: its
    strongly connected components (scipy's, on the edges as arrays), then in each, for up to 20 edges in which
    time passes, the shortest way back (breadth first, inside the component)."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import breadth_first_order, connected_components

    if not len(g.frm):
        return
    if edges is None:
        edges = edges_of(g, rep)
    ru, rt, stepg, key, ref = edges.ru, edges.rt, edges.grown, edges.key, g.ref
    on = watch[g.frm] & watch[rt]
    if not on.any():
        return
    n = len(g.parent)
    kept = edges.order[on[edges.order]]  # the watching edges by (from, into), in the order met within a pair
    firsts = kept[np.r_[True, key[kept][1:] != key[kept][:-1]]]  # each pair's first edge, by (from, into)
    names, local = _numbered(n, ru[firsts], rt[firsts])
    m = len(names)
    # the pairs come by (from, into): the adjacency's rows as they are, without sorting (nor scipy's conversion)
    rows, cols = local[ru[firsts]], local[rt[firsts]]
    indptr = np.zeros(m + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=m), out=indptr[1:])
    adj = csr_matrix((np.ones(len(cols), dtype=np.int8), cols, indptr), shape=(m, m))
    del rows, cols
    first = np.sort(firsts)  # each pair's first edge, in the order they were first met
    src, dst = ru[first], rt[first]
    a, b = local[src], local[dst]
    _, comp = connected_components(adj, directed=True, connection="strong")
    inside = np.flatnonzero(comp[a] == comp[b])  # an edge inside a component is on a cycle (a self-loop alone)
    if not len(inside):
        return
    # the step standing for each edge inside: the last one met in which time passes, else the first
    label = first[inside]
    ikey = key[first[inside]]
    order = np.argsort(ikey)
    sorted_keys = ikey[order]
    timed = np.flatnonzero(on & stepg)
    tkey = key[timed]
    at = np.searchsorted(sorted_keys, tkey)
    hit = (at < len(sorted_keys)) & (sorted_keys[np.minimum(at, len(sorted_keys) - 1)] == tkey)
    where, steps = order[at[hit]], timed[hit]  # in the order met
    last = len(where) - 1 - np.unique(where[::-1], return_index=True)[1]  # each edge's last one
    label[where[last]] = steps[last]

    def step(e: int):
        r = int(ref[e])
        return g.node(r) if r >= 0 else g.step(-r - 1)

    def edge_label(x: int, y: int) -> int:
        i = int(np.searchsorted(sorted_keys, x * n + y))
        return int(label[order[i]])

    timed_inside = np.flatnonzero(stepg[label])  # the edges inside a component in which time passes, in order met
    for picks in _first_per_component(timed_inside, comp[a[inside[timed_inside]]]):
        members = np.flatnonzero(comp == comp[a[inside[picks[0]]]])  # sorted: a node's place is a binary search
        sub = adj[members][:, members].tocsr().astype(np.float64)  # the form scipy's searches take, made once
        sub.sum_duplicates()
        for i in picks:
            u, v = int(a[inside[i]]), int(b[inside[i]])
            x, y = int(names[u]), int(names[v])
            if u == v:
                back = [x]
            else:
                at_v, at_u = np.searchsorted(members, [v, u]).tolist()
                _, pred = breadth_first_order(sub, at_v, directed=True, return_predecessors=True)
                path, k = [], at_u
                while k >= 0:
                    path.append(int(names[members[k]]))
                    k = int(pred[k]) if k != at_v else -1
                back = path[::-1]
            yield x, [step(edge_label(x, y))] + [step(edge_label(p, q)) for p, q in zip(back, back[1:])]


def _first_per_component(edges: np.ndarray, comps: np.ndarray, most: int = 20) -> list[list[int]]:
    """Of ``edges`` (in the order met) and their components, up to ``most`` per component in that order, the
    components in the order their first edge was met: a sort, not a Python loop over millions of edges."""
    if not len(edges):
        return []
    order = np.argsort(comps, kind="stable")
    grouped = comps[order]
    starts = np.r_[0, np.flatnonzero(np.diff(grouped)) + 1]
    rank = np.arange(len(order)) - np.repeat(starts, np.diff(np.r_[starts, len(order)]))
    kept = order[rank < most]  # positions in edges, grouped by component, in order met within each
    groups = np.split(kept, np.flatnonzero(np.diff(comps[kept])) + 1)
    groups.sort(key=lambda g: int(g[0]))
    return [edges[g].tolist() for g in groups]
