"""A zone search stopped on the way (Ctrl-C, its time budget) says how far it got without reading every stored
node back into Python.

The C search counts its nodes and discrete states; reading each node as an object to count them again costs
kilobytes a node, more than the search itself held (a search stopped after minutes ran out of memory there).
"""
from __future__ import annotations

import os
import re
import signal

import genom2bip.verify.zones as zones
from genom2bip.loading import TimeSettings
from genom2bip.verify import build_model
from genom2bip.verify.results import Verdict
from genom2bip.verify.options import Listener
from genom2bip.verify.zones import check_timing
from platformkit import FIXTURES, platform_file
from runtime.explore import Progress

ANOMALY = FIXTURES / "Anomaly.gen"
#: mid's codel may take 1 s on a 20 ms task: the response times search for minutes, far past the budget below.
LONG = "cores: 1\nexecution:\n  Anomaly.mid.mid_step: [0 ms, 1 s]\n"


class StopAt(Listener):
    """Presses Ctrl-C (a real SIGINT) once the search holds ``nodes`` nodes: a budget reached at a known point."""

    def __init__(self, nodes: int) -> None:
        self.nodes, self.pressed = nodes, False

    def progress(self):
        listener = self

        class Pressing(Progress):
            def tick(self, states, transitions, frontier, memory, depth=None):
                if states >= listener.nodes and not listener.pressed:
                    listener.pressed = True
                    os.kill(os.getpid(), signal.SIGINT)

        return Pressing(enabled=False)


def test_a_search_stopped_on_the_way_counts_without_reading_its_nodes(tmp_path, monkeypatch):
    made = []
    real = zones.explorer

    def kept(model, options=None):
        made.append(real(model, options))
        return made[-1]

    monkeypatch.setattr(zones, "explorer", kept)
    model = build_model([str(ANOMALY)], time=TimeSettings(platform=str(platform_file(tmp_path, LONG)),
                                                          responses=True))
    listener = StopAt(4096)
    results = check_timing(model, ("overrun",), responses=True, listener=listener)
    z = made[-1]
    assert listener.pressed and z.engine == "c" and hasattr(z.nodes, "rows"), "the C search stopped on the way"
    stopped = [r for r in results if r.verdict is Verdict.INCONCLUSIVE]
    assert stopped and all(r.limit == "interrupted" for r in stopped), [(r.subject, r.limit) for r in stopped]
    counts = z.search.counts()
    discrete = int(re.fullmatch(r"zones, ([\d,]+) discrete states", results[0].method).group(1).replace(",", ""))
    assert discrete == counts[1] > 0
    assert results[0].figures.states == counts[0] == len(z.nodes) >= 4096
    # the traces of the maxima and violations found read a few nodes, not every one
    assert len(z.nodes.cache) < len(z.nodes) // 4, (len(z.nodes.cache), len(z.nodes))
