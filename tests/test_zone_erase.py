"""The zone explorer searches an erased copy of the model (no tick, clock guards or resets, no compound priorities):
the copy shares what it does not change with the model, so the model itself must come out of it unchanged, and a
second explorer of the same model must find what the first found."""
from __future__ import annotations

import copy

from test_platform_responses import CASES, model_of
from runtime.model import Package
from runtime.zones.search import ZoneExplorer


def test_erasing_leaves_the_model_as_it_was_and_a_second_search_finds_the_same(tmp_path):
    _, gen, defines, platform, mission = CASES[0]
    model = model_of(tmp_path, gen, defines, platform, mission)
    before: Package = copy.deepcopy(model.package)
    first = ZoneExplorer(model.package, model.root, engine="python")
    got = first.explore()
    assert model.package == before
    erased = first.model.erased
    assert erased != before and erased.atom_types is not model.package.atom_types
    assert sum(len(t.priorities) for t in before.compound_types) > 0  # the erasing had priorities to take away
    assert all(not t.priorities for t in erased.compound_types)
    again = ZoneExplorer(model.package, model.root, engine="python").explore()
    assert (again.states, again.discrete, again.maxima, again.violations) == \
        (got.states, got.discrete, got.maxima, got.violations)
