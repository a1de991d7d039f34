"""A campaign output directory that cannot be used is refused (exit 1) before a cluster starts and before anything
is written; a disk that fills up while results are written leaves the results written before, whole, and no
temporary file."""
from __future__ import annotations

import errno
import json
import os

import pytest

from badinputkit import DALA, genom2bip, tree

pytestmark = pytest.mark.reliability

CAMPAIGN = DALA / "campaign.yaml"


def _files(tmp_path):
    return {p: (tmp_path / p).read_bytes() for p in tree(tmp_path) if (tmp_path / p).is_file()}


@pytest.mark.parametrize("make, output, message", [
    (lambda d: (d / "out" / "results.jsonl").mkdir(parents=True), "out",
     "out/results.jsonl: not a regular file (the campaign keeps results.jsonl there): move it away"),
    (lambda d: ((d / "out").mkdir(), (d / "out" / "jobs").write_text("x\n")), "out",
     "out/jobs: not a directory (the campaign keeps each job's result in it): move it away"),
    (lambda d: (d / "out" / ".lock").mkdir(parents=True), "out",
     "out/.lock: not a regular file (the campaign keeps .lock there): move it away"),
    (lambda d: (d / "out").write_text("mine\n"), "out/dala",
     "out/dala: cannot be used as the output directory: out is not a directory"),
    (lambda d: None, "/dev/null/x", "/dev/null/x: cannot be used as the output directory: /dev/null is not a "
                                    "directory"),
], ids=["results-a-directory", "jobs-a-file", "lock-a-directory", "a-file-on-the-way", "dev-null"])
def test_an_output_directory_that_cannot_be_used_is_refused_and_left_as_it_was(tmp_path, make, output, message):
    make(tmp_path)
    before = tree(tmp_path), _files(tmp_path)
    done = genom2bip("campaign", CAMPAIGN, "-o", output, cwd=tmp_path)
    assert done.code == 1, done.err
    assert done.err == f"genom2bip: error: {message}\n"
    assert "campaign dala" not in done.out  # refused before the cluster, before any job
    assert (tree(tmp_path), _files(tmp_path)) == before


RECORD = {"job": "j1", "status": "done", "verdict": "holds", "result": {"states": 3}}


@pytest.fixture
def full_disk(monkeypatch):
    """``full_disk()``: from now on the data of every file written stops short of the disk (fsync: ENOSPC)."""
    def arm() -> None:
        def fsync(fd):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        monkeypatch.setattr(os, "fsync", fsync)
    return arm


def test_a_full_disk_while_a_result_is_written_keeps_the_lines_before_and_leaves_no_partial_file(tmp_path, full_disk):
    from genom2bip.campaign.output import Output, OutputError

    out = Output.open(tmp_path / "out")
    out.write(dict(RECORD))
    before = _files(tmp_path)
    full_disk()
    with pytest.raises(OutputError) as caught:
        out.write(dict(RECORD, job="j2"))
    assert str(caught.value) == f"cannot write {tmp_path / 'out' / 'jobs' / 'j2.json'}: No space left on device; " \
                                "it is left as it was"
    assert _files(tmp_path) == before  # no jobs/j2.json, no .partial, results.jsonl as it was
    assert list(out.records) == ["j1"]


def test_a_full_disk_while_a_line_is_appended_removes_the_cut_line(tmp_path, full_disk):
    from genom2bip.campaign.output import Output, OutputError

    out = Output.open(tmp_path / "out")
    out.write(dict(RECORD))
    full_disk()
    with pytest.raises(OutputError) as caught:
        out.write(dict(RECORD, job="j2", result=None))
    assert str(caught.value).startswith(f"cannot write {out.results}: No space left on device; the results written "
                                        "before are kept"), caught.value
    lines = out.results.read_text().splitlines()
    assert [json.loads(line)["job"] for line in lines] == ["j1"]
    assert not [p for p in tree(tmp_path) if p.endswith(".partial")]
