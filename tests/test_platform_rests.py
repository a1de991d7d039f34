"""A period with nothing to run closes before any core is granted at its instant (genom2bip/build/platform.py,
``rests_first``): fewer interleavings of one instant, and the answers of the model without those ranks."""
from __future__ import annotations

import pytest

from genom2bip.build.platform import PlatformBuilder
from genom2bip.verify.options import SearchOptions
from platformkit import FIXTURES
from runtime.zones.search import ZoneExplorer
from test_platform_responses import model_of, tick_maxima

SPARE = FIXTURES / "Spare.gen"
RUN_ONLY = FIXTURES / "run_only.yaml"
RUN_THEN_HELP = FIXTURES / "run_then_help.yaml"
PLATFORMS = {"one-core": "cores: 1\nbest: 1 ms\n", "two-cores": "cores: 2\nbest: 1 ms\n"}


def build(tmp_path, platform: str, ranks: bool = True):
    with pytest.MonkeyPatch.context() as patch:
        if not ranks:
            patch.setattr(PlatformBuilder, "rests_first", lambda self, tasks: None)
        return model_of(tmp_path, SPARE, {}, PLATFORMS[platform], RUN_THEN_HELP)


def search(model):
    z = ZoneExplorer(model.package, model.root, SearchOptions().externs, engine="c")
    return z, z.explore()


def _labels(z, state) -> set[str]:
    return {z.interaction(i)[2] for i, _ in z.successors(state)}


def test_each_rest_is_above_the_other_tasks_grants(tmp_path):
    z, _ = search(build(tmp_path, "one-core"))
    names = {r.name for r in z.model.rules}
    assert {"Spare_main_grant_after_Spare_spare_rest", "Spare_spare_grant_after_Spare_main_rest"} <= names
    z_off, _ = search(build(tmp_path, "one-core", ranks=False))
    assert not any(r.name.endswith("_rest") and "grant_after_Spare" in r.name for r in z_off.model.rules)


@pytest.mark.parametrize("platform", sorted(PLATFORMS))
def test_no_core_is_granted_while_a_period_with_nothing_to_run_can_close(tmp_path, platform):
    granted_first = {}
    for ranks in (True, False):
        z, result = search(build(tmp_path, platform, ranks))
        assert result.complete
        granted_first[ranks] = sum(
            1 for n in z.nodes if n.parent >= 0 and z.interaction(n.via)[2] == "Spare.main:grant"
            and "Spare.spare:sleep" in _labels(z, z.nodes[n.parent].state))
    assert granted_first[True] == 0 and granted_first[False] > 0  # without the ranks, main may take its core first


@pytest.mark.parametrize("platform", sorted(PLATFORMS))
def test_the_ranks_store_fewer_states_and_change_no_answer(tmp_path, platform):
    on_model, off_model = build(tmp_path, platform), build(tmp_path, platform, ranks=False)
    (z, on), (_, off) = search(on_model), search(off_model)
    assert on.complete and off.complete
    assert on.states < off.states and on.discrete < off.discrete
    assert {k: v[0] for k, v in on.maxima.items()} == {k: v[0] for k, v in off.maxima.items()}
    assert on.violations.keys() == off.violations.keys()
    # an oracle that knows nothing of zones nor of the ranks: the tick model without them, state by state
    ticks = tick_maxima(off_model)
    names = {clock: z.model.flat.atoms[atom].name for atom, (_, clock) in z.model.measures.items()}
    zones = {names[k]: v[0] for k, v in on.maxima.items()}
    assert zones == {n: ticks[n] for n in zones} and len(zones) == 3  # tasks and Help; Run never ends
