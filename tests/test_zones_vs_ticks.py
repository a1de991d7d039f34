"""Clock zones against ticks on random small networks of timed automata, with every reduction on and off.

The oracle (tests/randomtimed.py) explores each network's integer-time semantics state by state, written from the
TChecker format's meaning, without the zone engine or the translation to BIP.  The zone engine must reach the same
configurations (locations and integer) whatever its options: merging zones (``merge``), Extra_LU+ by place
(``local_ceilings``), invariants kept in the state (``invariants``), subtrees of covered nodes pruned (``prune``, on
unless said), the C or the Python search.  With the
partial-order reduction (``reduce``), which keeps out orders of commuting zero-time steps, every location must keep
its reachability verdict.
"""
from __future__ import annotations

import random
from pathlib import Path

import pytest

from randomtimed import Edge, Location, Network, configurations as ticked, network
from runtime.tchecker.reach import _Goal, configurations, load
from runtime.zones.csearch import library
from runtime.zones.search import ZoneExplorer

#: The options of the zone search, each one on and off; the C search where it builds.
ENGINES = ["python"] + (["c"] if library() else [])
OPTIONS = [dict(engine=e, merge=m, local_ceilings=lu, invariants=inv) for e in ENGINES
           for m in (False, True) for lu in (False, True) for inv in (False, True)] + \
    [dict(engine=e, prune=False) for e in ENGINES]
SEEDS = range(96)
#: Networks on which each location's verdict is compared with the partial-order reduction on and off.
POR_SEEDS = range(96, 128)


def _file(tmp_path: Path, net: Network) -> tuple[Path, int]:
    path = tmp_path / "random.tck"
    path.write_text(net.text())
    return path, 2 if net.strict else 1


def _configurations(path: Path, grid: int, options: dict) -> set:
    return {(locs, dict(ints)["n"]) for locs, ints in configurations(path, grid, **options)}


@pytest.mark.parametrize("chunk", range(4))
def test_zones_reach_what_ticks_reach_with_every_option(tmp_path, chunk):
    for seed in SEEDS[chunk::4]:
        net = network(random.Random(seed))
        path, grid = _file(tmp_path, net)
        want = ticked(net, grid)
        for options in OPTIONS:
            got = _configurations(path, grid, options)
            assert got == want, f"seed {seed}, {options}: zones only {got - want}, ticks only {want - got}\n" \
                                f"{net.text()}"


def test_each_option_changes_what_is_stored_on_some_network(tmp_path):
    # Else the comparison above would say nothing about it.
    changed = {"merge": 0, "local_ceilings": 0, "prune": 0}
    for seed in SEEDS:
        path, grid = _file(tmp_path, network(random.Random(seed)))
        counts = {name: ZoneExplorer(*_translated(path, grid), merge=name == "merge",
                                     local_ceilings=name == "local_ceilings", prune=name == "prune").explore().states
                  for name in ("none", "merge", "local_ceilings", "prune")}
        for name in changed:
            changed[name] += counts[name] != counts["none"]
    assert all(changed.values()), changed


def _translated(path: Path, grid: int):
    _, tr = load(path, grid)
    return tr.package, tr.root


@pytest.mark.parametrize("chunk", range(2))
def test_the_partial_order_reduction_keeps_every_locations_verdict(tmp_path, chunk):
    for seed in POR_SEEDS[chunk::2]:
        net = network(random.Random(seed))
        path, grid = _file(tmp_path, net)
        reached = ticked(net, grid)
        _, tr = load(path, grid)
        for p, locs in enumerate(net.locations):
            for k in range(len(locs)):
                want = any(c[0][p] == f"l{k}" for c in reached)
                for reduce in (False, True):
                    z = ZoneExplorer(tr.package, tr.root, reduce=reduce)
                    z.goal = _Goal(z, tr, [f"L{p}_{k}"]).need
                    result = z.explore(stop_at_violation=True)
                    assert bool(result.violations) is want, f"seed {seed}, L{p}_{k}, reduce={reduce}\n{net.text()}"


def test_the_partial_order_reduction_leaves_states_out_where_ticks_see_every_order(tmp_path):
    # Three processes each take one urgent step of their own: ticks reach the 8 combinations, the reduction
    # stores one order of the three steps and still finds each location.
    urgent = [[Location("urgent"), Location()] for _ in range(3)]
    net = Network(urgent, [Edge(p, 0, 1, "a", reset=0) for p in range(3)])
    path, grid = _file(tmp_path, net)
    assert len(ticked(net, grid)) == 8
    plain = ZoneExplorer(*_translated(path, grid)).explore()
    reduced = ZoneExplorer(*_translated(path, grid), reduce=True).explore()
    assert reduced.states < plain.states
    assert _configurations(path, grid, {}) == ticked(net, grid)
