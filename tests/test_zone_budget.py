"""A zone search stopped on the way (Ctrl-C, its time budget) says how far it got without reading every stored
node back into Python.

The C search counts its nodes and discrete states; reading each node as an object to count them again costs
kilobytes a node, more than the search itself held (a search stopped after minutes ran out of memory there).
"""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys

import genom2bip.verify.zones as zones
from genom2bip.loading import TimeSettings
from genom2bip.verify import build_model
from genom2bip.verify.results import Verdict
from genom2bip.verify.options import Listener, SearchOptions
from genom2bip.verify.zones import check_timing
from platformkit import FIXTURES, ROOT, platform_file
from runtime.explore import Progress
from runtime.zones.csearch import Nodes

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


def searched(tmp_path, monkeypatch, options: SearchOptions | None = None, listener: Listener | None = None):
    """The Anomaly search's results (its response times too, far past any budget here), and its explorer."""
    made = []
    real = zones.explorer

    def kept(model, options=None):
        made.append(real(model, options))
        return made[-1]

    monkeypatch.setattr(zones, "explorer", kept)
    model = build_model([str(ANOMALY)], time=TimeSettings(platform=str(platform_file(tmp_path, LONG)),
                                                          responses=True))
    results = check_timing(model, ("overrun",), responses=True, options=options, listener=listener)
    return results, made[-1]


def _budgeted(tmp_path, monkeypatch, mb: int, max_states: int | None = None):
    """The Anomaly search's results under ``--max-memory mb``, and its explorer."""
    return searched(tmp_path, monkeypatch, SearchOptions(max_memory_mb=mb, max_states=max_states))


def test_a_search_stopped_on_the_way_counts_without_reading_its_nodes(tmp_path, monkeypatch):
    listener = StopAt(4096)
    results, z = searched(tmp_path, monkeypatch, listener=listener)
    assert listener.pressed and z.engine == "c" and isinstance(z.nodes, Nodes), "the C search stopped on the way"
    stopped = [r for r in results if r.verdict is Verdict.INCONCLUSIVE]
    assert stopped and all(r.limit == "interrupted" for r in stopped), [(r.subject, r.limit) for r in stopped]
    counts = z.search.counts()
    discrete = int(re.fullmatch(r"zones, ([\d,]+) discrete states", results[0].method).group(1).replace(",", ""))
    assert discrete == counts[1] > 0
    assert results[0].figures.states == counts[0] == len(z.nodes) >= 4096
    # the traces of the maxima and violations found read a few nodes, not every one
    assert len(z.nodes.cache) < len(z.nodes) // 4, (len(z.nodes.cache), len(z.nodes))


def test_a_search_past_its_memory_budget_stops_with_what_it_found(tmp_path, monkeypatch):
    """--max-memory bounds what the zone search holds: past it the search stops as at --time-limit (the verdicts
    found, the response times reached as lower bounds) instead of growing until the system kills it."""
    said = []

    class Unbounded(Listener):
        def unbounded(self, max_bytes, bounds="--max-states or --max-depth"):
            said.append((max_bytes, bounds))

    results, z = searched(tmp_path, monkeypatch, SearchOptions(max_memory_mb=4), Unbounded())
    assert said == [(4 * 2**20, "--max-states or --time-limit")]
    stopped = [r for r in results if r.verdict is Verdict.INCONCLUSIVE]
    assert stopped and all(r.limit == "max-memory" for r in stopped), [(r.subject, r.limit) for r in stopped]
    # the overruns found before the budget are kept with their traces
    violated = [r for r in results if r.verdict is Verdict.VIOLATED]
    assert violated and all(r.trace for r in violated)


def _limits(results) -> set[str]:
    return {r.limit for r in results if r.verdict is Verdict.INCONCLUSIVE}


def test_the_memory_budget_keeps_room_for_reading_the_search_back(tmp_path, monkeypatch):
    """A search stopped at its budget still reads its nodes and edges back for the traces (about 110 bytes a node
    at RobNav's size, more on whole DALA): that room is part of the budget, or the process ends far past it."""
    import runtime.explore.search as explore_search

    monkeypatch.setattr(explore_search, "resident_bytes", lambda: 10**9)  # the process does not grow
    monkeypatch.setattr(zones, "READ_BACK", (0, 0))
    results, z = _budgeted(tmp_path, monkeypatch, 1000, max_states=3000)
    assert _limits(results) == {"max-states"}  # 1000 MB holds 3,000 nodes...
    monkeypatch.setattr(zones, "READ_BACK", (2**20, 0))
    results, z = _budgeted(tmp_path, monkeypatch, 1000, max_states=3000)
    assert _limits(results) == {"max-memory"}  # ...but not 1,000 of them read back at 1 MB each
    assert 1000 <= z.search.counts()[0] < 3000


def test_the_memory_budget_counts_what_the_process_grows_by_beyond_what_the_search_counts(tmp_path, monkeypatch):
    """The allocator's slack and what Python holds for the search are not in the search's own count; the growth
    of the resident set since the search began is, where it is larger."""
    import runtime.explore.search as explore_search

    monkeypatch.setattr(zones, "READ_BACK", (0, 0))
    grown = iter(range(0, 10**12, 64 * 2**20))  # 64 MB more at each look: past 1000 MB at the 17th
    monkeypatch.setattr(explore_search, "resident_bytes", lambda: next(grown))
    results, z = _budgeted(tmp_path, monkeypatch, 1000, max_states=200_000)
    assert _limits(results) == {"max-memory"}
    assert z.memory() < 1000 * 2**20 and z.search.counts()[0] < 200_000


def test_the_progress_line_shows_the_memory_the_budget_bounds(tmp_path, monkeypatch):
    """The line's ``memory`` is the figure compared with --max-memory (what reading the search back will take
    included), so that a search stopped there stops at the figure the user saw grow."""
    seen = []

    class Seeing(Listener):
        def progress(self):
            class Line(Progress):
                def tick(self, states, transitions, frontier, memory, depth=None):
                    seen.append((states, memory()))

            return Line(enabled=False)

    monkeypatch.setattr(zones, "READ_BACK", (2**20, 0))  # a megabyte a node: the reserve outweighs the rest
    results, _ = searched(tmp_path, monkeypatch, SearchOptions(max_memory_mb=100_000, max_states=3000), Seeing())
    assert seen and all(memory >= states * 2**20 for states, memory in seen), seen[:3]
    assert _limits(results) == {"max-states"}


def test_a_bounded_search_is_not_told_as_unbounded(tmp_path):
    said = []

    class Unbounded(Listener):
        def unbounded(self, max_bytes, bounds="--max-states or --max-depth"):
            said.append(bounds)

    model = build_model([str(ANOMALY)], time=TimeSettings(platform=str(platform_file(tmp_path, LONG)),
                                                          responses=True))
    results = check_timing(model, ("overrun",), responses=True, options=SearchOptions(max_states=3000),
                           listener=Unbounded())
    assert said == []
    assert _limits(results) == {"max-states"}


def test_the_command_says_its_memory_budget_and_stops_there(tmp_path):
    platform = platform_file(tmp_path, LONG)
    proc = subprocess.run([sys.executable, "-m", "genom2bip", "verify", str(ANOMALY), "--timed", "--platform",
                           str(platform), "--response-times", "--max-memory", "4", "--progress"],
                          capture_output=True, text=True, cwd=tmp_path, env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert "searching with no --max-states or --time-limit: until complete or 4 MB (--max-memory)" in proc.stderr
    assert re.search(r"search stopped \(at --max-memory\) after [\d,]+ symbolic states", proc.stdout), proc.stdout
    for task in ("high", "mid", "low"):
        row = next(x for x in proc.stdout.splitlines() if x.startswith(f"  Anomaly.{task} "))
        assert "so far (at --max-memory)" in row, row
    assert proc.returncode == 4, proc.stdout + proc.stderr  # the overruns found are the answer
    assert "Traceback" not in proc.stderr


def test_the_programs_may_hold_a_quarter_of_the_memory_budget_and_never_less_than_a_gib(tmp_path):
    """Programs let go past their budget are written again when a new zone of their state comes (whole DALA on
    two cores with throws wrote 2.6 million again at 1 GiB): a larger memory budget gives them more room."""
    from runtime.zones.search import PROGRAM_BYTES

    model = build_model([str(ANOMALY)], time=TimeSettings(platform=str(platform_file(tmp_path, LONG)),
                                                          responses=True))
    gib = 1 << 30
    assert zones.explorer(model, SearchOptions(max_memory_mb=16 * 1024)).program_bytes == 4 * gib
    assert zones.explorer(model, SearchOptions(max_memory_mb=2 * 1024)).program_bytes == PROGRAM_BYTES == gib
