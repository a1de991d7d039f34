"""A campaign's results are never deleted nor trusted blindly, its name never escapes ``out/``, and a stop (Ctrl-C,
an output closed) counts every job the table counts.

The first tests read results directories by hand and need no cluster; the
last run jobs on an in-process Dask cluster (a thread per worker).
"""
from __future__ import annotations

import json

import pytest

from badinputkit import ROOT, genom2bip, tree

pytestmark = pytest.mark.reliability

CRUISE = ROOT / "tests" / "fixtures" / "timed" / "Cruise.gen"
SWEEP = f"""campaign: cruise
models:
  cruise:
    paths: [{CRUISE}]
    timed: {{observers: {CRUISE.parent / "observers.yaml"}}}
vary:
  define.PERIOD: [10, 12, 15]
checks:
  - check: observer
    model: cruise
"""


def _jobs(path):
    from genom2bip.campaign import expand, read_campaign

    return expand(read_campaign(path)).jobs


def _record(job, verdict="holds"):
    return {"job": job.id, **job.parameters(), "host": "h", "worker": "w", "pid": 1, "status": "done",
            "verdict": verdict, "message": "", "limit": None, "figures": {"states": 12}, "values": None,
            "result": None, "trace": None, "seconds": 0.5, "cpu_seconds": 0.4, "peak_memory": 1 << 20}


@pytest.fixture
def sweep(tmp_path):
    path = tmp_path / "cruise.yaml"
    path.write_text(SWEEP)
    return path, _jobs(path)


def test_lines_that_are_not_records_are_kept_aside_as_they_were_and_the_summary_reads_the_others(tmp_path, sweep):
    path, jobs = sweep
    out = tmp_path / "out"
    out.mkdir()
    good = b"".join(json.dumps(_record(j)).encode() + b"\n" for j in jobs)
    bad = [b'{"a": 1}\n', b"not json\n", json.dumps({"job": jobs[0].id}).encode() + b"\n",  # no status: not done
           json.dumps({**_record(jobs[1]), "verdict": [1]}).encode() + b"\n",  # crashed the summary
           json.dumps({**_record(jobs[2]), "figures": "lots"}).encode() + b"\n",
           b"\xff\xfe not UTF-8\n", b'[' * 100_000 + b"\n", b'{"job": "cut by a kill", "sta']
    (out / "results.jsonl").write_bytes(good + b"".join(bad))
    done = genom2bip("campaign", path, "-o", out)
    assert done.code == 0, done.out + done.err  # every job holds: none runs again, nothing needs a cluster
    assert "internal error" not in done.err
    assert f"note: {len(bad)} line(s) of {out / 'results.jsonl'} are not job records (cut short or edited): moved, " \
           f"as they were, to {out / 'results.unreadable.jsonl'}; their jobs run again" in done.out, done.out
    assert "9 jobs, 9 already in" in done.out and "9 jobs: 9 holds" in done.out
    assert (out / "results.jsonl").read_bytes() == good
    assert (out / "results.unreadable.jsonl").read_bytes() == b"".join(bad) + b"\n"  # the cut line ended


def test_a_record_without_a_status_is_not_done_and_its_job_runs_again(tmp_path, sweep):
    from genom2bip.campaign.output import Output

    _, jobs = sweep
    out = tmp_path / "out"
    out.mkdir()
    lines = [json.dumps(_record(j)) + "\n" for j in jobs[1:]] + [json.dumps({"job": jobs[0].id}) + "\n"]
    (out / "results.jsonl").write_text("".join(lines))
    assert jobs[0].id not in Output.peek(out)  # before opening: nothing changed yet
    assert (out / "results.jsonl").read_text() == "".join(lines)
    opened = Output.open(out)
    try:
        assert jobs[0].id not in opened.records and len(opened.records) == 8 and opened.dropped == 1
    finally:
        opened.close()
    assert (out / "results.unreadable.jsonl").read_text() == lines[-1]
    assert (out / "results.jsonl").read_text() == "".join(lines[:-1])


@pytest.mark.parametrize("name, message", [
    ("../../trav", "a name is one component of a path, without '/' or '\\'"),
    ("a/b", "a name is one component of a path, without '/' or '\\'"),
    ("'..'", "'..' names a directory"),
])
def test_a_campaign_name_that_is_not_one_plain_file_name_is_located_and_nothing_is_written(tmp_path, name, message):
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    path = work / "c.yaml"
    path.write_text(SWEEP.replace("campaign: cruise", f"campaign: {name}"))
    done = genom2bip("campaign", path, cwd=work)
    assert done.code == 1, done.out + done.err
    shown = name.strip("'")
    assert done.err.startswith(f"{path}:1:11: error: campaign: {shown!r} cannot name its output directory: "
                               f"{message}\n"), done.err
    assert tree(tmp_path) == ["a", "a/b", "a/b/c.yaml"]


@pytest.fixture
def threads():
    """A Dask client of an in-process cluster: one worker thread (the jobs build their models in it)."""
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None)
    client = distributed.Client(cluster)
    yield client
    client.close()
    cluster.close()


class _Display:
    def started(self, job_id, worker):
        pass

    def finished(self, job, record):
        pass


def test_ctrl_c_while_a_result_is_taken_counts_and_lists_that_job(sweep, threads, monkeypatch):
    """Ctrl-C just after a job's future left the cluster's hands, before its record was written: it is not done."""
    from genom2bip.campaign import cluster

    _, jobs = sweep
    taken, real = [], cluster._record

    def record(job, future):
        taken.append(job)
        if len(taken) == 2:
            raise KeyboardInterrupt
        return real(job, future)

    monkeypatch.setattr(cluster, "_record", record)
    written = []
    run = cluster.run(jobs, threads, lambda r: written.append(r) or r, _Display())
    assert run.interrupted and len(written) == len(run.written) == 1
    assert taken[1] in run.undone  # the job taken when Ctrl-C came
    assert sorted(j.id for j in run.undone) == sorted(j.id for j in jobs if j.id != written[0]["job"])


def test_a_closed_output_stops_the_run_after_the_job_that_met_it(sweep, threads):
    from genom2bip.campaign import cluster

    _, jobs = sweep
    written = []
    run = cluster.run(jobs, threads, lambda r: written.append(r) or r, _Display(), closed=lambda: bool(written))
    assert run.closed and not run.interrupted and len(written) == 1
    assert sorted(j.id for j in run.undone) == sorted(j.id for j in jobs if j.id != written[0]["job"])


def test_an_output_closed_before_the_run_runs_nothing(sweep, threads):
    from genom2bip.campaign import cluster

    _, jobs = sweep
    run = cluster.run(jobs, threads, lambda r: pytest.fail("nothing runs"), _Display(), closed=lambda: True)
    assert run.closed and run.undone == sorted(jobs, key=lambda j: j.index) and run.written == []
