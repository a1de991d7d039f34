"""Cycles across the search's branches (runtime/zones/lassos.py, _graph_lassos) on small graphs written by hand:
each one found is a cycle of the graph in which time passes, among nodes that watch, and none is made up."""
from __future__ import annotations

import numpy as np

from runtime.zones.lassos import Graph, _graph_lassos


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
