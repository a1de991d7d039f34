"""Difference-bound matrices over integer clocks: the sets of clock values a zone explorer keeps per state.

A zone over clocks ``x1 .. xn`` is ``M[i][j]``: ``xi - xj <= M[i][j]``, with
``x0 = 0``.  Time here is discrete (a model's tick), so every bound is an
integer and a strict ``x < c`` is ``x <= c - 1``: the integer points of a zone
are exactly the clock values the tick semantics reaches (closed constraints,
as digitization wants).  Entries are floats so that ``inf`` absorbs sums;
integers below 2**53 are exact.  Every function takes and returns canonical
matrices (all bounds tight), and never changes its argument.
"""
from __future__ import annotations

import ctypes
from functools import cache
from pathlib import Path

import numpy as np

INF = np.inf


@cache
def _c():
    """dbm.c compiled and loaded (the C cache of runtime/native), or None without a compiler."""
    from runtime.native.build import BuildError, build, compiler

    cc = compiler()
    if cc is None:
        return None
    try:
        lib = ctypes.CDLL(str(build((Path(__file__).with_name("dbm.c")).read_text(), cc, what="zone DBM")))
    except (BuildError, OSError):
        return None
    ptr, i32, dbl = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    for name, res, args in (("z_close", None, [ptr, i32]), ("z_constrain", i32, [ptr, i32, i32, i32, dbl]),
                            ("z_extrapolate", i32, [ptr, i32, ptr]), ("z_includes", i32, [ptr, ptr, i32]),
                            ("z_free", None, [ptr, ptr, i32, ptr, i32]), ("z_union", i32, [ptr, ptr, ptr, i32, ptr])):
        fn = getattr(lib, name)
        fn.restype, fn.argtypes = res, args
    return lib


def use_c(on: bool) -> None:
    """Choose the C operations (the default where a compiler is) or the numpy ones (the reference, for tests)."""
    global close, constrain, extrapolate, includes, free_many, union
    lib = _c() if on else None
    if lib is None:
        close, constrain, extrapolate, includes, free_many, union = close_np, constrain_np, extrapolate_np, \
            includes_np, free_many_np, union_np
        return

    def close_c(m: np.ndarray) -> np.ndarray:
        out = np.array(m, order="C")
        lib.z_close(out.ctypes.data, out.shape[0])
        return out

    def constrain_c(m: np.ndarray, i: int, j: int, c: float) -> np.ndarray | None:
        if m[i, j] <= c:
            return m
        out = m.copy()
        return out if lib.z_constrain(out.ctypes.data, out.shape[0], i, j, c) else None

    def extrapolate_c(m: np.ndarray, ceiling: np.ndarray) -> np.ndarray:
        out = m.copy()
        return out if lib.z_extrapolate(out.ctypes.data, out.shape[0], _doubles(ceiling).ctypes.data) else m

    def includes_c(big: np.ndarray, small: np.ndarray) -> bool:
        return bool(lib.z_includes(big.ctypes.data, small.ctypes.data, big.size))

    def free_many_c(m: np.ndarray, clocks: list[int]) -> np.ndarray:
        out = np.empty_like(m, order="C")  # z_free copies m's rows
        idx = (ctypes.c_int * len(clocks))(*clocks)
        lib.z_free(out.ctypes.data, m.ctypes.data, out.shape[0], idx, len(clocks))
        return out

    def union_c(a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
        out = np.empty_like(a)
        past = np.empty(a.size, dtype=np.intc)  # z_union's scratch
        return out if lib.z_union(out.ctypes.data, _doubles(a).ctypes.data, _doubles(b).ctypes.data,
                                  a.shape[0], past.ctypes.data) else None

    close, constrain, extrapolate, includes, free_many, union = close_c, constrain_c, extrapolate_c, includes_c, \
        free_many_c, union_c


def _doubles(a: np.ndarray) -> np.ndarray:
    return a if a.dtype == np.float64 and a.flags.c_contiguous else np.ascontiguousarray(a, dtype=np.float64)


def zero(n: int) -> np.ndarray:
    """Every clock at 0."""
    return np.zeros((n + 1, n + 1))


def free_all(n: int) -> np.ndarray:
    """Every clock any value >= 0: the universe."""
    m = np.full((n + 1, n + 1), INF)
    m[0, :] = 0
    np.fill_diagonal(m, 0)
    return m


def close_np(m: np.ndarray) -> np.ndarray:
    """Floyd–Warshall: the tightest bounds (canonical form); an empty zone has a negative diagonal."""
    m = m.copy()
    for k in range(m.shape[0]):
        np.minimum(m, m[:, k:k + 1] + m[k:k + 1, :], out=m)
    return m


def empty(m: np.ndarray) -> bool:
    return bool((np.diagonal(m) < 0).any())


def constrain_np(m: np.ndarray, i: int, j: int, c: float) -> np.ndarray | None:
    """``xi - xj <= c`` added (incremental closure, O(n^2)); None when nothing is left."""
    if m[i, j] <= c:
        return m
    if m[j, i] + c < 0:
        return None
    out = m.copy()
    # every path a -> i -> j -> b may now be shorter
    np.minimum(out, m[:, i:i + 1] + c + m[j:j + 1, :], out=out)
    return out


def constrain_all(m: np.ndarray, bounds) -> np.ndarray | None:
    """Several ``(i, j, c)`` at once; None when the zone is empty."""
    for i, j, c in bounds:
        m = constrain(m, i, j, c)
        if m is None:
            return None
    return m


def up(m: np.ndarray) -> np.ndarray:
    """Time passes: no clock has an upper bound any more (differences stay)."""
    out = m.copy()
    out[1:, 0] = INF
    return out


def down(m: np.ndarray) -> np.ndarray:
    """The past: every point time could have reached it from (lower bounds as low as the differences let them)."""
    out = m.copy()
    out[0, 1:] = np.minimum(0, m[1:, 1:].min(axis=0))
    return out


def intersect(a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    """The points of both zones; None when they share none."""
    return constrain_all(a, [(i, j, b[i, j]) for i, j in zip(*np.nonzero(b < a))])


def reset(m: np.ndarray, i: int, v: float) -> np.ndarray:
    """``xi := v``."""
    out = m.copy()
    out[i, :] = v + m[0, :]
    out[:, i] = m[:, 0] - v
    out[i, i] = 0
    return out


def free(m: np.ndarray, i: int) -> np.ndarray:
    """``xi`` forgotten: any value >= 0 (a clock no guard reads before its next reset)."""
    out = m.copy()
    out[i, :] = INF
    out[:, i] = m[:, 0]
    out[i, i] = 0
    return out


def free_many_np(m: np.ndarray, clocks: list[int]) -> np.ndarray:
    """:func:`free` of several clocks at once."""
    out = m.copy()
    out[clocks, :] = INF
    out[:, clocks] = m[:, [0]]
    out[np.ix_(clocks, clocks)] = INF
    out[clocks, clocks] = 0
    return out


def forget_below(m: np.ndarray, clocks: list[int]) -> np.ndarray:
    """Each of ``clocks`` keeps its upper bounds only: any value from 0 up to what it could reach with the other
    clocks' values (a column of the closed matrix set to the clocks' own upper bounds; still closed)."""
    if not clocks:
        return m
    out = m.copy()
    out[:, clocks] = m[:, [0]]
    out[clocks, clocks] = 0
    return out


def includes_np(big: np.ndarray, small: np.ndarray) -> bool:
    return bool((big >= small).all())


def upper(m: np.ndarray, i: int) -> float:
    """The largest value ``xi`` takes in the zone (inf when unbounded)."""
    return float(m[i, 0])


def lower(m: np.ndarray, i: int) -> float:
    return float(-m[0, i])


def extrapolate_np(m: np.ndarray, ceiling: np.ndarray) -> np.ndarray:
    """Extra_M: bounds past the largest constant a clock is compared with are forgotten (finitely many zones).

    ``ceiling[i]`` is that constant for clock ``i`` (``ceiling[0] = 0``); a clock compared with nothing has
    ceiling -1 and is then free of bounds above and below.  On integers, every value above ``M`` is alike:
    ``x <= v`` with ``v > M`` becomes no bound, ``x >= v`` with ``v > M + 1`` becomes ``x >= M + 1``.
    """
    return extrapolate_lu(m, ceiling, ceiling)


def extrapolate_lu(m: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Extra_LU (Behrmann, Bouyer, Larsen, Pelanek): as Extra_M, with each clock's largest lower-bound constant
    deciding the bounds of its row and its largest upper-bound constant those of its column."""
    rows = lower[:, None]
    cols = upper[None, :] + 1
    above = (m > rows) & (m != INF)
    low = (m < -cols) & ~(m > rows)
    np.fill_diagonal(above, False)
    np.fill_diagonal(low, False)
    if not above.any() and not low.any():
        return m
    out = m.copy()
    out[above] = INF
    out[low] = np.broadcast_to(-cols, out.shape)[low]
    return close_np(out)


def extrapolate_lu_plus(m: np.ndarray, lower: np.ndarray, upper: np.ndarray, plus: np.ndarray) -> np.ndarray:
    """Extra_LU+ where ``plus`` (one bool per clock): a clock above its lower-bound constant has no bound left in its
    row, one above its upper-bound constant none in its column (its lower bound raised to it); only between clocks
    both marked (no priority compares them), Extra_LU elsewhere.  A lower bound raised above 0 (a side no guard
    bounds) is put back to ``x >= 0``, which every clock meets: equal zones then have equal matrices."""
    first = -m[0, :]
    n = m.shape[0]
    idx = np.arange(n)
    li = (idx != 0) & plus & (first > lower + 1)
    uj = (idx != 0) & plus & (first > upper + 1)
    rows, cols = np.meshgrid(idx, idx, indexing="ij")
    both_plus = plus[rows] & (plus[cols] | (cols == 0))
    out = m.copy()
    drop_l = li[rows] & both_plus
    drop_u = ~drop_l & uj[cols] & (rows != 0) & plus[rows]
    raise_u = ~drop_l & ~drop_u & uj[cols] & (rows == 0)
    rest = ~drop_l & ~drop_u & ~raise_u
    above = rest & (m > lower[:, None]) & (m != INF)
    low = rest & ~(m > lower[:, None]) & (m < -(upper[None, :] + 1))
    diag = rows == cols
    out[(drop_l | drop_u | above) & ~diag] = INF
    clamp = (raise_u | low) & ~diag
    out[clamp] = np.broadcast_to(-(upper[None, :] + 1), out.shape)[clamp]
    out[0, 1:] = np.minimum(out[0, 1:], 0)  # clocks are >= 0: one form per zone, so inclusion is exact
    if np.array_equal(out, m):
        return m
    return close_np(out)


def union_np(a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    """The zone ``a`` or ``b`` when their union is one (exact on integer points), else None.  Zones that differ
    only in the order of independent zero-time steps merge so.

    A point of the hull in neither is past a bound ``(i, j)`` of ``a`` that ``b`` goes beyond and past a bound
    ``(k, l)`` of ``b`` that ``a`` goes beyond; the hull (closed) has one iff ``h[i, l] + h[k, j] >= a[i, j] +
    b[k, l] + 2``, the only cycle through both negated bounds."""
    hull = np.maximum(a, b)
    ai, aj = np.nonzero(b > a)
    bk, bl = np.nonzero(a > b)
    if not len(ai) or not len(bk):
        return hull
    reach = hull[ai[:, None], bl[None, :]] + hull[bk[None, :], aj[:, None]]
    return None if (reach >= a[ai, aj][:, None] + b[bk, bl][None, :] + 2).any() else hull


def subtract(m: np.ndarray, other: np.ndarray) -> list[np.ndarray]:
    """``m`` minus ``other`` as disjoint zones (integer complements: ``not (xi - xj <= c)`` is ``xj - xi <= -c-1``)."""
    return [z for z, _ in subtract_bounds(m, other)]


def subtract_bounds(m: np.ndarray, other: np.ndarray) -> list[tuple[np.ndarray, list]]:
    """:func:`subtract`, each piece with the bounds ``(i, j, c)`` that cut it out of ``m`` (for traces)."""
    out = []
    rest = m
    kept: list = []
    n = m.shape[0]
    for i in range(n):
        for j in range(n):
            if i == j or other[i, j] == INF or rest[i, j] <= other[i, j]:
                continue
            cut = (j, i, -other[i, j] - 1)
            piece = constrain(rest, *cut)
            if piece is not None:
                out.append((piece, kept + [cut]))
            rest = constrain(rest, i, j, other[i, j])
            kept = kept + [(i, j, other[i, j])]
            if rest is None:
                return out
    return out


def point(m: np.ndarray) -> list[int]:
    """One integer valuation of a non-empty canonical zone (each clock as low as it can be, in order)."""
    z = m
    values = []
    for i in range(1, m.shape[0]):
        v = lower(z, i)
        z = constrain_all(z, [(i, 0, v), (0, i, -v)])
        values.append(int(v))
    return values


def key(m: np.ndarray) -> bytes:
    return m.tobytes()


close, constrain, extrapolate, includes, free_many, union = close_np, constrain_np, extrapolate_np, includes_np, \
    free_many_np, union_np
use_c(True)
