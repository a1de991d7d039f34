"""A campaign far beyond the machine: more local workers than it can run, or a sweep of millions of jobs, is refused
before a process is started or a job is made; a large one (over 10,000 jobs) is run with a note saying how large."""
from __future__ import annotations

import os

import pytest

from badinputkit import DALA, genom2bip, tree

pytestmark = pytest.mark.reliability

CAMPAIGN = DALA / "campaign.yaml"


def _sweep(tmp_path, *sizes: int):
    """A campaign of one model, one check and an axis per size: prod(sizes) jobs (NDD has one task)."""
    axes = [("default-wcet", lambda i: f"{i} us"), ("wcet-scale", lambda i: f"{1 + i / 100000}"),
            ("define.UNUSED", str)]
    vary = "".join(f"  {key}: [{', '.join(value(i) for i in range(n))}]\n" for (key, value), n in zip(axes, sizes))
    path = tmp_path / "sweep.yaml"
    path.write_text(f"campaign: sweep\nmodels:\n  ndd: {{paths: [{DALA / 'NDD.gen'}], no-rules: true, timed: true}}\n"
                    f"vary:\n{vary}checks:\n  - check: observer\n    model: ndd\n    kinds: [overrun]\n")
    return path


def test_more_workers_than_four_per_core_are_refused_before_anything_starts(tmp_path):
    cores = os.cpu_count() or 1
    done = genom2bip("campaign", CAMPAIGN, "--list", "--workers", 10000, "-o", tmp_path / "out")
    assert done.code == 2, done.out + done.err
    assert done.err == f"genom2bip: error: --workers 10000: at most {4 * cores} on this machine (4 per core, {cores} " \
                       "cores): each worker is a process that searches on a core of its own\n"
    assert done.out == ""
    assert tree(tmp_path) == []


def test_a_sweep_of_a_hundred_million_jobs_is_refused_before_a_job_is_made(tmp_path):
    path = _sweep(tmp_path, 1000, 1000, 100)
    done = genom2bip("campaign", path, "--list")
    assert done.code == 1, done.err[-500:]
    assert done.err.startswith(f"{path}:5:3: error: the campaign makes at least 100,000,000 jobs (the cross product "
                               "of the axes' values, for each model and target), more than the 100,000 a campaign "
                               "may hold\n"), done.err[:400]
    assert "hint: fewer values per axis, or several campaigns" in done.err
    assert done.out == ""
    assert done.peak_mb < 400, done.peak_mb
    assert tree(tmp_path) == ["sweep.yaml"]


def test_a_sweep_just_past_the_limit_is_refused(tmp_path):
    path = _sweep(tmp_path, 317, 317)  # 100,489 points of one target each
    done = genom2bip("campaign", path, "--list")
    assert done.code == 1, done.err[-500:]
    assert done.err.startswith(f"{path}:5:3: error: the campaign makes at least 100,489 jobs "), done.err[:400]


def test_a_sweep_of_fifteen_thousand_jobs_is_listed_with_a_note(tmp_path):
    path = _sweep(tmp_path, 150, 100)
    done = genom2bip("campaign", path, "--list")
    assert done.code == 0, done.err[-500:]
    assert done.err == f"{path}: warning: 15,000 jobs: a large campaign (each job takes seconds to hours); --list " \
                       "shows them\n"
    assert done.out.endswith("\n15000 jobs\n")
