"""An output nobody reads (``run ... | sleep 1000``) stalls neither the engine nor the services interface."""
from __future__ import annotations

import re

from controlproc import ControllerProcess
from flood import Flood


def test_an_undrained_stdout_stalls_nothing_and_the_lines_dropped_are_counted_and_said_once():
    with ControllerProcess(read_stdout=False) as ctl:
        ctl.wait_ready()
        client = ctl.client()
        # 6,000 final reports, a console line each: more than a pipe (64 KiB) and the console's queue hold
        flood = Flood(ctl.url, 6000, 8, wait_every=1, answer_wait=30)
        seen = flood.run()
        assert len(seen.answers) == 6000 and all(seen.answers.values()), \
            f"{sum(seen.answers.values())} of {len(seen.answers)} answers with their final report"
        assert client.info()["status"] == "running"
        assert ctl.wait_for(lambda: ctl.printed("the output is not being read"))
        end = ctl.stop()  # stdout is read again from the signal on
    assert end.status == 0 and "Traceback" not in end.err, end.err[-2000:]
    dropped = re.search(r"^stopped after \d+ steps; requests: 6000 ok; (\d+) output lines dropped", end.out, re.M)
    assert dropped and int(dropped.group(1)) > 0, end.out[-1000:]
    assert end.err.count("the output is not being read") == 1, end.err
    marker = re.search(r"^\.\.\. (\d+) lines dropped: the output was not read$", end.out, re.M)
    assert marker and int(marker.group(1)) <= int(dropped.group(1)), end.out[-3000:]
