"""A full disk while generating: nothing is left behind, the previous output is intact, the next run works.

The disk fills up deterministically: the n-th file written gets half its
bytes, then ENOSPC, as a write on a full file system does.
"""
from __future__ import annotations

import errno
import os
import pathlib

import pytest

from badinputkit import DALA, tree
from genom2bip.cli import main

pytestmark = pytest.mark.reliability


@pytest.fixture
def full_disk(monkeypatch):
    """``full_disk(n)``: from now on the n-th write of a whole file stops half-way with ENOSPC."""
    real = pathlib.Path.write_bytes

    def arm(n: int) -> None:
        count = [0]

        def write_bytes(self, data):
            count[0] += 1
            if count[0] != n:
                return real(self, data)
            with open(self, "wb") as f:
                f.write(data[: len(data) // 2])
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(self))

        monkeypatch.setattr(pathlib.Path, "write_bytes", write_bytes)

    yield arm
    monkeypatch.setattr(pathlib.Path, "write_bytes", real)


def _contents(out: pathlib.Path) -> dict[str, bytes]:
    return {p: (out / p).read_bytes() for p in tree(out) if (out / p).is_file()}


@pytest.mark.parametrize("nth", [1, 3, 6])  # the marker, a file in the middle, the last file
def test_a_full_disk_leaves_the_previous_output_and_no_debris(tmp_path, capsys, full_disk, nth):
    out = tmp_path / "gen"
    assert main([str(DALA), "-o", str(out)]) == 0
    before = _contents(out)
    capsys.readouterr()
    full_disk(nth)
    assert main([str(DALA), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"error: cannot write {out}: No space left on device (writing " in err, err
    assert f"); {out} is left as it was" in err
    assert "internal error" not in err
    assert sorted(os.listdir(out)) == ["dala"]  # no staging directory left behind
    assert _contents(out) == before


def test_after_a_full_disk_the_next_run_writes_without_a_word_about_leftovers(tmp_path, capsys, full_disk):
    out = tmp_path / "gen"
    assert main([str(DALA), "-o", str(out)]) == 0
    full_disk(3)
    assert main([str(DALA), "-o", str(out)]) == 1
    full_disk(0)  # space is back
    capsys.readouterr()
    assert main([str(DALA), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "left by an interrupted run" not in err and "refusing" not in err, err
    assert sorted(os.listdir(out)) == ["dala"]


def test_a_full_disk_on_a_first_run_leaves_no_directory(tmp_path, capsys, full_disk):
    out = tmp_path / "new" / "gen"
    full_disk(2)
    assert main([str(DALA), "-o", str(out)]) == 1
    assert not (tmp_path / "new").exists()
    full_disk(0)
    assert main([str(DALA), "-o", str(out)]) == 0
    assert (out / "dala" / ".genom2bip").is_file()


def test_a_staging_directory_cut_short_by_a_killed_run_is_cleared(tmp_path, capsys):
    """A run killed while writing a file: the marker lists it, its bytes stop half-way."""
    out = tmp_path / "gen"
    assert main([str(DALA), "-o", str(out)]) == 0
    staging = out / ".dala.new.killed"
    staging.mkdir()
    for name in (".genom2bip", "dala.bip"):
        (staging / name).write_bytes((out / "dala" / name).read_bytes())
    (staging / "model.py").write_bytes((out / "dala" / "model.py").read_bytes()[:100])
    capsys.readouterr()
    assert main([str(DALA), "-o", str(out)]) == 0
    assert "left by an interrupted run" not in capsys.readouterr().err
    assert sorted(os.listdir(out)) == ["dala"]
