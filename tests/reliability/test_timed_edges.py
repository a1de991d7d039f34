"""Components at the edge of what time means: one with no task at all, a periodic task that runs no codel.  With
--timed --response-times (and a platform) each builds a valid model and gets an answer, never a generator bug."""
from __future__ import annotations

import pytest

from badinputkit import genom2bip

pytestmark = pytest.mark.reliability

EMPTY = 'component Empty { version "1.0"; lang "c"; };\n'
IDLE_TASK = "component C {\n  task t { period 10 ms; };\n};\n"


@pytest.fixture
def inputs(tmp_path):
    (tmp_path / "Empty.gen").write_text(EMPTY)
    (tmp_path / "T.gen").write_text(IDLE_TASK)
    (tmp_path / "one.yaml").write_text("cores: 1\n")
    return tmp_path


@pytest.mark.parametrize("more", [(), ("--platform", "one.yaml")], ids=["dedicated", "one-core"])
def test_a_component_with_no_task_generates_a_valid_timed_model(inputs, more):
    from runtime.bip2 import parse_file

    done = genom2bip("generate", "Empty.gen", "-o", "out", "--timed", "--response-times", *more, cwd=inputs)
    assert done.code == 0, done.err
    assert "generator bug" not in done.err
    assert parse_file(inputs / "out" / "empty" / "empty.bip").name == "empty"  # the runtime reads it back


def test_response_times_of_a_component_with_no_task_say_there_is_none(inputs):
    done = genom2bip("verify", "Empty.gen", "--timed", "--response-times", cwd=inputs)
    assert done.code == 0, done.err
    assert "response times: none to measure (Empty (EMPTY()) has no periodic task and no service)\n" in done.out


@pytest.mark.parametrize("more", [(), ("--platform", "one.yaml")], ids=["dedicated", "one-core"])
def test_a_periodic_task_with_no_codel_has_a_response_time_of_zero(inputs, more):
    done = genom2bip("verify", "T.gen", "--timed", "--response-times", *more, cwd=inputs)
    assert done.code == 0, done.err
    assert "IdleScheduler" not in done.err and "time changes discrete data" not in done.err, done.err
    assert "period of C.t (10 ms): no overrun reachable (zones" in done.out, done.out
    assert "\n  C.t  0 ms  (period 10 ms)\n" in done.out, done.out
