"""Cycles across the search's branches (runtime/zones/lassos.py, _graph_lassos) on small graphs written by hand:
each one found is a cycle of the graph in which time passes, among nodes that watch, and none is made up.  The
tree's shape (depths and the ancestor test, computed a level at a time) against walking up parent by parent."""
from __future__ import annotations

import random

import numpy as np

from runtime.zones.lassos import (Graph, _first_per_component, _graph_lassos, _path_sums, _shape, _tree, _tree_lassos,
                                  edges_of)


def _graph(parent: list[int], covered_by: dict[int, int], edges: list[tuple[int, int, bool]],
           grown: set[int] = frozenset()) -> tuple[Graph, np.ndarray]:
    """Nodes with their tree parents; ``covered_by``: node -> the node covering it; ``edges``: (from, into node,
    time passes), each a step into the zone of ``into`` (a step of its own when ``into`` is a covered node)."""
    n = len(parent)
    by = [covered_by.get(k, -1) for k in range(n)]
    frm, target, ref, step_grown = [], [], [], []
    for u, t, passes in edges:
        frm.append(u)
        target.append(t)
        ref.append(-len(step_grown) - 1)
        step_grown.append(passes)
    g = Graph(np.array(parent), np.array([k in covered_by for k in range(n)]), np.array(by),
              np.array([k in grown for k in range(n)]), np.ones(n, bool), np.array(frm), np.array(target),
              np.array(ref), np.array(step_grown), lambda k: ("node", k), lambda s: ("step", s))
    rep = np.array([covered_by.get(k, k) for k in range(n)])
    return g, rep


def test_a_cycle_through_two_branches_is_found_with_its_steps_in_order():
    # 0 -> 1 -> 3 and 0 -> 2 -> 4 in the tree; 3 steps into 2's zone, 4 into 1's: 1 -> 3 -> 2 -> 4 -> 1.
    g, rep = _graph([-1, 0, 0, 1, 2], {}, [(0, 1, True), (0, 2, True), (1, 3, True), (2, 4, False),
                                            (3, 2, True), (4, 1, False)])
    found = list(_graph_lassos(g, np.ones(5, bool), rep))
    assert found
    steps_of = {("step", s): (int(g.frm[s]), int(g.target[s])) for s in range(len(g.frm))}
    for entry, loop in found:
        hops = [steps_of[s] for s in loop]
        assert hops[0][0] == entry and hops[-1][1] == entry  # it closes where it starts
        assert all(a[1] == b[0] for a, b in zip(hops, hops[1:]))  # each step starts where the last one ended
        assert set(hops) <= {(1, 3), (3, 2), (2, 4), (4, 1)}
        assert g.step_grown[[s for _, s in loop]].any()  # time passes in it
    assert {h for _, loop in found for h in (steps_of[s] for s in loop)} == {(1, 3), (3, 2), (2, 4), (4, 1)}


def test_a_covered_node_stands_for_the_node_covering_it():
    # 3 is covered by 1: the step 1 -> 3 goes back into 1's zone, a cycle of one node.
    g, rep = _graph([-1, 0, 1, 1], {3: 1}, [(0, 1, True), (1, 2, False), (1, 3, True)])
    found = list(_graph_lassos(g, np.ones(4, bool), rep))
    assert found == [(1, [("step", 2)])]


def test_no_cycle_without_time_passing_or_outside_the_watched_nodes():
    edges = [(0, 1, True), (1, 2, False), (2, 1, False)]
    g, rep = _graph([-1, 0, 1], {}, edges)
    assert list(_graph_lassos(g, np.ones(3, bool), rep)) == []  # a cycle in zero time: no request waits for ever
    g, rep = _graph([-1, 0, 1], {}, [(0, 1, True), (1, 2, True), (2, 1, False)])
    assert list(_graph_lassos(g, np.array([True, True, False]), rep)) == []  # 2 does not watch
    assert len(list(_graph_lassos(g, np.ones(3, bool), rep))) == 1
    g, rep = _graph([-1, 0, 0], {}, [(0, 1, True), (0, 2, True), (1, 2, True)])
    assert list(_graph_lassos(g, np.ones(3, bool), rep)) == []  # no way back


def test_of_several_steps_between_the_same_two_nodes_the_last_one_where_time_passes_stands_for_them():
    # Three steps from 1 into zones 1 covers: the first and the third let time pass, the second does not.
    g, rep = _graph([-1, 0, 1, 1, 1], {2: 1, 3: 1, 4: 1}, [(0, 1, True), (1, 2, True), (1, 3, False), (1, 4, True)])
    assert list(_graph_lassos(g, np.ones(5, bool), rep)) == [(1, [("step", 3)])]


def _ancestors(parent: list[int], u: int) -> list[int]:
    """u, its parent, and so on up to its root."""
    up = [u]
    while parent[up[-1]] >= 0:
        up.append(parent[up[-1]])
    return up


def test_the_tree_shape_is_the_one_walking_up_gives():
    rng = random.Random(7)
    for _ in range(200):  # forests of up to 60 nodes, a parent stored before its children, siblings anywhere
        n = rng.randint(1, 60)
        parent = [-1 if u == 0 or rng.random() < 0.05 else rng.randrange(u) for u in range(n)]
        depth, enter, leave, levels = _shape(np.array(parent))
        up = [_ancestors(parent, u) for u in range(n)]
        assert depth.tolist() == [len(a) - 1 for a in up]
        for u in range(n):
            below = [a for a in range(n) if enter[a] <= enter[u] and leave[u] <= leave[a]]
            assert sorted(below) == sorted(up[u]), (parent, u)
        assert sorted(np.concatenate(levels).tolist()) == list(range(n))
        # each watching run starts at the depth of its first watching node
        watch = np.array([rng.random() < 0.7 for _ in range(n)])
        none = np.zeros(0, np.int64)
        g = Graph(np.array(parent), np.zeros(n, bool), np.full(n, -1), np.zeros(n, bool), np.ones(n, bool), none, none,
                  none, np.zeros(0, bool), None, None)
        _, top, _, _ = _tree(g, watch, (depth, enter, leave, levels))
        for u in range(n):
            a = up[u]
            k = 0
            while k + 1 < len(a) and watch[a[k]] and watch[a[k + 1]]:
                k += 1
            assert top[u] == len(a) - 1 - k


def test_a_cycle_down_the_tree_needs_time_to_pass_after_its_entry():
    # 0 -> 1 -> 2 -> 3 -> 4 in the tree, 4's zone covered by 1's: the run 1 -> 2 -> 3 -> 4 goes back into 1.
    parent = np.array([-1, 0, 1, 2, 3])
    rep = np.array([0, 1, 2, 3, 1])

    def lassos(grown: set[int]):
        g = Graph(parent, np.array([False] * 4 + [True]), np.array([-1] * 4 + [1]),
                  np.array([k in grown for k in range(5)]), np.ones(5, bool), np.array([0, 1, 2, 3]),
                  np.array([1, 2, 3, 4]), np.array([1, 2, 3, 4]), np.zeros(0, bool), lambda k: k, None)
        shape = _shape(parent)
        shape += (_path_sums(parent, shape[3], g.grown),)
        return list(_tree_lassos(g, np.ones(5, bool), 200, shape, edges_of(g, rep)))

    assert lassos(set()) == []  # all in zero time
    assert lassos({0, 1}) == []  # time passes before the entry only
    for k in (2, 3, 4):  # in a step of the loop, the last one included
        assert lassos({k}) == [(1, [2, 3, 4])]


def test_the_edges_tried_are_the_first_twenty_of_each_component_components_in_the_order_first_met():
    edges = np.arange(100, 160)
    comps = np.array([7, 3] * 25 + [9] * 10)  # 7 and 3 interleaved, 25 edges each, then 9
    got = _first_per_component(edges, comps)
    assert got == [list(range(100, 140, 2)), list(range(101, 141, 2)), list(range(150, 160))]
    assert _first_per_component(np.array([4, 5, 6]), np.array([2, 1, 2]), most=1) == [[4], [5]]
    assert _first_per_component(np.array([], dtype=np.int64), np.array([], dtype=np.int64)) == []
