"""bench/robnav_bench.py reads the artefact's UPPAAL model: checked on a fixture of the same shape
(tests/fixtures/artefact), since the artefact itself stays out of the repository."""
from __future__ import annotations

import sys
from pathlib import Path

from genom2bip.parser import parse_paths

ROOT = Path(__file__).resolve().parents[1]
ARTEFACT = ROOT / "tests" / "fixtures" / "artefact"
sys.path.insert(0, str(ROOT / "bench"))
import robnav_bench  # noqa: E402


def read():
    description = parse_paths([str(ARTEFACT / "alpha" / "alpha.gen")], [str(ARTEFACT)])
    return robnav_bench.read_artefact((ARTEFACT / "robnav-artefact-edf.xta").read_text(), description)


def test_intervals_offsets_requests_and_when_requests_are_taken_come_from_the_model():
    execution, offsets, requests, ready = read()
    assert execution == {"alpha.t.InitT": (8, 10), "alpha.u.InitU": (9, 10),
                         "alpha.Go.goStart": (3, 5), "alpha.Go.goWork": (10, 10)}
    assert offsets == {"alpha.u": (8, 10)}  # u's timer starts when t's initial codel ends
    assert requests == ["alpha.Go"]
    assert ready == 20  # alpha's control waits for u's initial codel, which waits for t's: 10 + 10 ms


def test_the_client_sends_its_first_request_when_the_components_take_requests():
    _, _, requests, ready = read()
    text = robnav_bench.client_text(requests, ready)
    assert text.splitlines()[2:] == ["  - send: alpha.Go", "    after: 20 ms", "    until: queued"]
    assert "after" not in robnav_bench.client_text(requests, 0)  # --requests-at-start


def test_the_platform_written_is_valid_and_releases_one_by_one_as_the_artefact(tmp_path):
    from genom2bip.platform import load_platform
    from runtime.diagnostics import Reporter

    execution, offsets, _, _ = read()
    description = parse_paths([str(ARTEFACT / "alpha" / "alpha.gen")], [str(ARTEFACT)])
    for releases in ("one-by-one", "together"):
        path = tmp_path / f"{releases}.yaml"
        path.write_text(robnav_bench.platform_text(3, execution, offsets, releases))
        reporter = Reporter()
        platform = load_platform(path, description, reporter)
        assert platform is not None, reporter.diagnostics
        assert (platform.cores, platform.policy, platform.releases) == (3, "edf", releases)
        assert platform.tasks[("alpha", "u")].delay.best_us == 8000
    assert "releases: one-by-one" in robnav_bench.platform_text(3, execution, offsets).splitlines()


SUSPENDING = """process Manager_t_alpha(urgent chan &exe, bool &lock_t_alpha) {
clock x;
state
    start,
    manage;
init
    start;
trans
    start -> manage { guard x==10; };
}

process Manager_u_alpha(urgent chan &exe, bool &lock_u_alpha) {
clock x,y;
state
    start,
    manage,
    delay { y<=11 };
init
    start;
trans
    delay -> manage { guard y==11; };
}
"""


def test_the_suspending_task_is_the_one_whose_manager_has_a_delay_state():
    assert robnav_bench.suspending_task(SUSPENDING) == "alpha.u"
    assert robnav_bench.suspending_task((ARTEFACT / "robnav-artefact-edf.xta").read_text()) is None


def test_the_published_suspension_figures_are_read_per_sd(tmp_path):
    csv = tmp_path / "res.csv"
    csv.write_text(";sd;MRT odo;MRT track;MRT fuse;MRT scan;MRT plan\n;0;40;40;45;65;60\n;45;35;35;40;60;105\n")
    assert robnav_bench.published_by_sd(csv) == {
        0: {"robloco.odo": 40, "robloco.track": 40, "robmap.fuse": 45, "roblaser.scan": 65, "robmotion.plan": 60},
        45: {"robloco.odo": 35, "robloco.track": 35, "robmap.fuse": 40, "roblaser.scan": 60, "robmotion.plan": 105}}


def test_the_suspension_is_written_after_the_grant_as_in_the_artefact(tmp_path):
    from genom2bip.platform import load_platform
    from runtime.diagnostics import Reporter

    execution, offsets, _, _ = read()
    description = parse_paths([str(ARTEFACT / "alpha" / "alpha.gen")], [str(ARTEFACT)])
    path = tmp_path / "p.yaml"
    path.write_text(robnav_bench.platform_text(4, execution, offsets, suspend={"alpha.u": 11}))
    reporter = Reporter()
    platform = load_platform(path, description, reporter)
    assert platform is not None, reporter.diagnostics
    settings = platform.tasks[("alpha", "u")]
    assert (settings.suspend.best_us, settings.suspend.worst_us, settings.suspend_after) == (11000, 11000, "grant")
    assert settings.delay.best_us == 8000  # its offset is kept beside
