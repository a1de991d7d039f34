"""``genom2bip campaign FILE``: every job of a campaign file on Dask workers, one JSON line each, a summary table,
a picture per numeric axis (docs/verification/campaigns.md).

Exit status: 0 every job done and every check holds, 4 a check is violated
(or meets a model error), 5 a job is inconclusive, failed, crashed or timed out, 1 bad
input (the campaign file, a model, a property file: nothing is run or
written), 130 interrupted (what is done is written; the same command runs the
rest), 141 stopped because the output was closed (``| head``: the same).
"""
from __future__ import annotations

import argparse
import os
import sys

from genom2bip.cli.verbs import (
    EXIT_CLOSED, EXIT_ERRORS, EXIT_INCONCLUSIVE, EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE, EXIT_VIOLATED, Failure, error,
    print_diagnostics, verb,
)

#: Local workers per core at most: a job keeps its core busy, so more only adds processes (10,000 of them ran out
#: of file descriptors before running a job).
WORKERS_PER_CORE = 4
#: Seconds --connect-timeout may wait at most: a day.
MAX_CONNECT_TIMEOUT = 86400.0
#: A job's answer -> the exit status it asks for.
EXITS = {"holds": EXIT_OK, "violated": EXIT_VIOLATED, "error": EXIT_VIOLATED}


def _arguments(parser: argparse.ArgumentParser) -> None:
    """FILE, the output, --set, --list, --retry-failed, and the cluster's options."""
    parser.add_argument("file", metavar="FILE", help="a campaign file (YAML): models, checks, values to vary over")
    parser.add_argument("-o", "--output", metavar="DIR",
                        help="where results.jsonl, jobs/ and the pictures go (default: out/<campaign name>); "
                             "the jobs whose results are there already are not run again")
    parser.add_argument("--set", dest="settings", metavar="NAME=VALUE", action="append", default=[],
                        help="the value of ${NAME} in the campaign file's paths (e.g. --set corpus=DIR)")
    parser.add_argument("--list", action="store_true", help="list the jobs and run nothing")
    parser.add_argument("--retry-failed", action="store_true",
                        help="run again the jobs recorded as failed or crashed (the others done are kept)")
    parser.add_argument("--json", action="store_true",
                        help="print one JSON document instead of the job lines and the table: each job with its "
                             "answer and record, the counts, the pictures, the exit status (schema: "
                             "genom2bip/cli/campaign_schema.json; docs/output.md)")
    cluster = parser.add_argument_group("the Dask cluster (default: a local one, a worker process per core)")
    cluster.add_argument("--scheduler", metavar="ADDRESS",
                         help="a running cluster's scheduler, tcp://HOST:PORT or tls://HOST:PORT")
    cluster.add_argument("--workers", type=int, metavar="N", help="local cluster: N worker processes")
    cluster.add_argument("--listen", metavar="HOST", default="127.0.0.1",
                         help="local cluster: the address its scheduler and workers listen on (default: loopback)")
    cluster.add_argument("--connect-timeout", type=float, default=30, metavar="SECONDS",
                         help="--scheduler: how long to try to reach it (default 30)")
    cluster.add_argument("--tls-ca-file", metavar="FILE", help="TLS: the certificate authority of the cluster")
    cluster.add_argument("--tls-cert", metavar="FILE", help="TLS: this client's certificate")
    cluster.add_argument("--tls-key", metavar="FILE", help="TLS: this client's private key")


def _settings(items: list[str]) -> dict[str, str]:
    out = {}
    for item in items:
        name, eq, value = item.partition("=")
        if not eq or not name.isidentifier():
            error(f"--set {item}: NAME=VALUE expected")
            raise Failure(EXIT_USAGE)
        out[name] = value
    return out


def _cluster(args: argparse.Namespace):
    """The cluster asked for (:class:`~genom2bip.campaign.cluster.ClusterSpec`); options that do not go together
    are a usage error."""
    from genom2bip.campaign.cluster import ClusterSpec

    if args.workers is not None and args.workers < 1:
        error("--workers must be >= 1")
        raise Failure(EXIT_USAGE)
    cores = os.cpu_count() or 1
    if args.workers is not None and args.workers > WORKERS_PER_CORE * cores:
        error(f"--workers {args.workers}: at most {WORKERS_PER_CORE * cores} on this machine ({WORKERS_PER_CORE} per "
              f"core, {cores} cores): each worker is a process that searches on a core of its own")
        raise Failure(EXIT_USAGE)
    if args.scheduler and (args.workers is not None or args.listen != "127.0.0.1"):
        error("--workers and --listen belong to the local cluster: drop them with --scheduler")
        raise Failure(EXIT_USAGE)
    tls = (args.tls_ca_file, args.tls_cert, args.tls_key)
    if any(tls) and not (all(tls) and args.scheduler):
        error("TLS takes --scheduler tls://HOST:PORT with --tls-ca-file, --tls-cert and --tls-key together")
        raise Failure(EXIT_USAGE)
    if not 0 < args.connect_timeout <= MAX_CONNECT_TIMEOUT:  # also refuses nan and inf
        error(f"--connect-timeout: a number of seconds above 0 and at most {MAX_CONNECT_TIMEOUT:g} (a day) expected, "
              f"got {args.connect_timeout:g}")
        raise Failure(EXIT_USAGE)
    if args.scheduler:
        _check_scheduler(args.scheduler)
    return ClusterSpec(args.scheduler, args.workers, args.listen, *tls, connect_timeout=args.connect_timeout)


def _check_scheduler(address: str) -> None:
    """A usage error unless ``address`` is [tcp://]HOST:PORT or tls://HOST:PORT, as Dask itself reads it."""
    from distributed.comm.addressing import parse_address, parse_host_port

    try:
        scheme, location = parse_address(address)  # HOST:PORT alone is tcp://, as for Dask
        if scheme not in ("tcp", "tls"):
            raise ValueError(f"the scheme is {scheme}://")
        host, port = parse_host_port(location)
        if not host or not 0 < int(port) < 65536:
            raise ValueError("a host and a port from 1 to 65535 are needed")
    except (ValueError, TypeError) as exc:
        error(f"--scheduler {address!r}: tcp://HOST:PORT or tls://HOST:PORT expected ({exc})")
        raise Failure(EXIT_USAGE) from None


@verb("campaign", help="run a campaign of checks (a YAML file) on Dask workers: JSON lines, a table, pictures",
      arguments=_arguments)
def verb_campaign(args: argparse.Namespace) -> int:
    """Read and expand the campaign (nothing runs on an error), run the jobs not done yet, report them all (or, with
    ``--json``, print one document saying it: the job lines and the table are not printed)."""
    import contextlib
    import io
    import json

    from genom2bip.campaign.document import CampaignAnswer, document
    from genom2bip.campaign.jobs import expand
    from genom2bip.campaign.spec import read_campaign

    settings, spec = _settings(args.settings), _cluster(args)
    campaign = read_campaign(args.file, settings)
    expansion = expand(campaign)
    if expansion.warnings:
        print_diagnostics(expansion.warnings, None)
    _warn_models(expansion)
    answer = CampaignAnswer(campaign.name, str(args.file), expansion.jobs)
    with contextlib.redirect_stdout(io.StringIO()) if args.json else contextlib.nullcontext():
        status = _campaign(args, spec, campaign, answer)
    if args.json:
        print(json.dumps(document(answer, status), indent=1))
    return status


def _campaign(args: argparse.Namespace, spec, campaign, answer) -> int:
    """List the jobs, or run those not done yet and report them all; ``answer`` gathers what is found."""
    from pathlib import Path

    from genom2bip.campaign.output import Output

    jobs = answer.jobs
    if args.list:
        for job in jobs:
            print(f"{job.id}  {job.title}  ({job.method})")
        print(f"{len(jobs)} jobs")
        return EXIT_OK
    directory = Path(args.output) if args.output else Path("out") / campaign.name
    Output.check(directory)  # before a cluster is started: its results could not be kept
    done = Output.peek(directory)
    todo = [j for j in jobs if j.id not in done
            or (args.retry_failed and done[j.id].get("status") != "done")]
    client = _connect(spec) if todo else None  # a scheduler out of reach: nothing written
    try:
        out = Output.open(directory)
    except BaseException:
        _close(client)
        raise
    try:
        if out.dropped:
            print(f"note: {out.dropped} line(s) of {out.results} are not job records (cut short or edited): moved, "
                  f"as they were, to {out.unreadable}; their jobs run again", file=sys.stderr if args.json else None)
        todo = [j for j in jobs if j.id not in out.records
                or (args.retry_failed and out.records[j.id].get("status") != "done")]
        print(f"campaign {campaign.name}: {len(jobs)} jobs, {len(jobs) - len(todo)} already in {out.results}, "
              f"{len(todo)} to run", flush=True)
        before = {j.id: out.records.get(j.id) for j in todo}  # a job is done in this run when its record changes
        run = _run(todo, client, out) if todo and client else None
        answer.records, answer.directory, answer.results = out.records, str(out.directory), str(out.results)
        answer.ran = {j.id for j in todo if out.records.get(j.id) is not before[j.id]}
        return _report(campaign, jobs, out, run, todo, [j for j in todo if out.records.get(j.id) is before[j.id]],
                       answer)
    finally:
        _close(client)
        out.close()


def _connect(spec):
    """``(client, cluster)`` of the cluster asked for; a scheduler out of reach is an error (exit 1)."""
    from genom2bip.campaign.cluster import connect

    try:
        return connect(spec)
    except (OSError, TimeoutError) as exc:
        error(f"cannot reach the Dask scheduler {spec.scheduler}: {exc}")
        raise Failure(EXIT_ERRORS) from None


def _close(client) -> None:
    if client is not None:
        client[0].close()
        if client[1] is not None:
            client[1].close()


def _run(todo, connection, out):
    """The jobs on the cluster, each record written as it comes."""
    from genom2bip.campaign.cluster import describe, run
    from genom2bip.campaign.report import Display
    from genom2bip.cli.pipes import output_closed

    client, cluster = connection
    display = Display(len(todo))
    try:
        print(describe(client, cluster), flush=True)
        found = run(todo, client, out.write, display, closed=lambda: output_closed(sys.stdout))
        found.where = describe(client, cluster)
        return found
    finally:
        display.close()


def _report(campaign, jobs, out, run, todo, undone, answer) -> int:
    """The summary table, the pictures, what a stop left undone; the exit status.  ``answer`` gathers the same for
    ``--json``.

    ``undone``: the jobs of ``todo`` whose record did not change (counted from the records, as the table is,
    so that the job taken from the cluster when Ctrl-C came is counted and listed too).
    """
    from genom2bip.campaign.pictures import draw
    from genom2bip.campaign.report import summary, values_table

    print()
    counts = summary(jobs, out.records)
    values_table(jobs, out.records)
    if run is not None:
        busy = sum(r.get("seconds") or 0 for r in run.written)
        cpu = sum(r.get("cpu_seconds") or 0 for r in run.written)
        print(f"{len(run.written)} jobs run in {run.seconds:.1f} s of wall clock ({busy:.1f} s of job time, "
              f"{cpu:.1f} s of CPU)")
        answer.run = {"cluster": run.where, "jobs_run": len(run.written), "wall_s": round(run.seconds, 3),
                      "job_s": round(busy, 3), "cpu_s": round(cpu, 3)}
    for path in draw(jobs, out.records, out.directory):
        print(f"picture: {path}")
        answer.pictures.append(str(path))
    print(f"results: {out.results}")
    if run is not None and (run.interrupted or run.closed):
        answer.stopped = "interrupted" if run.interrupted else "closed"
        answer.undone = [j.id for j in sorted(undone, key=lambda j: j.index)]
        ran = len(todo) - len(undone)
        why = "interrupted" if run.interrupted else "stopped: the output was closed (nobody reads the rest)"
        print(f"{why}: {ran} jobs done in this run and written; {len(undone)} not done:", file=sys.stderr)
        running = set(run.running)
        undone = sorted(undone, key=lambda j: j.id not in running)  # those under way first: never cut off the list
        for job in undone[:10]:
            print(f"  {job.title}" + ("  (was running: stopped)" if job.id in running else ""), file=sys.stderr)
        if len(undone) > 10:
            print(f"  … and {len(undone) - 10} more", file=sys.stderr)
        print(f"run the same command again to run them (the {len(out.records)} results written are kept)",
              file=sys.stderr)
        return EXIT_INTERRUPTED if run.interrupted else EXIT_CLOSED
    return max((EXITS.get(word, EXIT_INCONCLUSIVE) for word in counts), default=EXIT_OK)


def _warn_models(expansion) -> None:
    """The warnings of the models built to name the jobs (codels without WCET), once per model."""
    from genom2bip.verify.model import untimed_codels

    seen = set()
    for model in expansion.built.values():
        if model is None:
            continue
        for group in model.warnings:
            print_diagnostics(group.diagnostics, group.sources)
        default, codels = untimed_codels(model.package)
        if codels and model.title not in seen:
            seen.add(model.title)
            print(f"genom2bip: warning: {model.title}: codels without wcet take {default / 1000:g} ms: "
                  f"{', '.join(codels)}", file=sys.stderr)
