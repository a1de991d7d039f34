"""A corpus of small descriptions, each with the exit status genom3 (or GenoM2) gives it.

Every file of tests/fixtures/fidelity/<dialect>/ starts with ``// expect: 0``
(accepted) or ``// expect: 1 LINE:COL message`` (refused, with the first error
at that place).  ``genom2bip check`` must agree on every one.
"""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from genom2bip.cli import main

CORPUS = Path(__file__).parent / "fixtures" / "fidelity"
CASES = sorted(CORPUS.glob("*/*.gen"))
_EXPECT = re.compile(r"(?://|/\*)\s*expect:\s*(\d)(?:\s+(\d+):(\d+)\s+(.*?))?\s*(?:\*/)?$")


def _expectation(path: Path) -> tuple[int, tuple[int, int] | None, str | None]:
    m = _EXPECT.match(path.read_text(encoding="utf-8").splitlines()[0])
    assert m, f"{path.name}: the first line must be '// expect: STATUS [LINE:COL message]'"
    status, line, col, message = m.groups()
    return int(status), (int(line), int(col)) if line else None, message


@pytest.mark.parametrize("path", CASES, ids=[f"{p.parent.name}/{p.stem}" for p in CASES])
def test_check_agrees_with_genom(path, capsys):
    status, where, message = _expectation(path)
    got = main(["check", str(path), "-I", str(path.parent)])
    err = capsys.readouterr().err
    assert got == status, err
    if status:
        first = next(line for line in err.splitlines() if ": error: " in line)
        assert first == f"{path}:{where[0]}:{where[1]}: error: {message}", err
    else:
        assert ": error: " not in err


def test_the_corpus_covers_both_outcomes_in_both_dialects():
    outcomes = {(p.parent.name, _expectation(p)[0]) for p in CASES}
    assert {("genom3", 0), ("genom3", 1), ("genom2", 0), ("genom2", 1)} <= outcomes
