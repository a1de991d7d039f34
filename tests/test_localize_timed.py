"""Timing observers by localization: what the first round keeps, the same verdicts as the full search, real traces."""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import pytest

from genom2bip.build.timed import TimeOptions
from genom2bip.cli import main
from genom2bip.verify.timing import observer_atoms
from genom2bip.generate import model_of
from genom2bip.observers import load_observers
from genom2bip.parser import parse_paths
from genom2bip.rules import all_rules
from runtime.diagnostics import Reporter
from runtime.engine import flatten
from runtime.explore import StateSpace
from runtime.localize.abstraction import abstract, always_ready
from runtime.localize.refine import check_localized
from runtime.localize.timed import observer_seed
from runtime.native.properties import compiled_check
from runtime.props import read_property_text
from tests.nativekit import needs_cc
from tests.runkit import dala_without_wcets

pytestmark = needs_cc

ROOT = Path(__file__).resolve().parents[1]
#: whole DALA with its codels at 0 ms (no WCET declared): the shape these rounds were written on
DALA = dala_without_wcets()
CRUISE = ROOT / "tests" / "fixtures" / "timed" / "Cruise.gen"
CRUISE_OBSERVERS = ROOT / "tests" / "fixtures" / "timed" / "observers.yaml"


@lru_cache(maxsize=None)
def timed(kind: str, wcet_us: int = 0, defines: tuple = ()):
    """(package, root, flat) of timed whole DALA (its rules and latency observer) or of the Cruise fixture."""
    if kind == "dala":
        files, observers = sorted(str(p) for p in DALA.glob("*.gen")), DALA / "observers.yaml"
    else:
        files, observers = [str(CRUISE)], CRUISE_OBSERVERS
    description = parse_paths(files, defines=dict(defines))
    reporter = Reporter()
    latencies = load_observers(observers, description, reporter)
    rules = all_rules(description, DALA / "rules.yaml" if kind == "dala" else None, reporter)
    assert not reporter.has_errors
    package, root, _ = model_of(description, kind, rules, TimeOptions(None, wcet_us, latencies, ticks=True))
    return package, root, flatten(package, root)


def observer_item(flat, path: str):
    return read_property_text(f"invariant not ({path} @ ERROR)", flat)


def names(flat, atoms) -> set[str]:
    return {flat.atoms[a].name for a in atoms}


def port(flat, path: str) -> int:
    return next(fp.id for fp in flat.ports if fp.path == path)


# --------------------------------------------------------------------------- ports always offered


def test_a_port_offered_from_every_place_without_guard_is_always_ready():
    _, _, flat = timed("dala")
    assert always_ready(flat, port(flat, "RFLEX.Odo.write"))  # a poster
    assert always_ready(flat, port(flat, "obstacle_to_servo.effect"))  # an observer
    assert always_ready(flat, port(flat, "RFLEX.servo.overrun.tick"))
    assert not always_ready(flat, port(flat, "RFLEX.servo.timer.tick"))  # refused while the period is due
    assert not always_ready(flat, port(flat, "RFLEX.servo.scheduler.exec"))


def test_the_engine_says_which_ports_each_state_offers():
    package, root, flat = timed("dala")
    space = StateSpace(package, root)
    start = space.engine_state(space.initial_ids[0])
    ready = space.engine.ready(start)
    assert len(ready) == len(flat.ports)
    due = {fp.path for fp in flat.ports if fp.name == "tick" and not ready[fp.id]}
    assert due == {"Aspect.map.timer.tick", "LaserRF.acquisition.timer.tick", "NDD.motion.timer.tick",
                   "Planner.plan.timer.tick", "POM.fusion.timer.tick",
                   "RFLEX.servo.timer.tick"}  # every period is due at time 0
    # every port of every enabled interaction is offered, along the first few hundred states
    seen = 0
    for sid in range(400):
        state = space.engine_state(sid)
        ready = space.engine.ready(state)
        for inter in space.engine.enabled(state):
            assert all(ready[port(flat, p)] for p in inter.ports), inter.label
        space.successors(sid)
        seen += 1
    assert seen == 400


def test_a_priority_stays_when_its_high_side_frees_only_always_ready_ports():
    package, root, flat = timed("dala")
    kept = {a.index for a in flat.atoms if a.name in ("RFLEX.servo.timer", "RFLEX.servo.scheduler",
                                                      "RFLEX.servo.permanent")}
    a = abstract(package, root, flat, kept)
    # the high side RFLEX.servo:exec_odometry also takes the dropped poster Odo (always ready): the priority stays
    assert not any(p.endswith("servo_sleep_before_servo_exec_odometry") for p in a.removed_priorities)
    # the high side RFLEX.TrackSpeed:exec_track needs the dropped activity, which may refuse: the priority goes
    assert any(p.endswith("servo_sleep_before_TrackSpeed_exec_track") for p in a.removed_priorities)


# --------------------------------------------------------------------------- the first round


def test_a_latency_observer_starts_with_what_forces_its_effect_in_time():
    _, _, flat = timed("dala")
    observer = next(a.index for a in flat.atoms if a.name == "obstacle_to_servo")
    # the servo step's scheduler and activity (the poster Odo is always ready), and the timer that opens the
    # servo's periods; not the laser side, whose scans may come at any time
    assert names(flat, observer_seed(flat, observer)) == {"obstacle_to_servo", "RFLEX.servo.scheduler",
                                                         "RFLEX.servo.permanent", "RFLEX.servo.timer"}
    assert observer_seed(flat, next(a.index for a in flat.atoms if a.name == "RFLEX.Odo")) == set()


def test_every_observer_of_whole_dala_holds_in_one_round():
    package, root, flat = timed("dala")
    for obs in observer_atoms(package, root):
        rounds = []
        result = check_localized(package, root, observer_item(flat, obs.path), on_round=rounds.append)
        assert result.verdict.holds is True, obs.path
        assert len(rounds) == 1 and rounds[0].kept <= 4 and rounds[0].states < 100, (obs.path, rounds)


# --------------------------------------------------------------------------- verdicts and traces


@pytest.mark.parametrize("defines", [(), (("PERIOD", "15"),)])
def test_the_verdicts_on_cruise_are_the_full_searchs(defines):
    package, root, flat = timed("cruise", defines=defines)
    verdicts = {}
    for obs in observer_atoms(package, root):
        item = observer_item(flat, obs.path)
        got = check_localized(package, root, item).verdict
        want = compiled_check(StateSpace(package, root, observed=item.observed), item)
        assert got.holds is want.holds, obs.path
        if got.holds is False:
            end = StateSpace(package, root).concrete(got.trace)  # the trace fires on the model
            atom = next(a for a in flat.atoms if a.name == obs.path)
            assert end[atom.offset] == 1 << atom.places.index("ERROR")
        verdicts[obs.path] = got.holds
    if defines:
        assert verdicts["Cruise.loop.overrun"] is True
    else:
        assert verdicts == {"Cruise.loop.overrun": False, "track_reacts": True, "command_quickly": False}


def test_an_overrun_of_whole_dala_is_found_with_a_trace_that_replays():
    package, root, flat = timed("dala", wcet_us=25_000)
    rounds = []
    result = check_localized(package, root, observer_item(flat, "RFLEX.servo.overrun"), on_round=rounds.append)
    v = result.verdict
    assert v.holds is False and rounds[-1].outcome == "violated" and rounds[-1].kept < 10
    labels = [s.label for s in v.trace]
    # RFLEX's first period: its init and odometry codels, 25 ms each, in a period of 25 ms; the next release
    # comes when the init codel ends, with the period still open (late)
    assert [x for x in labels if x.startswith("RFLEX.servo")] == ["RFLEX.servo:period", "RFLEX.servo:exec_start",
                                                                 "RFLEX.servo:late", "RFLEX.servo:exec_odometry"]
    end = StateSpace(package, root).concrete(v.trace)
    atom = next(a for a in flat.atoms if a.name == "RFLEX.servo.overrun")
    assert end[atom.offset] == 1 << atom.places.index("ERROR")


# --------------------------------------------------------------------------- the command line


def verify(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(["verify", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_the_timed_whole_level_is_verified_by_invariants_and_localization(capsys):
    """The command of the README's job, on DALA with 0 ms codels (what the same job gives with its measured WCETs
    is in docs/verification/localization.md, *DALA with its measured WCETs*)."""
    code, out, _ = verify(capsys, str(DALA), "--timed", "--method", "compositional")
    assert code == 0
    lines = out.splitlines()
    assert "deadlock-free (compositional" in out
    for task, period in (("Aspect.map", 100), ("LaserRF.acquisition", 75), ("NDD.motion", 100),
                         ("Planner.plan", 200), ("POM.fusion", 50), ("RFLEX.servo", 25)):
        assert any(x.startswith(f"period of {task} ({period} ms): no overrun reachable (localization, 1 round, ")
                   for x in lines), task
    assert any(x.startswith("latency obstacle_to_servo (within 1000 ms): no violation reachable (localization, "
                            "1 round, 4 of 86 atoms kept") for x in lines), [x for x in lines if "latency" in x]


def test_a_violated_observer_is_printed_with_its_timed_trace(capsys):
    code, out, _ = verify(capsys, str(CRUISE), "--timed", "--method", "compositional", "--observers",
                          str(CRUISE_OBSERVERS))
    assert code == 4
    assert "latency track_reacts (within 16 ms): no violation reachable (localization" in out
    head = "latency command_quickly (within 2 ms): violation reachable (localization"
    after = out[out.index(head):].splitlines()[1:6]
    assert [x.split("] ", 1)[1] for x in after[:4]] == ["Cruise.loop:period", "Cruise.Track:trigger",
                                                      "Cruise.Track:start", "Cruise.Track:exec_start  "
                                                      "[track_start -> pause::track]"]
    assert after[4].strip() == "[0 ms .. 4 ms] time passes (2 ticks)"


def test_a_round_stopped_by_its_default_limit_says_so_and_how_to_lift_it(capsys, monkeypatch):
    from genom2bip.verify import localized

    monkeypatch.setattr(localized, "ROUND_STATES", 5)
    code, out, _ = verify(capsys, str(CRUISE), "--timed", "--method", "compositional", "--schedulability")
    assert code == 5
    assert ("period of Cruise.loop (10 ms): inconclusive (a round stopped at 5 states (the default limit of a "
            "localization round; --max-states N sets another))") in out.splitlines()
    code, out, _ = verify(capsys, str(CRUISE), "--timed", "--method", "compositional", "--schedulability",
                          "--max-states", "5")
    assert code == 5
    assert ("period of Cruise.loop (10 ms): inconclusive (the search stopped at max-states before an answer)"
            in out.splitlines())
