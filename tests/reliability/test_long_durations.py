"""Durations far beyond the periods: refused or warned at their line, and an overrun found early ends the check."""
from __future__ import annotations

import pytest

from genom2bip.cli import main
from genom2bip.loading import InputError, TimeSettings
from genom2bip.variants import Variant, apply_variant
from genom2bip.verify import build_model
from genom2bip.verify.options import SearchOptions
from genom2bip.verify.zones import check_timing
from platformkit import FIXTURES, platform_file, verify

ANOMALY = FIXTURES / "Anomaly.gen"

REFUSED = [
    ("cores: 1\ntasks:\n  Anomaly.high:\n    delay: 10 s\n", 4, 12,
     "delay of Anomaly.high: 10000 ms is more than 100 times the period of high (20 ms)"),
    ("cores: 1\ntasks:\n  Anomaly.high:\n    delay: [0 ms, 1440 min]\n", 4, 12,
     "delay of Anomaly.high: 8.64e+07 ms is more than 100 times the period of high (20 ms)"),
    ("cores: 1\nexecution:\n  Anomaly.mid.mid_step: [0 ms, 3 s]\n", 3, 25,
     "execution of Anomaly.mid.mid_step: 3000 ms is more than 100 times the period of mid (20 ms)"),
]


@pytest.mark.parametrize("text,line,column,message", REFUSED, ids=[r[3][:30] for r in REFUSED])
def test_a_duration_far_beyond_the_period_is_refused_where_it_is_written(tmp_path, capsys, text, line, column,
                                                                          message):
    path = platform_file(tmp_path, text)
    code, out, err = verify(capsys, ANOMALY, "--timed", "--platform", path, "--max-states", "20000")  # accepted, a
    assert code == 1  # bounded search instead of one that does not end
    assert f"{path}:{line}:{column}: error: {message}" in err, err
    assert "hint: a duration in ms of the order of the periods is expected" in err
    assert "overrun" not in out
    out_dir = tmp_path / "gen"
    out_dir.mkdir()
    (out_dir / "kept.txt").write_text("before")
    assert main([str(ANOMALY), "--timed", "--platform", str(path), "-o", str(out_dir)]) == 1
    assert f"{path}:{line}:{column}: error: {message}" in capsys.readouterr().err
    assert sorted(p.name for p in out_dir.iterdir()) == ["kept.txt"]


CONTROL = """component Ctl {
  version "1.0";
  lang "c";
  task t { period 10 ms; codel <start> tick() yield pause::start wcet 1 ms; };
  function Set() { codel set() wcet 1 ms; };
};
"""


def test_a_codel_of_the_control_task_is_measured_against_the_longest_period(tmp_path, capsys):
    gen = tmp_path / "Ctl.gen"
    gen.write_text(CONTROL)
    path = platform_file(tmp_path, "cores: 1\nexecution:\n  Ctl.Set.set: [0 ms, 2 s]\n")
    code, _, err = verify(capsys, gen, "--timed", "--platform", path)
    assert code == 1
    assert (f"{path}:3:16: error: execution of Ctl.Set.set: 2000 ms is more than 100 times the longest period "
            "(10 ms)") in err, err


def test_a_codel_longer_than_its_period_is_a_warning_and_its_overrun_is_found_early(tmp_path, capsys):
    path = platform_file(tmp_path, "cores: 1\nexecution:\n  Anomaly.mid.mid_step: [0 ms, 1 s]\n")
    code, out, err = verify(capsys, ANOMALY, "--timed", "--schedulability", "--platform", path,
                            "--max-states", "50000")
    assert (f"{path}:3:25: warning: execution of Anomaly.mid.mid_step: 1000 ms is longer than the period of mid "
            "(20 ms)") in err, err
    assert code == 4
    assert "period of Anomaly.mid (20 ms): overrun reachable" in out
    assert "inconclusive" not in out


def test_the_search_ends_when_every_overrun_asked_for_is_found(tmp_path):
    """Every task overruns here: the check stops there, far below the budget (the whole search is minutes)."""
    path = platform_file(tmp_path, "cores: 1\nexecution:\n  Anomaly.mid.mid_step: [0 ms, 1 s]\n")
    model = build_model([str(ANOMALY)], time=TimeSettings(platform=str(path)))
    results = check_timing(model, ("overrun",), options=SearchOptions(max_states=50_000))
    assert {r.observer: r.verdict.value for r in results} == {
        "Anomaly.high.overrun": "violated", "Anomaly.mid.overrun": "violated", "Anomaly.low.overrun": "violated"}
    assert all(r.trace is not None for r in results)
    assert results[0].figures.states < 25_000, results[0].figures


def test_a_wcet_scale_far_beyond_every_period_is_refused():
    from genom2bip.parser import parse_paths

    description = parse_paths([str(ANOMALY)])
    with pytest.raises(InputError) as info:
        apply_variant(description, Variant(wcet_scale=1e300))
    assert "wcet scale 1e+300: a factor from 0 to 1000 expected" in str(info.value)
    with pytest.raises(InputError):
        apply_variant(description, Variant(wcet_scale=float("nan")))
    assert apply_variant(description, Variant(wcet_scale=1000)) is not description


def test_a_running_search_tells_its_violations_and_its_maxima_so_far(tmp_path, monkeypatch):
    """Through the listener: each overrun (with its trace) while the search goes on, and the largest response
    times reached so far, as lower bounds; the search stops at its budget with those values kept."""
    import io

    from genom2bip.verify import zones
    from genom2bip.verify.options import Listener
    from runtime.explore import Progress

    class Heard(Listener):
        def __init__(self) -> None:
            self.found_at, self.lines = [], []

        def progress(self):
            return Progress(stream=io.StringIO(), force=True)

        def found(self, result) -> None:
            self.found_at.append((result.observer, result.figures.states, result.trace is not None))

        def so_far(self, text: str) -> None:
            self.lines.append(text)

    monkeypatch.setattr(zones, "SO_FAR_PERIOD", 0.0)
    path = platform_file(tmp_path, "cores: 1\nexecution:\n  Anomaly.mid.mid_step: [0 ms, 1 s]\n")
    model = build_model([str(ANOMALY)], time=TimeSettings(platform=str(path), responses=True))
    heard = Heard()
    results = check_timing(model, ("overrun",), responses=True, options=SearchOptions(max_states=3000),
                           listener=heard)
    assert sorted(o for o, _, _ in heard.found_at) == ["Anomaly.high.overrun", "Anomaly.low.overrun",
                                                       "Anomaly.mid.overrun"]
    assert all(traced and states < 3000 for _, states, traced in heard.found_at)  # told before the search ended
    assert heard.lines and "Anomaly.mid ≥ " in heard.lines[0]
    assert any("Anomaly.mid > 80 ms" in line for line in heard.lines)  # past its cap (4 periods)
    mid = next(r for r in results if getattr(r, "owner", "") == "Anomaly.mid")
    assert mid.verdict.value == "inconclusive" and mid.limit == "max-states" and mid.message == zones.ABOVE_CAP
