"""What a remote call costs: the remote fixture's ``asker.Ask`` (two remote calls) against ``divider.Divide`` asked
directly, on the real clock, in the controller's process and with the codels in processes of their own.

    PYTHONPATH=. python bench/remote_calls.py [--requests 200]

Generates tests/fixtures/ccodels/remote into a temporary folder, starts its controller, sends the requests one
after the other and prints the median, 90th percentile and longest time from ``submit`` to the final report.
A figure, not a test: it depends on the machine and on what else runs on it.
"""
from __future__ import annotations

import argparse
import importlib.util
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from genom2bip.cli import main as genom2bip  # noqa: E402


def _package(out: Path):
    spec = importlib.util.spec_from_file_location("remote_bench_pkg", out / "remote" / "__init__.py",
                                                  submodule_search_locations=[str(out / "remote")])
    module = importlib.util.module_from_spec(spec)
    sys.modules["remote_bench_pkg"] = module
    spec.loader.exec_module(module)
    return module


def _times(pkg, component: str, service: str, inputs: dict, n: int, isolate: bool) -> list[float]:
    from runtime.controller import Controller

    os.environ["GENOM2BIP_CODELS_PROCESS"] = "1" if isolate else "0"
    controller = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, None)
    controller.start()
    took = []
    try:
        for _ in range(n):
            t0 = time.perf_counter()
            final = controller.wait(controller.submit(component, service, inputs).id, 60).final
            took.append(time.perf_counter() - t0)
            if final is None or final["status"] != "ok":
                raise SystemExit(f"{component}.{service} did not end ok: {final}")
    finally:
        controller.stop(timeout=30)
    return took


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--requests", type=int, default=200)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="remote-bench-") as tmp:
        if genom2bip([str(ROOT / "tests" / "fixtures" / "ccodels" / "remote"), "-o", tmp]) != 0:
            return 1
        pkg = _package(Path(tmp))
        for isolate in (False, True):
            where = "codels in their own processes" if isolate else "codels in the controller's process"
            for component, service, inputs in (("divider", "Divide", {"num": 7.0, "den": 2.0}),
                                               ("asker", "Ask", {"num": 7.0, "den": 2.0})):
                took = sorted(_times(pkg, component, service, inputs, args.requests, isolate))
                p90 = took[int(0.9 * (len(took) - 1))]
                print(f"{where}: {component}.{service}: median {statistics.median(took) * 1e3:.2f} ms, "
                      f"p90 {p90 * 1e3:.2f} ms, longest {took[-1] * 1e3:.2f} ms ({len(took)} requests)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
