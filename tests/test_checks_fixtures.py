"""Check fixtures: one description per dialect with one mistake of each kind, all reported, in order.

Each ``tests/fixtures/checks/NAME.gen`` has a ``NAME.expected`` listing
``line:column message`` of every error ``genom2bip check`` must report.
"""
from pathlib import Path

import pytest

from genom2bip import cli

FIXTURES = Path(__file__).parent / "fixtures" / "checks"


@pytest.mark.parametrize("name", sorted(p.stem for p in FIXTURES.glob("*.gen")))
def test_every_error_of_the_fixture_is_reported_in_order(capsys, name):
    path = FIXTURES / f"{name}.gen"
    code = cli.main(["check", str(path)])
    out, err = capsys.readouterr()
    assert code == 1
    assert out == ""
    prefix = f"{path}:"
    found = [line[len(prefix):].replace(": error: ", " ", 1)
             for line in err.splitlines() if line.startswith(prefix) and ": error: " in line]
    expected = (FIXTURES / f"{name}.expected").read_text().splitlines()
    assert found == expected
    assert err.rstrip().endswith(f"{len(expected)} errors")
