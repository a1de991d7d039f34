"""Ctrl-C during a timing check: one press stops the whole verify command after what was found so far is printed.

A real SIGINT is sent to a ``genom2bip verify`` subprocess once it has printed its first overruns and a progress
line (waiting for those lines, not for a time); two checks (deadlock, a property) are still to come then.
"""
from __future__ import annotations

import os
import queue
import signal
import subprocess
import sys
import threading
import time

from platformkit import FIXTURES, ROOT, platform_file

ANOMALY = FIXTURES / "Anomaly.gen"
#: Seconds to wait for a line or the end: far above what a slow machine takes (the compile, a second of search).
PATIENCE = 600


def _lines(stream, into: queue.Queue, name: str) -> None:
    for line in stream:
        into.put((name, line))
    into.put((name, None))


def _until(lines: queue.Queue, seen: dict[str, list[str]], done) -> None:
    """Read both streams' lines until ``done(seen)`` holds (or one stream ends); an error past :data:`PATIENCE`."""
    end = time.monotonic() + PATIENCE
    while not done(seen):
        left = end - time.monotonic()
        assert left > 0, "never came:\n" + "".join(seen["out"] + seen["err"][-5:])
        name, line = lines.get(timeout=left)
        if line is None:
            return
        seen[name].append(line)


def _interrupted(argv: list[str], cwd, ready) -> tuple[int, str, str]:
    """``genom2bip verify`` with ``argv``, one SIGINT once ``ready(seen)`` holds of the lines printed so far; its exit
    status, stdout and stderr once it has ended."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-m", "genom2bip", "verify", *argv], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env, cwd=cwd)
    lines: queue.Queue = queue.Queue()
    for stream, name in ((proc.stdout, "out"), (proc.stderr, "err")):
        threading.Thread(target=_lines, args=(stream, lines, name), daemon=True).start()
    seen: dict[str, list[str]] = {"out": [], "err": []}
    try:
        _until(lines, seen, ready)
        assert proc.poll() is None, "".join(seen["out"] + seen["err"])
        proc.send_signal(signal.SIGINT)
        code = proc.wait(timeout=PATIENCE)
    finally:
        if proc.poll() is None:
            proc.kill()
    _until(lines, seen, lambda s: False)
    _until(lines, seen, lambda s: False)
    return code, "".join(seen["out"]), "".join(seen["err"])


def test_one_ctrl_c_prints_what_was_found_and_stops_the_whole_command(tmp_path):
    # mid's codel may take 1 s on a 20 ms task: every task overruns at once, the response times search for minutes
    platform = platform_file(tmp_path, "cores: 1\nexecution:\n  Anomaly.mid.mid_step: [0 ms, 1 s]\n")
    props = tmp_path / "p.mcl"
    props.write_text("ok: deadlock free;\n")
    code, out, err = _interrupted(
        [str(ANOMALY), "--timed", "--platform", str(platform), "--response-times", "--deadlock", "--property",
         str(props), "--progress"], tmp_path,
        lambda s: sum("overrun reachable" in x for x in s["out"]) == 3 and any(x.startswith("states ")
                                                                              for x in s["err"]))
    assert code == 4, out + err  # three overruns were found: the answer, whatever is left undecided
    assert "genom2bip: stopping: what was found so far follows (Ctrl-C again stops at once)" in err
    assert "search stopped (interrupted by Ctrl-C) after " in out, out
    for task in ("high", "mid", "low"):
        assert f"period of Anomaly.{task} (20 ms): overrun reachable (trace above)" in out
        row = next(x for x in out.splitlines() if x.startswith(f"  Anomaly.{task} "))
        assert "so far (interrupted by Ctrl-C)" in row, row
    assert "interrupted: not run: deadlock, property ok" in out
    assert "explored:" not in out and "deadlocks:" not in out and "property ok" not in out.replace("property ok\n", "")
    assert "Traceback" not in err


def test_one_ctrl_c_during_an_untimed_search_stops_the_properties_after_it(tmp_path):
    """DALA's whole level explores for minutes: one SIGINT once progress shows; the properties are not started."""
    dala = ROOT / "descriptions/dala"
    props = tmp_path / "p.mcl"
    props.write_text("a: deadlock free;\nb: deadlock free;\n")
    code, out, err = _interrupted([str(dala), "--deadlock", "--property", str(props), "--progress"], tmp_path,
                                  lambda s: any(x.startswith("states ") for x in s["err"]))
    assert code == 5, out + err
    assert "explored: " in out and "interrupted" in out
    assert "interrupted: not run: property a, property b" in out, out
    assert "Traceback" not in err
