"""What the running controller loses and how late its 25 ms task gets under a flood, slow clients and signals.

    python bench/reliability_bench.py [--requests 2000] [--clients 8] [--subscribers 200] [--only NAME ...]

Each scenario starts ``python -m dala run`` (gen/dala) with DALA's real codels and the ir-sim world in a
process of its own, brings the modules up (LaserRF acquiring, Aspect mapping, POM fusing, RFLEX tracking),
then floods it with ``--requests`` requests from ``--clients`` clients (tests/reliability/flood.py: one in
two waits for its answer, the others are long-polled, /events is read all along) and prints:

* requests lost, and final reports missing on each channel (the answer, long polls, /events, the console),
  after a stop at the end of the flood, and with SIGINT or SIGTERM sent in the middle of it;
* RFLEX.servo's missed and overrun periods during the flood (the controller's own counters, GET /tasks),
  with ``--subscribers`` event-stream clients that never read, with as many that stop reading and then
  disconnect, and with a stdout nobody reads (filled first by 3,000 report lines; a controller whose
  engine then makes no step in 2 s is reported FROZE);
* the periods missed while the controller started (the world loading).
"""
from __future__ import annotations

import argparse
import re
import signal
import socket
import statistics
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests"), str(ROOT / "tests" / "reliability")]

from controlproc import ControllerProcess  # noqa: E402
from flood import Flood  # noqa: E402

SERVO = "RFLEX.servo"


def modules_up(client) -> None:
    """The modules running their permanent activities, as during a navigation (without a GoTo)."""
    from runkit import navigation_ready, ndd_settings

    navigation_ready(client)
    ndd_settings(client)


def servo(client) -> dict:
    return next(t for t in client.tasks() if t["task"] == SERVO)


def idle_subscribers(port: int, n: int, disconnect: bool) -> list[socket.socket]:
    """``n`` event-stream clients that never read (small receive buffers); closed at once when ``disconnect``."""
    socks = []
    for _ in range(n):
        s = socket.socket()
        s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        s.connect(("127.0.0.1", port))
        s.sendall(b"GET /events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
        socks.append(s)
    return socks


def filled(ctl, client, clients: int) -> bool:
    """Fill the unread stdout (3,000 report lines and more): whether the engine still steps afterwards."""
    fill = Flood(ctl.url, 3000, clients, wait_every=1, answer_wait=5, timeout=30)
    fill.run()
    fill.close()
    try:
        steps = client.info()["steps"]
        time.sleep(2.0)
        return client.info()["steps"] > steps
    except OSError:  # the server does not answer either (it waits for the engine's lock)
        return False


def index_p50(client, n: int = 40) -> float:
    """Median time of ``GET /`` (ms)."""
    times = []
    for _ in range(n):
        t = time.perf_counter()
        client.info()
        times.append((time.perf_counter() - t) * 1e3)
    return statistics.median(times)


def scenario(name: str, args, sig: int | None = None, subscribers: str | None = None,
             read_stdout: bool = True) -> str:
    """One controller, one flood: the line of figures it gives."""
    with ControllerProcess(read_stdout=read_stdout) as ctl:
        ctl.wait_ready()
        client = ctl.client(timeout=10)
        startup = servo(client)
        modules_up(client)
        port = int(ctl.url.rsplit(":", 1)[1])
        socks = []
        if subscribers:
            socks = idle_subscribers(port, args.subscribers, disconnect=subscribers == "gone")
            time.sleep(2.0)  # let their socket buffers fill with events (they stop reading from now on)
            if subscribers == "gone":
                for s in socks:
                    s.close()
                socks = []
        extra = ""
        if not read_stdout and not filled(ctl, client, args.clients):
            end = ctl.stop(timeout=120)
            return (f"{name}: FROZE once stdout was full: the engine made no step in 2 s; exit {end.status}, "
                    f"{end.err.count('Traceback')} tracebacks")
        first = client.requests(limit=1)[0]["id"] + 1
        flood = Flood(ctl.url, args.requests, args.clients, wait_every=args.wait_every, first_id=first,
                      on_accepted=(args.requests // 2, lambda: ctl.send_signal(sig)) if sig else None, timeout=60)
        flood.start_listening()
        before = servo(client) if sig is None else None
        t0 = time.perf_counter()
        froze = False
        runner = threading.Thread(target=flood.run, daemon=True)
        runner.start()
        runner.join(120)
        froze = runner.is_alive()
        took = time.perf_counter() - t0
        if sig is None and not froze:
            after = servo(client)
            extra = (f"; {SERVO}: missed {after['missed'] - before['missed']}, "
                     f"overruns {after['overruns'] - before['overruns']} of {after['periods'] - before['periods']} "
                     f"periods, worst lateness {after['lateness_ms']['max']} ms")
            if subscribers:
                extra += f"; GET / p50 {index_p50(client):.1f} ms"
        end = ctl.stop(sig or signal.SIGINT, timeout=60) if sig is None else ctl.stop(sig, timeout=60,
                                                                                     signal_sent=True)
        for s in socks:
            s.close()
        flood.join_listener(10)
        missing = flood.missing(end.out)
        dropped = re.search(r"; (\d+) output lines dropped", end.out)
        if dropped:
            extra += f"; console lines dropped (counted): {dropped.group(1)}"
        tracebacks = end.err.count("Traceback")
        rate = missing.accepted / took if took else 0.0
        return (f"{name}: {'FROZE; ' if froze else ''}{missing.line()}; {rate:.0f} requests/s{extra}; "
                f"exit {end.status}, {tracebacks} tracebacks; at start: {SERVO} missed {startup['missed']} "
                f"and overran {startup['overruns']} of {startup['periods']} periods")


SCENARIOS = {
    "flood": {},
    "sigint": {"sig": signal.SIGINT},
    "sigterm": {"sig": signal.SIGTERM},
    "idle-subscribers": {"subscribers": "idle"},
    "gone-subscribers": {"subscribers": "gone"},
    "stalled-stdout": {"read_stdout": False},
}


def main() -> None:
    """Run the scenarios asked for, one line of figures each."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--requests", type=int, default=2000)
    ap.add_argument("--clients", type=int, default=8)
    ap.add_argument("--subscribers", type=int, default=200)
    ap.add_argument("--wait-every", type=int, default=4, help="one request in N waits for its answer (default 4)")
    ap.add_argument("--only", nargs="*", choices=list(SCENARIOS), help="run these scenarios only")
    args = ap.parse_args()
    for name in args.only or SCENARIOS:
        try:
            print(scenario(name, args, **SCENARIOS[name]), flush=True)
        except Exception as err:  # noqa: BLE001 - a scenario that breaks is a figure too
            print(f"{name}: failed: {type(err).__name__}: {err}", flush=True)


if __name__ == "__main__":
    main()
