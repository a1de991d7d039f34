"""What the running controller and ``simulate`` print stays readable: overruns summed up at most once a second,
a step's line within 120 columns."""
from __future__ import annotations

import io


from runkit import ROOT

from runtime.services.digest import OverrunDigest


class Clock:
    """A clock the test moves: no wall-clock dependence."""

    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


def _overrun(task: str, took: float) -> dict:
    return {"event": "overrun", "task": task, "took_ms": took, "message": f"task {task} overran: {took} ms"}


def test_overruns_come_at_most_one_line_a_second_and_every_one_is_counted():
    clock = Clock()
    digest = OverrunDigest(clock=clock)
    printed = []
    for i in range(136):  # one a 10 ms step over 1.36 s: what a loaded machine gave, a line each
        printed += digest.take(_overrun("RFLEX.servo" if i % 4 else "POM.fusion", 30.0 + i % 7))
        clock.t += 0.01
    printed += digest.flush()
    assert printed[0] == "overrun: task POM.fusion overran: 30.0 ms"
    assert len(printed) == 3  # the first, the count due after a second, the rest at the end
    assert printed[1].startswith("overruns: 100 more in the last 1.0 s: RFLEX.servo overran 75x (longest 36 ms), "
                                 "POM.fusion overran 25x (longest 36 ms)")
    assert printed[2].startswith("overruns: 35 more since the last line: ")
    counted = sum(int(part.split(" more")[0].split()[-1]) for part in printed[1:])
    assert counted + 1 == 136


def test_a_quiet_second_lets_the_next_overrun_through_and_other_events_bring_the_count_due():
    clock = Clock()
    digest = OverrunDigest(clock=clock)
    assert digest.take(_overrun("NDD.motion", 120)) == ["overrun: task NDD.motion overran: 120 ms"]
    assert digest.take({"event": "codel_overrun", "codel": "nddPlan", "running_ms": 250.0, "message": "m"}) == []
    clock.t += 1.5
    assert digest.take({"event": "report"}) == [
        "overruns: 1 more in the last 1.5 s: nddPlan codel late 1x (longest 250 ms) (every one: the live page, "
        "GET /events)"]
    clock.t += 2.0
    assert digest.take(_overrun("NDD.motion", 130)) == ["overrun: task NDD.motion overran: 130 ms"]
    assert digest.flush() == []


def test_simulate_lines_of_the_whole_level_stay_within_120_columns(monkeypatch, capsys):
    monkeypatch.syspath_prepend(str(ROOT / "gen"))
    import dala
    from runtime.app import main

    assert main(dala.package(), dala.ROOT, ["simulate", "--seed", "1", "--limit", "300"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) > 300 and max(len(line) for line in lines) <= 120
    assert "(1 of 36 enabled)" in lines[0]  # the thirty-six alternatives are counted, not listed


def test_a_small_model_still_lists_its_alternatives():
    from runtime.bip2 import parse_file
    from runtime.engine import ConsoleTracer, Engine, first

    out = io.StringIO()
    Engine(parse_file(str(ROOT / "examples" / "model.bip")), "System()").run(first, 2, ConsoleTracer(out))
    assert out.getvalue().splitlines()[0] == "[    1] left0    (of 2: left0, left1)"
