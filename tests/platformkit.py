"""Helpers of the platform timing tests: run verify, read its verdicts and response times, check traces."""
from __future__ import annotations

import re
from pathlib import Path

from genom2bip.cli import main

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "tests/fixtures/platform"
#: Service reports that end a request (what a service's response-time observer closes on).
FINALS = ("finish", "fail", "interrupted", "reject")


def verify(capsys, *argv: str) -> tuple[int, str, str]:
    """``genom2bip verify ARGV``: exit status, stdout, stderr."""
    code = main(["verify", *[str(a) for a in argv]])
    out, err = capsys.readouterr()
    return code, out, err


def platform_file(tmp_path: Path, text: str, name: str = "platform.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def verdicts(out: str) -> dict[str, str]:
    """``{task label: "overrun" | "none"}`` of every period observer printed."""
    found = {}
    for label, what in re.findall(r"^period of (\S+) \([\d.]+ ms\): (overrun reachable|no overrun reachable)",
                                  out, re.M):
        found[label] = "overrun" if what == "overrun reachable" else "none"
    return found


def response_table(out: str) -> dict[str, str]:
    """``{owner: value}`` of the response-time table (``12 ms``, ``never requested``, ``no bound: ...``)."""
    block = out.split("\nresponse times (", 1)
    assert len(block) == 2, f"no response-time table in:\n{out}"
    table = {}
    for line in block[1].splitlines()[1:]:
        m = re.match(r"^  (\S+)\s+(.*?)(?:  \(period [\d.]+ ms\))?$", line)
        if not m:
            break
        table[m.group(1)] = m.group(2)
    return table


def response_ms(out: str) -> dict[str, float]:
    """The response times that are numbers, in ms."""
    return {k: float(v[:-3]) for k, v in response_table(out).items() if re.fullmatch(r"[\d.]+ ms", v)}


def printed_trace(out: str, head: str) -> list[tuple[float, str]]:
    """(ms, label) of the steps of the trace printed after the line starting with ``head``."""
    lines = out.split("\n" + head, 1)[1].splitlines()[1:]
    steps = []
    for line in lines:
        m = re.match(r"^\s+\d+\s+\[([\d.]+) ms\] (\S+)", line)
        if m:
            steps.append((float(m.group(1)), m.group(2)))
        elif not re.match(r"^\s+\[[\d.]+ ms \.\. [\d.]+ ms\] time passes", line):
            break
    return steps


def observed_response(owner: str, kind: str, steps: list[tuple[float, str]], end_ms: float) -> float | None:
    """The response a trace shows at its end: from the opening still watched to ``end_ms`` (None: nothing open).

    A task's response opens at ``owner:period`` and closes at ``owner:sleep``; a service's opens at
    ``owner:trigger`` and closes at its final report.  A second opening while one is watched keeps the first.
    """
    opens = {f"{owner}:period"} if kind == "task" else {f"{owner}:trigger"}
    closes = {f"{owner}:sleep"} if kind == "task" else {f"{owner}:{p}" for p in FINALS}
    since = None
    for ms, label in steps:
        if label in opens and since is None:
            since = ms
        elif label in closes:
            since = None
    return None if since is None else end_ms - since
