"""Peak memory and time of bad or hostile inputs: descriptions (a 10 MB .gen, #include "/dev/zero", 1.5 MB of each
shape), then campaign, mission and world files that are devices, a sweep of 10^8 jobs, servers that lie to
``genom2bip call`` and to ``campaign --scheduler``.

Each probe runs genom2bip in a child process whose peak resident memory
(``ru_maxrss`` of that child, from ``os.wait4``) and wall time are printed,
with its exit status.  The lying servers run in this process, on 127.0.0.1.
Children run with their address space capped (``--cap``, default 4096 MB) and a time cap (``--seconds``, default 300): a
child stopped by either is shown as such, with what it reached.

``--before DIR`` runs the same inputs with the code of another checkout too
(e.g. ``git archive main | tar -x -C /tmp/main``), side by side.

    python bench/bad_input_bench.py [--before DIR] [--cap MB] [--seconds S] [--only NAME]
"""
from __future__ import annotations

import argparse
import os
import resource
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))

from parse_bench import genom3_text  # noqa: E402

MB = 1024 * 1024
MINIMAL = "component c {\n  ids { long n; };\n};\n"


def inputs(directory: Path) -> dict[str, Path]:
    """name -> description file, each written into ``directory``."""
    out = {}

    def write(name: str, text: str) -> None:
        out[name] = directory / f"input{len(out)}.gen"
        out[name].write_text(text)

    write("10 MB .gen (a comment)", "/*\n" + ("x" * 79 + "\n") * (10 * MB // 80) + "*/\n" + MINIMAL)
    write('#include "/dev/zero"', '#include "/dev/zero"\n' + MINIMAL)
    n = 3 * MB // 2
    write("1.5 MB comment", "/*\n" + ("x" * 79 + "\n") * (n // 80) + "*/\n" + MINIMAL)
    write("1.5 MB doc string", 'component c {\n  doc "' + "y" * n + '";\n  ids { long n; };\n};\n')
    write("1.5 MB constants", "".join(f"const long c{i} = {i};\n" for i in range(n // 24)) + MINIMAL)
    services, text = 100, ""
    while len(text) < n:
        services *= 2
        text = genom3_text(services)
    write(f"{len(text) / MB:.1f} MB component ({services} services)", text)
    write("macro doubling 40 times", "#define A0 x\n" + "".join(f"#define A{i} A{i - 1} A{i - 1}\n"
                                                             for i in range(1, 41)) + "const long k = A40;\n" + MINIMAL)
    return out


@dataclass
class Probe:
    """One hostile input: the genom2bip arguments (``{port}`` filled with the server's), the server's answer if any."""

    name: str
    argv: list[str]
    reply: bytes | Callable[[socket.socket], None] | None = None
    size: int = 0  # bytes of the input file, when there is one


class Server:
    """A TCP server on 127.0.0.1 answering each connection with ``reply`` until closed (at most 100 connections)."""

    def __init__(self, reply) -> None:
        self.reply = reply
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        for _ in range(100):
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            with conn:
                try:
                    self.reply(conn) if callable(self.reply) else conn.sendall(self.reply)
                    conn.shutdown(socket.SHUT_WR)
                    while conn.recv(65536):
                        pass
                except OSError:
                    pass

    def close(self) -> None:
        try:
            self.sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self.sock.close()
        self.thread.join()


def _endless(conn: socket.socket) -> None:
    conn.sendall(b"HTTP/1.1 200 OK\r\nContent-Type: application/json\r\nConnection: close\r\n\r\n[")
    while True:
        conn.sendall(b"1," * 32768)


def _http(body: bytes) -> bytes:
    return f"HTTP/1.1 200 OK\r\nContent-Length: {len(body)}\r\n\r\n".encode() + body


def probes(directory: Path) -> list[Probe]:
    """Every probe: the descriptions checked, then the other surfaces, their files written into ``directory``."""
    out = [Probe(name, ["check", str(gen)], size=gen.stat().st_size) for name, gen in inputs(directory).items()]
    sensing = ROOT / "descriptions" / "dala" / "missions" / "sensing.yaml"
    campaign = ROOT / "descriptions" / "dala" / "campaign.yaml"
    sweep = directory / "sweep.yaml"
    axes = [", ".join(f"{i} us" for i in range(1000)), ", ".join(f"{1 + i / 100000}" for i in range(1000)),
            ", ".join(str(i) for i in range(100))]
    sweep.write_text(f"campaign: sweep\nmodels:\n  ndd: {{paths: [{ROOT / 'descriptions' / 'dala' / 'NDD.gen'}], "
                     f"no-rules: true, timed: true}}\nvary:\n  default-wcet: [{axes[0]}]\n  wcet-scale: [{axes[1]}]\n"
                     f"  define.UNUSED: [{axes[2]}]\nchecks:\n  - check: observer\n    model: ndd\n"
                     "    kinds: [overrun]\n")
    out += [
        Probe("campaign /dev/zero", ["campaign", "/dev/zero", "-o", str(directory / "c0")]),
        Probe("mission /dev/zero", ["mission", "/dev/zero", "--out", str(directory / "m0"), "--quiet"]),
        Probe("mission --world /dev/zero", ["mission", str(sensing), "--world", "/dev/zero", "--out",
                                            str(directory / "m1"), "--quiet"]),
        Probe("campaign sweep of 10^8 jobs --list", ["campaign", str(sweep), "--list"], size=sweep.stat().st_size),
        Probe("call: endless body", ["call", "http://127.0.0.1:{port}"], _endless),
        Probe("call: 200,000 nested [", ["call", "http://127.0.0.1:{port}"], _http(b"[" * 200_000)),
        Probe("call: not HTTP", ["call", "http://127.0.0.1:{port}"], b"SSH-2.0-OpenSSH_9.6\r\n"),
        Probe("--scheduler announcing 3.5 EB", ["campaign", str(campaign), "-o", str(directory / "c1"), "--scheduler",
                                                "tcp://127.0.0.1:{port}", "--connect-timeout", "10"],
              struct.pack("<Q", 3 << 60) + bytes(64)),
    ]
    return out


def measure(tree: Path, argv: list[str], cap_mb: int, seconds: float) -> tuple[float, str, float]:
    """(peak MB, how it ended, wall seconds) of ``genom2bip ARGV`` run with the code of ``tree``."""
    def capped() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (cap_mb * MB, cap_mb * MB))

    with tempfile.TemporaryFile() as err:
        started = time.perf_counter()
        child = subprocess.Popen([sys.executable, "-m", "genom2bip", *argv], cwd=tree,
                                 stdout=subprocess.DEVNULL, stderr=err, stdin=subprocess.DEVNULL,
                                 preexec_fn=capped, env={**os.environ, "PYTHONPATH": str(tree)})
        stopped = threading.Event()
        timer = threading.Timer(seconds, lambda: (stopped.set(), child.kill()))
        timer.start()
        try:
            _, status, usage = os.wait4(child.pid, 0)
        finally:
            timer.cancel()
        child.returncode = code = os.waitstatus_to_exitcode(status)
        wall = time.perf_counter() - started
        err.seek(0)
        text = err.read().decode("utf-8", "replace")
    if stopped.is_set():
        how = f"did not finish in {seconds:g} s"
    elif "MemoryError" in text:
        how = f"ran out of the {cap_mb} MB cap"
    else:
        first = next((line for line in text.splitlines() if "error" in line), "")
        how = f"exit {code}" + (f": {first.split('error: ', 1)[-1][:60]}" if first else "")
    return usage.ru_maxrss / 1024, how, wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", metavar="DIR", help="a checkout of the code to compare with (e.g. main)")
    parser.add_argument("--cap", type=int, default=4096, metavar="MB", help="address space of each child")
    parser.add_argument("--seconds", type=float, default=300, help="time cap of each child")
    parser.add_argument("--only", metavar="NAME", help="only the inputs whose name contains NAME")
    args = parser.parse_args()
    trees = ([("before", Path(args.before).resolve())] if args.before else []) + [("after", ROOT)]
    with tempfile.TemporaryDirectory() as tmp:
        for probe in probes(Path(tmp)):
            if args.only and args.only not in probe.name:
                continue
            size = probe.size
            print(f"{probe.name}" + (f" ({size / MB:.2f} MB)" if size else "") + ":", flush=True)
            for label, tree in trees:
                server = Server(probe.reply) if probe.reply is not None else None
                try:
                    argv = [a.replace("{port}", str(server.port)) if server else a for a in probe.argv]
                    peak, how, wall = measure(tree, argv, args.cap, args.seconds)
                finally:
                    if server is not None:
                        server.close()
                per_byte = f", {peak * MB / size:.0f} bytes per input byte" if size > MB else ""
                print(f"  {label:6} peak {peak:7.0f} MB{per_byte}, {wall:.1f} s, {how}", flush=True)

if __name__ == "__main__":
    main()
