"""Zones of clock values (runtime/zones/dbm.py): what each operation means on integer points, and the C
operations giving exactly the numpy reference's matrices on random sequences."""
from __future__ import annotations

import itertools
import random

import numpy as np
import pytest

from nativekit import needs_cc
from runtime.zones import dbm


def points(m: np.ndarray, top: int = 6) -> set[tuple[int, ...]]:
    """The integer valuations of a zone with every clock in 0..top."""
    n = m.shape[0] - 1
    out = set()
    for v in itertools.product(range(top + 1), repeat=n):
        x = (0,) + v
        if all(x[i] - x[j] <= m[i, j] for i in range(n + 1) for j in range(n + 1)):
            out.add(v)
    return out


@pytest.fixture(params=["numpy", "c"])
def ops(request):
    if request.param == "c" and dbm._c() is None:
        pytest.skip("no C compiler (gcc) on PATH")
    dbm.use_c(request.param == "c")
    yield request.param
    dbm.use_c(True)


def test_time_passing_then_a_guard_keeps_exactly_the_points_that_meet_it(ops):
    z = dbm.up(dbm.zero(2))  # x1 = x2, any value
    z = dbm.constrain(z, 1, 0, 3)  # x1 <= 3
    assert points(z) == {(v, v) for v in range(4)}
    z = dbm.reset(z, 2, 0)  # x2 := 0
    assert points(z) == {(v, 0) for v in range(4)}
    z = dbm.up(z)
    assert points(z) == {(a, b) for a in range(7) for b in range(7) if 0 <= a - b <= 3}
    assert dbm.constrain(z, 0, 1, -10) is not None  # x1 >= 10: still there with time
    assert dbm.constrain(dbm.constrain(z, 1, 0, 2), 0, 2, -3) is None  # x1 <= 2 and x2 >= 3: empty


def test_freeing_clocks_forgets_them_and_keeps_the_others(ops):
    z = dbm.reset(dbm.reset(dbm.up(dbm.zero(3)), 2, 1), 3, 2)
    z = dbm.constrain(z, 1, 0, 4)
    freed = dbm.free_many(z, [2, 3])
    assert points(freed) == {(a, b, c) for a in range(5) for b in range(7) for c in range(7)}
    one = dbm.free(z, 2)
    assert dbm.free_many(z, [2]).tolist() == one.tolist()


def test_inclusion_and_subtraction_split_a_zone_into_disjoint_pieces(ops):
    big = dbm.constrain(dbm.up(dbm.zero(2)), 1, 0, 5)
    small = dbm.constrain(big, 0, 1, -2)
    assert dbm.includes(big, small) and not dbm.includes(small, big)
    pieces = dbm.subtract(big, small)
    got = [points(p) for p in pieces]
    assert set().union(*got) == points(big) - points(small)
    assert sum(len(g) for g in got) == len(points(big) - points(small))


def test_extrapolation_forgets_only_what_is_above_a_clock_s_ceiling(ops):
    z = dbm.constrain(dbm.up(dbm.zero(1)), 0, 1, -9)  # x >= 9
    ceiling = np.array([0.0, 4.0])
    wide = dbm.extrapolate(z, ceiling)
    assert dbm.lower(wide, 1) == 5 and dbm.upper(wide, 1) == np.inf  # above 4, every value alike
    low = dbm.constrain(dbm.up(dbm.zero(1)), 1, 0, 3)
    assert dbm.extrapolate(low, ceiling).tolist() == low.tolist()


def _boxed(rng: random.Random, n: int, top: int) -> np.ndarray:
    """A random zone with every clock in 0..top (so that :func:`points` sees all of it)."""
    z = dbm.constrain_all(dbm.free_all(n), [(i, 0, top) for i in range(1, n + 1)])
    for _ in range(rng.randint(1, 5)):
        i, j = rng.sample(range(n + 1), 2)
        got = dbm.constrain(z, i, j, rng.randint(-top, top))
        z = z if got is None else got
    return z


def test_the_past_and_the_intersection_keep_exactly_their_points(ops):
    rng = random.Random(11)
    for _ in range(100):
        a, b = _boxed(rng, 2, 4), _boxed(rng, 2, 4)
        both = dbm.intersect(a, b)
        assert (points(both, 4) if both is not None else set()) == points(a, 4) & points(b, 4)
        past = {tuple(v - d for v in p) for p in points(a, 4) for d in range(5) if min(p) - d >= 0}
        assert points(dbm.down(a), 4) == past


def test_two_zones_make_one_exactly_when_their_points_do(ops):
    box = dbm.constrain_all(dbm.free_all(2), [(1, 0, 4), (2, 0, 4)])
    before, after = dbm.constrain(box, 1, 2, 0), dbm.constrain(box, 2, 1, 0)  # x1 <= x2, x2 <= x1
    assert dbm.union(before, after).tolist() == box.tolist()  # the two orders of two resets: the whole box
    apart = dbm.constrain_all(box, [(1, 0, 1)]), dbm.constrain_all(box, [(0, 1, -3)])  # x1 <= 1, x1 >= 3
    assert dbm.union(*apart) is None  # x1 = 2 is in neither
    touching = dbm.constrain_all(box, [(1, 0, 1)]), dbm.constrain_all(box, [(0, 1, -2)])  # integers: no gap
    assert points(dbm.union(*touching), 4) == points(box, 4)
    rng = random.Random(7)
    merged = 0
    for _ in range(300):
        a, b = _boxed(rng, 3, 4), _boxed(rng, 3, 4)
        got = dbm.union(a, b)
        whole = points(a, 4) | points(b, 4)
        assert (got is not None) == (points(np.maximum(a, b), 4) == whole)
        if got is not None:
            merged += 1
            assert points(got, 4) == whole
            assert a.tolist() == dbm.union(a, a).tolist()
    assert 20 < merged < 280  # both answers were exercised


def _random_run(seed: int) -> list:
    rng = random.Random(seed)
    n = 5
    z = dbm.zero(n)
    ceiling = np.array([0.0] + [rng.choice([-1, 3, 7, 12]) for _ in range(n)])
    out: list = []
    for _ in range(40):
        op = rng.random()
        if op < 0.2:
            z = dbm.up(z)
        elif op < 0.35:
            z = dbm.reset(z, rng.randint(1, n), rng.randint(0, 5))
        elif op < 0.45:
            z = dbm.extrapolate(z, ceiling)
        elif op < 0.5:
            z = dbm.free_many(z, rng.sample(range(1, n + 1), rng.randint(1, 3)))
        elif op < 0.55:
            other = dbm.constrain(dbm.up(z), rng.randint(1, n), 0, rng.randint(0, 9))
            got = dbm.union(z, other) if other is not None else None
            out.append(None if got is None else got.tolist())
        else:
            i, j = rng.sample(range(n + 1), 2)
            got = dbm.constrain(z, i, j, rng.randint(-8, 9))
            out.append(got is None)
            z = z if got is None else got
        out += [z.tolist(), dbm.includes(z, dbm.zero(n)), dbm.close(z).tolist()]
    return out


@needs_cc
def test_the_c_operations_give_the_numpy_reference_s_matrices():
    assert dbm._c() is not None
    try:
        for seed in range(200):
            dbm.use_c(False)
            reference = _random_run(seed)
            dbm.use_c(True)
            assert _random_run(seed) == reference, f"seed {seed}"
    finally:
        dbm.use_c(True)
