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
   until every one has its final report.
"""
from __future__ import annotations

import argparse
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


def http_rate(requests: int, clients: int) -> tuple[float, float]:
    import dala
    from runtime.services.client import Client
    from runtime.services.server import ServiceServer

    package = dala.package()
    controller = Controller(package, dala.ROOT, dala.INTERFACE, noop_codels(package, dala.INTERFACE))
    controller.start()
    server = ServiceServer(controller).start()
    targets = [("NDD", "SetSpeed"), ("NDD", "SetParams"), ("Aspect", "SetParams"), ("LaserRF", "SetConfig"),
               ("RFLEX", "SetAcceleration")]
    try:
        one = Client(server.url)
        t = time.perf_counter()
        for i in range(200):
            one.call(*targets[i % len(targets)])
        sequential = 200 / (time.perf_counter() - t)
        ids: list[int] = []
        lock = threading.Lock()

        def send(k: int) -> None:
            client = Client(server.url)
            mine = [client.send(*targets[(k + i) % len(targets)]) for i in range(requests // clients)]
            for rid in mine:
                client.wait(rid, timeout=60)
            with lock:
                ids.extend(mine)

        t = time.perf_counter()
        threads = [threading.Thread(target=send, args=(k,)) for k in range(clients)]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        concurrent = len(ids) / (time.perf_counter() - t)
        assert all(controller.requests[i].final is not None for i in ids)
    finally:
        server.stop()
        controller.stop()
    return sequential, concurrent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=10.0, help="real time of the jitter measure (default 10)")
    ap.add_argument("--steps", type=int, default=20_000, help="engine steps (default 20000)")
    ap.add_argument("--requests", type=int, default=2000, help="requests through HTTP (default 2000)")
    ap.add_argument("--clients", type=int, default=8, help="concurrent HTTP clients (default 8)")
    args = ap.parse_args()
    bare, loop = engine_steps(args.steps)
    print(f"engine steps/s, DALA, no-op codels: {bare:,.0f} (enabled+fire), {loop:,.0f} (run-time loop, "
          f"virtual clock)")
    stats = jitter(args.seconds)
    lat = stats["lateness_ms"]
    print(f"period jitter, 10 ms task over {args.seconds:g} s ({stats['periods']} periods): "
          f"p50 {lat['p50']:.3f} ms, p99 {lat['p99']:.3f} ms, max {lat['max']:.3f} ms late; "
          f"{stats['overruns']} overruns, {stats['missed']} missed")
    sequential, concurrent = http_rate(args.requests, args.clients)
    print(f"requests/s through HTTP (send + final report): {sequential:,.0f} (one client, one at a time), "
          f"{concurrent:,.0f} ({args.clients} clients, {args.requests} requests)")


if __name__ == "__main__":
    main()
