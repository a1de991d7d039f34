"""Run-time figures of the generated controller: engine steps per second, period jitter, HTTP requests per second.

    python bench/runtime_bench.py [--seconds 10] [--requests 2000] [--clients 8]

1. Engine steps per second on the DALA model with no-op Python codels (each
   returns its first yield) called through the codel binding: the bare engine
   (``Engine.run``, any request at any time) and the whole run-time loop
   (timers, choice, reports) on a virtual clock that jumps to the next deadline.
2. Period jitter of a 10 ms task (tests/fixtures/genom3/counter.gen) over
   ``--seconds`` of real time: how late each period starts after its
   deadline, p50 / p99 / max.
3. Requests per second through the HTTP interface: ``--requests`` requests to
   DALA attributes from ``--clients`` threads, each with its own connection,
   until every one has its final report; the p99 latency of a request (POST
   sent to final report, from the reports' times) and what the flood cost
   RFLEX.servo, the 25 ms task: periods missed, overruns, worst lateness, and
   where the lateness of its late periods went (engine CPU, waiting for a
   core, blocked on the interpreter or a lock; full collections).
"""
from __future__ import annotations

import argparse
import math
import multiprocessing
import os
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "gen"))

from runtime.codels import any_request, codel_specs  # noqa: E402
from runtime.controller import Controller, VirtualClock  # noqa: E402
from runtime.engine import Engine, RandomPolicy  # noqa: E402


def noop_codels(package, interface) -> dict:
    """Every codel of every component, returning its first yield (validate codels: nothing, i.e. ok)."""
    out: dict[str, dict] = {c: {} for c in interface["components"]}
    for extern, spec in codel_specs(package).items():
        component = next(c for c, x in interface["components"].items() if extern.startswith(x["instance"] + "_"))
        first = spec.yields[0] if spec.yields and spec.yields != ("ok",) else None
        out[component][spec.codel] = lambda _first=first, **kw: _first
    return out


def engine_steps(steps: int) -> tuple[float, float]:
    import dala

    package = dala.package()
    controller = Controller(package, dala.ROOT, dala.INTERFACE, noop_codels(package, dala.INTERFACE),
                            clock=VirtualClock())
    externs = dict(controller.binder.externs())
    externs.update(any_request())
    engine = Engine(package, dala.ROOT, externs)
    t = time.perf_counter()
    summary = engine.run(RandomPolicy(1), limit=steps)
    bare = summary.steps / (time.perf_counter() - t)
    t = time.perf_counter()
    controller.run(limit=steps)
    loop = controller.steps / (time.perf_counter() - t)
    return bare, loop


def jitter(seconds: float) -> dict:
    from genom2bip.back.interface import interface_data
    from genom2bip.generate import model_of
    from genom2bip.parser import parse_paths

    source = ROOT / "tests" / "fixtures" / "genom3" / "counter.gen"
    description = parse_paths([source])
    package, root, _ = model_of(description, "counter")
    interface = interface_data(description, "counter", str(source))
    codels = {"counter": {"clock_init": lambda **kw: "count", "clock_count": lambda **kw: "pause::count",
                          "clock_idle": lambda **kw: "pause::count", "clock_stop": lambda **kw: "ether"}}
    controller = Controller(package, root, interface, codels)
    controller.run(duration=seconds)
    return controller.timers.stats()[0]


def _pct(values: list[float], q: float) -> float:
    values = sorted(values)
    return values[min(len(values) - 1, int(q * len(values)))] if values else float("nan")


def _flood(url: str, requests: int, clients: int, targets: list, out=None) -> tuple[list[int], list[float]]:
    """``clients`` threads each send their share of ``requests``, then wait for every final report."""
    from runtime.services.client import Client, ServiceError

    ids: list[int] = []
    posts: list[float] = []
    lock = threading.Lock()

    def send(k: int) -> None:
        client = Client(url)
        mine, took = [], []
        for i in range(requests // clients):
            t0 = time.perf_counter()
            while True:
                try:
                    mine.append(client.send(*targets[(k + i) % len(targets)]))
                    break
                except ServiceError as err:  # 429: too many waiting, send it again a little later
                    if err.status != 429:
                        raise
                    time.sleep(0.05)
            took.append(time.perf_counter() - t0)
        for rid in mine:
            client.wait(rid, timeout=60)
        with lock:
            ids.extend(mine)
            posts.extend(took)

    threads = [threading.Thread(target=send, args=(k,)) for k in range(clients)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    if out is not None:
        out.put((ids, posts))
    return ids, posts


def http_rate(requests: int, clients: int, apart: bool = False) -> dict:
    """The flood; ``apart``: the clients in a process of their own, as a decisional layer would be."""
    import dala
    from runtime.services.client import Client
    from runtime.services.server import ServiceServer

    package = dala.package()
    controller = Controller(package, dala.ROOT, dala.INTERFACE, noop_codels(package, dala.INTERFACE))
    server = ServiceServer(controller)  # built first, as `run` does
    controller.start()
    server.start()
    where = _Whereabouts(controller)
    targets = [("NDD", "SetSpeed"), ("NDD", "SetParams"), ("Aspect", "SetParams"), ("LaserRF", "SetConfig"),
               ("RFLEX", "SetAcceleration")]
    try:
        one = Client(server.url)
        t = time.perf_counter()
        for i in range(200):
            one.call(*targets[i % len(targets)])
        sequential = 200 / (time.perf_counter() - t)
        servo = next(t for t in controller.timers.timers if t.task == "RFLEX.servo")
        before = (servo.periods, servo.missed, servo.overruns)
        where.since = time.monotonic()
        t = time.perf_counter()
        if apart:
            ctx = multiprocessing.get_context("fork")
            out = ctx.Queue()
            child = ctx.Process(target=_flood, args=(server.url, requests, clients, targets, out))
            child.start()
            ids, posts = out.get(timeout=600)
            child.join()
        else:
            ids, posts = _flood(server.url, requests, clients, targets)
        concurrent = len(ids) / (time.perf_counter() - t)
        assert all(controller.requests[i].final is not None for i in ids)
        late = list(servo.lateness)[before[0]:servo.periods]
        latency = [controller.requests[i].final["time"] - controller.requests[i].reports[0]["time"] for i in ids]
        return {"sequential": sequential, "concurrent": concurrent, "p50_ms": _pct(latency, 0.5) * 1e3,
                "p99_ms": _pct(latency, 0.99) * 1e3,
                "post_p99_ms": _pct(posts, 0.99) * 1e3, "periods": servo.periods - before[0],
                "missed": servo.missed - before[1], "overruns": servo.overruns - before[2],
                "late_max_ms": max(late, default=0.0) * 1e3, "where": where.late(servo.task, 0.005)}
    finally:
        where.close()
        server.stop()
        controller.stop()


def _schedstat() -> tuple[float, float, float]:
    """(now, CPU time, time spent waiting for a CPU) of the calling thread, in s (Linux; zeros elsewhere)."""
    try:
        with open("/proc/thread-self/schedstat") as f:
            cpu, queued, _ = f.read().split()
        return time.monotonic(), int(cpu) / 1e9, int(queued) / 1e9
    except OSError:
        return time.monotonic(), 0.0, 0.0


class _SampledCondition:
    """The engine's condition, sampling the thread's counters when its wait returns (it no longer sleeps)."""

    def __init__(self, condition, samples: list) -> None:
        self._condition, self._samples = condition, samples

    def wait(self, timeout=None):
        woken = self._condition.wait(timeout)
        self._samples.append((*_schedstat(), False))
        return woken

    def __getattr__(self, name):
        return getattr(self._condition, name)


class _Whereabouts:
    """Where a late period's lateness went: the engine thread's CPU, its wait for a CPU, the rest blocked.

    Samples the engine thread's scheduler counters each time it goes to sleep,
    wakes up and starts a period.  From the last sample before a deadline to the
    period's start, the time is CPU (the engine's own work: steps, codels),
    run queue (a runnable thread waiting for a core) or blocked (waiting for
    the interpreter lock or the controller's lock), less what was slept before
    the deadline; when the thread did not sleep in between, the lateness takes
    each one's share of the interval.  Full collections are timed too.
    """

    def __init__(self, controller) -> None:
        import gc

        self.samples: list[tuple[float, float, float, bool]] = []  # (..., the thread then slept)
        self.opens: list[tuple[str, float, tuple[float, float, float]]] = []
        self.collections: list[float] = []
        self.since = math.inf  # set when the flood starts: what came before is left out
        choose, timers = controller._choose, controller.timers

        def sampled_choose(now):
            chosen = choose(now)
            if chosen[0] is None:  # the engine thread is about to sleep: sampling here costs the steps nothing
                self.samples.append((*_schedstat(), True))
            return chosen

        controller._choose = sampled_choose
        controller._wake = _SampledCondition(controller._wake, self.samples)
        for timer in timers.timers:
            opened = timer.open

            def sampled_open(now, _timer=timer, _open=opened):
                sample = _schedstat()
                self.opens.append((_timer.task, _timer.deadline, sample))
                self.samples.append((*sample, False))
                _open(now)

            timer.open = sampled_open
        self._gc_start = 0.0

        def collected(phase, info):
            if info["generation"] == 2:
                if phase == "start" and time.monotonic() >= self.since:
                    self._gc_start = time.monotonic()
                elif phase == "stop" and self._gc_start:
                    self.collections.append(time.monotonic() - self._gc_start)
                    self._gc_start = 0.0

        self._callback = collected
        gc.callbacks.append(collected)

    def close(self) -> None:
        import gc

        if self._callback in gc.callbacks:
            gc.callbacks.remove(self._callback)

    def late(self, task: str, over: float) -> dict:
        """Sums over the periods of ``task`` that started more than ``over`` s late (ms)."""
        import bisect

        times = [s[0] for s in self.samples]
        out = {"periods": 0, "cpu_ms": 0.0, "run_queue_ms": 0.0, "blocked_ms": 0.0, "run_queue_max_ms": 0.0,
               "blocked_max_ms": 0.0,
               "full_collections": len(self.collections), "collection_max_ms": max(self.collections, default=0) * 1e3}
        for name, deadline, (t1, cpu1, queued1) in self.opens:
            i = bisect.bisect_right(times, deadline) - 1
            if name != task or deadline < self.since or t1 - deadline <= over or i < 0:
                continue
            t0, cpu0, queued0, slept = self.samples[i]
            cpu, queued = cpu1 - cpu0, queued1 - queued0
            blocked = max(0.0, (t1 - t0) - cpu - queued - (max(0.0, deadline - t0) if slept else 0.0))
            if not slept:  # busy since an earlier period start: the lateness takes each share of the interval
                share = (t1 - deadline) / max(t1 - t0, 1e-9)
                cpu, queued, blocked = cpu * share, queued * share, blocked * share
            out["periods"] += 1
            out["cpu_ms"] += cpu * 1e3
            out["run_queue_ms"] += queued * 1e3
            out["blocked_ms"] += blocked * 1e3
            out["run_queue_max_ms"] = max(out["run_queue_max_ms"], queued * 1e3)
            out["blocked_max_ms"] = max(out["blocked_max_ms"], blocked * 1e3)
        return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=10.0, help="real time of the jitter measure (default 10)")
    ap.add_argument("--steps", type=int, default=20_000, help="engine steps (default 20000)")
    ap.add_argument("--requests", type=int, default=2000, help="requests through HTTP (default 2000)")
    ap.add_argument("--clients", type=int, default=8, help="concurrent HTTP clients (default 8)")
    ap.add_argument("--only-http", action="store_true", help="only the HTTP flood (part 3)")
    args = ap.parse_args()
    if args.only_http:
        return report_flood(args)
    bare, loop = engine_steps(args.steps)
    print(f"engine steps/s, DALA, no-op codels: {bare:,.0f} (enabled+fire), {loop:,.0f} (run-time loop, "
          f"virtual clock)")
    stats = jitter(args.seconds)
    lat = stats["lateness_ms"]
    print(f"period jitter, 10 ms task over {args.seconds:g} s ({stats['periods']} periods): "
          f"p50 {lat['p50']:.3f} ms, p99 {lat['p99']:.3f} ms, max {lat['max']:.3f} ms late; "
          f"{stats['overruns']} overruns, {stats['missed']} missed")
    report_flood(args)


def report_flood(args) -> None:
    for apart in (False, True):
        flood = http_rate(args.requests, args.clients, apart)
        print(f"clients {'in another process' if apart else 'in the same process (threads)'}:")
        _print_flood(args, flood)


def _print_flood(args, flood: dict) -> None:
    print(f"requests/s through HTTP (send + final report): {flood['sequential']:,.0f} (one client, one at a time), "
          f"{flood['concurrent']:,.0f} ({args.clients} clients, {args.requests} requests)")
    print(f"during the flood: latency queued->final p50 {flood['p50_ms']:.1f} ms, p99 {flood['p99_ms']:.1f} ms, "
          f"POST answered p99 {flood['post_p99_ms']:.1f} ms; "
          f"RFLEX.servo (25 ms): {flood['periods']} periods, {flood['missed']} missed, {flood['overruns']} overruns, "
          f"max lateness {flood['late_max_ms']:.1f} ms")
    w = flood["where"]
    print(f"  where the lateness went ({w['periods']} periods over 5 ms late): engine CPU {w['cpu_ms']:.0f} ms, "
          f"waiting for a core {w['run_queue_ms']:.0f} ms (at most {w['run_queue_max_ms']:.1f} in one period), "
          f"blocked on the interpreter or the controller's lock {w['blocked_ms']:.0f} ms (at most "
          f"{w['blocked_max_ms']:.1f}); {w['full_collections']} full collections, longest "
          f"{w['collection_max_ms']:.1f} ms; load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
