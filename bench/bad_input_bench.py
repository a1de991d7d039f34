"""Peak memory of reading bad or large descriptions: a 10 MB .gen, #include "/dev/zero", and 1.5 MB of each shape.

Each input is read by ``genom2bip check`` in a child process whose peak
resident memory (``ru_maxrss`` of that child, from ``os.wait4``) is printed,
with its exit status.  Children run with their address space capped
(``--cap``, default 4096 MB) and a time cap (``--seconds``, default 300): a
child stopped by either is shown as such, with what it reached.

``--before DIR`` runs the same inputs with the code of another checkout too
(e.g. ``git archive main | tar -x -C /tmp/main``), side by side.

    python bench/bad_input_bench.py [--before DIR] [--cap MB] [--seconds S] [--only NAME]
"""
from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

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


def measure(tree: Path, gen: Path, cap_mb: int, seconds: float) -> tuple[float, str, float]:
    """(peak MB, how it ended, wall seconds) of ``genom2bip check GEN`` run with the code of ``tree``."""
    def capped() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (cap_mb * MB, cap_mb * MB))

    with tempfile.TemporaryFile() as err:
        started = time.perf_counter()
        child = subprocess.Popen([sys.executable, "-m", "genom2bip", "check", str(gen)], cwd=tree,
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
        for name, gen in inputs(Path(tmp)).items():
            if args.only and args.only not in name:
                continue
            size = gen.stat().st_size
            print(f"{name} ({size / MB:.2f} MB):", flush=True)
            for label, tree in trees:
                peak, how, wall = measure(tree, gen, args.cap, args.seconds)
                per_byte = f", {peak * MB / size:.0f} bytes per input byte" if size > MB else ""
                print(f"  {label:6} peak {peak:7.0f} MB{per_byte}, {wall:.1f} s, {how}", flush=True)


if __name__ == "__main__":
    main()
