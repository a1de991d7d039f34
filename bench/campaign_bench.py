"""DALA's campaign on a local Dask cluster against the same checks run one after another: wall clock of each, with
the machine's load averages before and after (a shared machine's figures mean little without them).

    python bench/campaign_bench.py [--rounds 2] [--workers 2]

Runs, in each round and in turn: the README's three ``verify`` commands (the main job's checks, sequentially),
every job of descriptions/dala/campaign.yaml but its response-time sweep (which the README has not) in one process
through the verification API (sequentially, models built once), the same ``genom2bip campaign`` on a local cluster
(cluster start and the models built to name the jobs included), and the same campaign on a running cluster: a
``dask scheduler`` and one ``dask worker`` per core started beforehand, each in a session of its own, as workers
started on other machines are.  The C cache is warmed first, so no run pays for compiling.

Where the kernel shares the CPU between sessions (Linux's autogroup, ``/proc/sys/kernel/sched_autogroup_enabled``),
every process of one session shares one session's part of a busy machine: the local cluster's workers, children of
the command, then get no more CPU than one process would, while workers in sessions of their own each get a part.
"""
from __future__ import annotations

import argparse
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DALA = ROOT / "descriptions" / "dala"
CAMPAIGN = DALA / "campaign.yaml"
PROPS = DALA / "properties"
README = [
    ["verify", str(DALA / "NDD.gen"), "--property", str(PROPS / "NDD.mcl")],
    ["verify", str(DALA), "--timed", "--method", "compositional"],
    ["verify", str(DALA), "--method", "compositional", "--property", str(PROPS / "NDD.mcl"), "--property",
     str(PROPS / "rules.mcl")],
]


NOTES: list[str] = []  # what the last run said of itself, printed under its figure


def load() -> str:
    return "/".join(f"{x:.1f}" for x in os.getloadavg())


def timed(label: str, fn) -> float:
    before = load()
    start = time.perf_counter()
    fn()
    seconds = time.perf_counter() - start
    print(f"{label:<48} {seconds:7.1f} s   load {before} -> {load()}", flush=True)
    while NOTES:
        print(f"    ({NOTES.pop(0)})", flush=True)
    return seconds


def genom2bip(*args: str) -> None:
    proc = subprocess.run([sys.executable, "-m", "genom2bip", *args], capture_output=True, text=True, cwd=ROOT)
    if proc.returncode not in (0,):
        raise SystemExit(f"genom2bip {' '.join(args)} exited {proc.returncode}:\n{proc.stderr[-2000:]}")
    for line in proc.stdout.splitlines():  # a campaign's own account: its jobs' phase, the time its jobs took
        if " jobs run in " in line:
            NOTES.append(line.strip())


def main_job_campaign(tmp: str) -> Path:
    """DALA's campaign without its response-time sweep (the README's main job has no counterpart of it), written
    in ``tmp`` with every path made absolute."""
    import yaml

    data = yaml.safe_load(CAMPAIGN.read_text())
    data["checks"] = [c for c in data["checks"] if c["check"] != "response-times"]
    used = {c["model"] for c in data["checks"]}
    data["models"] = {name: m for name, m in data["models"].items() if name in used}
    for model in data["models"].values():
        model["paths"] = [str(DALA / p) for p in model["paths"]]
    for check in data["checks"]:
        if "files" in check:
            check["files"] = [str(DALA / f) for f in check["files"]]
    path = Path(tmp) / "campaign.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def in_process(campaign: str) -> None:
    """Every job of the campaign, one after another, in a fresh process (models built once each)."""
    code = ("from genom2bip.campaign import expand, read_campaign, run_job\n"
            f"jobs = expand(read_campaign({campaign!r})).jobs\n"
            "bad = [j.title for j in jobs if run_job(j)['verdict'] != 'holds']\n"
            "assert not bad, bad\n")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


def running_cluster(workers: int, log: Path):
    """A scheduler and ``workers`` workers on loopback, each in a session of its own: ``(address, processes)``."""
    from distributed import Client

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    dask = [sys.executable, "-m", "dask"]
    out = log.open("w")
    procs = [subprocess.Popen([*dask, "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
                              stdout=out, stderr=subprocess.STDOUT, start_new_session=True)]
    procs += [subprocess.Popen([*dask, "worker", address, "--nthreads", "1", "--host", "127.0.0.1", "--no-dashboard"],
                               stdout=out, stderr=subprocess.STDOUT, start_new_session=True) for _ in range(workers)]
    with Client(address, timeout=120) as client:
        client.wait_for_workers(workers, timeout=120)
    return address, procs


def autogroup() -> str:
    try:
        return Path("/proc/sys/kernel/sched_autogroup_enabled").read_text().strip()
    except OSError:
        return "?"


def main() -> None:
    """A running cluster started aside, then the rounds."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    args = parser.parse_args()
    print(f"{os.cpu_count()} cores; campaign: {args.workers} workers; {args.rounds} rounds; "
          f"autogroup {autogroup()}")
    with tempfile.TemporaryDirectory() as tmp:
        address, procs = running_cluster(args.workers, Path(tmp) / "cluster.log")
        try:
            rounds(args, tmp, address)
        finally:
            for p in procs:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()


def rounds(args, tmp: str, address: str) -> None:
    """Warm the cache, then each way of running the checks in turn, ``args.rounds`` times; the medians."""
    campaign = str(main_job_campaign(tmp))
    timed("warm-up (C cache): the campaign, 1 worker", lambda: genom2bip("campaign", campaign, "-o",
                                                                        f"{tmp}/warm", "--workers", "1"))
    totals: dict[str, list[float]] = {}
    for n in range(args.rounds):
        runs = {
            "README's 3 verify commands, one after another": lambda: [genom2bip(*c) for c in README],
            "campaign's jobs, one process, one after another": lambda: in_process(campaign),
            f"genom2bip campaign, local cluster of {args.workers}": lambda: genom2bip(
                "campaign", campaign, "-o", f"{tmp}/run{n}", "--workers", str(args.workers)),
            f"genom2bip campaign, {args.workers} workers in own sessions": lambda: genom2bip(
                "campaign", campaign, "-o", f"{tmp}/remote{n}", "--scheduler", address),
        }
        for label, fn in runs.items():
            totals.setdefault(label, []).append(timed(label, fn))
    print("median of the rounds:")
    for label, values in totals.items():
        print(f"  {label:<48} {sorted(values)[len(values) // 2]:7.1f} s")


if __name__ == "__main__":
    main()
