"""The C zone search without memory: each of its allocations made to fail in turn, the search either raises
MemoryError or stores exactly what it stores with memory to spare; it never goes on with less than it was given
(a piece of a zone lost, a program without its tail), and the explorer can still be freed."""
from __future__ import annotations

import re

import pytest

from test_platform_responses import CASES, model_of
from test_zone_engine_c import _node
from runtime.zones.csearch import library
from runtime.zones.search import ZoneExplorer

pytestmark = pytest.mark.skipif(library() is None, reason="the C zone search needs a C compiler (apt-get install gcc)")

#: pair-1-edf: priorities cut zones (EDF), time passes and stops; catchup: a client, merges, programs written in C.
NAMES = ("pair-1-edf", "catchup")


def _search(model, fail: int = -1):
    """A fresh C search of ``model`` with allocation ``fail`` (counted from the search's start) failing; its nodes
    and result, or the MemoryError it raised; and the allocations it made."""
    lib = library()
    z = ZoneExplorer(model.package, model.root, engine="c", program_bytes=1)
    z.successors(z.space.state(z.space.initial_ids[0]))  # the compiled step loaded before the count starts
    start = lib.zs_allocations()
    lib.zs_fail_allocation(fail)
    try:
        r = z.explore()
        got = ([_node(n) for n in z.nodes], r.states, r.transitions, r.violations, r.maxima)
    except MemoryError as e:
        got = e
    finally:
        lib.zs_fail_allocation(-1)
    made = lib.zs_allocations() - start
    search = getattr(z, "search", None)  # None where the context itself could not be made
    if search is not None:
        search.__del__()  # zs_free now on whatever the failed search holds (a later collection would hide where)
    return got, made


def _sample(made: int) -> list[int]:
    """Which allocations to fail: each of the first :data:`FIRST` (the context, the tables, the first programs and
    zones), then :data:`SPREAD` spread evenly over the rest (each one is a whole search: all of them take minutes)."""
    return list(range(min(made, FIRST))) + sorted({FIRST + i * (made - FIRST) // SPREAD for i in range(SPREAD)}
                                                  if made > FIRST else set())


FIRST, SPREAD = 64, 96


@pytest.mark.parametrize("name", NAMES)
def test_every_allocation_that_fails_ends_the_search_with_memory_error(tmp_path, name):
    _, gen, defines, platform, mission = next(c for c in CASES if c[0] == name)
    model = model_of(tmp_path, gen, defines, platform, mission)
    whole, made = _search(model)
    assert not isinstance(whole, MemoryError) and whole[1] > 20, whole
    assert made > 50, made
    raised = 0
    for k in _sample(made):
        got, _ = _search(model, k)
        if isinstance(got, MemoryError):
            assert re.fullmatch(r"zone search: (out of memory|no memory for (its context|the model's tables|a state))",
                                str(got)), (k, got)
            raised += 1
        else:
            assert got == whole, f"allocation {k} of {made} failed and the search went on with less"
    assert raised >= len(_sample(made)) // 2, (raised, made)
