"""Public GenoM3 components with their own C/C++ codels, compiled and run under the generated controller.

    PYTHONPATH=. python bench/public_components.py CORPUS_DIR [-I DIR]... [--wait S] [--calls N]

CORPUS_DIR holds components (each ``.gen`` declaring one, with its ``codels/`` beside it), fetched outside the
repository (docs/codels.md names the ones tried).  For each: ``genom2bip FILE.gen -o TMP`` (the header, the
library), then the controller on a virtual clock, every service requested once with its default inputs
(zero for the inputs without one); it prints each request's final report (or that it still runs after
WAIT s of wall time), then each codel's calls and its CPU time per call as ``--codel-times`` records it.
Last, the binding's own cost: N calls of a C codel that does nothing but set one ``out`` argument, through
the same function the controller calls, against the same call of a Python codel.
"""
from __future__ import annotations

import argparse
import importlib.util
import re
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from genom2bip.back.interface import zero  # noqa: E402
from genom2bip.cli import main as genom2bip  # noqa: E402
from runtime.controller import Controller, VirtualClock  # noqa: E402
from runtime.controller.requests import RequestError  # noqa: E402
from runtime.genom import Ref  # noqa: E402


def load(directory: Path, name: str):
    spec = importlib.util.spec_from_file_location(f"bench_{name}", directory / name / "__init__.py",
                                                  submodule_search_locations=[str(directory / name)])
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def inputs_of(spec: dict, types: dict) -> dict:
    out = {}
    for p in spec["parameters"]:
        if p["direction"] in ("in", "inout"):
            out[p["name"]] = p.get("default", zero(p["schema"], types))
    return out


def run_component(gen: Path, include: list[str], wait: float) -> None:
    folder = gen.parent
    out = Path(tempfile.mkdtemp(prefix="public-"))
    argv = [str(gen), "-o", str(out)] + [x for d in include for x in ("-I", d)]
    if genom2bip(argv) != 0:
        print(f"{folder.name}: does not generate (above)")
        return
    name = next(p.name for p in out.iterdir() if p.is_dir() and not p.name.startswith("."))
    pkg = load(out, name)
    interface = pkg.INTERFACE
    c = Controller(pkg.package(), pkg.ROOT, interface, None, clock=VirtualClock(), times=True)
    print(f"{folder.name}: codels {c.codels.where}; missing: {', '.join(c.binder.missing) or 'none'}")
    c.start()
    try:
        for comp, spec in interface["components"].items():
            for svc, s in spec["services"].items():
                try:
                    req = c.submit(comp, svc, inputs_of(s, interface["types"]))
                except RequestError as err:
                    print(f"  {comp}.{svc}: refused {err.status}: {err.message}")
                    continue
                final = c.wait(req.id, timeout=wait).final
                if final is None:
                    print(f"  {comp}.{svc}: still {c.get(req.id).status} after {wait} s")
                    continue
                extra = final.get("outputs") if final["status"] == "ok" else final.get("message")
                print(f"  {comp}.{svc}: {final['status']} {extra if extra not in (None, {}) else ''}".rstrip())
    finally:
        c.stop(timeout=30)
    times = c.codel_times() or {"codels": {}}
    for codel, t in sorted(times["codels"].items()):
        if t["calls"]:
            print(f"    {codel}: {t['calls']} calls, CPU per call mean {t['cpu']['mean'] * 1e3:.1f} us, "
                  f"longest {t['cpu']['max'] * 1e3:.1f} us")


def binding_cost(calls: int) -> None:
    """Per-call cost of the ctypes binding on a codel that sets one ``out`` double, against Python."""
    out = Path(tempfile.mkdtemp(prefix="probe-"))
    (out / "probe").mkdir()
    (out / "probe" / "probe.gen").write_text(
        "component probe {\n  ids { double x; };\n  task t { period 10 ms; };\n"
        "  function Set() { codel probeSet(ids out x); };\n};\n")
    (out / "probe" / "codels").mkdir()
    (out / "probe" / "codels" / "probe.c").write_text(
        '#include "probe_c_types.h"\ngenom_event probeSet(double *x, const genom_context self)\n'
        "{ (void)self; *x = 1.0; return probe_ether; }\n")
    if genom2bip([str(out / "probe"), "-o", str(out / "gen")]) != 0:
        return
    pkg = load(out / "gen", "probe")
    c = Controller(pkg.package(), pkg.ROOT, pkg.INTERFACE, None)
    fn = c.codels.find("probe", "probeSet")

    def python(x):
        x.value = 1.0
        return "ether"

    from runtime.ccodels.isolated import IsolatedLibrary

    c_spec = pkg.INTERFACE["components"]["probe"]["c"]
    started = time.perf_counter()
    isolated = IsolatedLibrary("probe", str(Path(pkg.INTERFACE["where"]) / c_spec["library"]), c_spec)
    print(f"binding: a codels process starts in {(time.perf_counter() - started) * 1e3:.0f} ms")
    for label, f in (("C through ctypes", fn), ("C in a process of its own", isolated.get("probeSet")),
                     ("Python", python)):
        ref = Ref(0.0)
        start = time.perf_counter()
        for _ in range(calls):
            f(x=ref)
        per = (time.perf_counter() - start) / calls * 1e6
        print(f"binding: {label}: {per:.2f} us per call ({calls} calls)")
    isolated.close()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("corpus", type=Path)
    parser.add_argument("-I", dest="include", action="append", default=[])
    parser.add_argument("--wait", type=float, default=5.0, help="wall seconds to wait for each request")
    parser.add_argument("--calls", type=int, default=20000)
    args = parser.parse_args()
    gens = sorted(p for p in args.corpus.rglob("*.gen")
                  if re.search(r"^\s*component\s", p.read_text(errors="replace"), re.M))
    for gen in gens:  # the file, not its folder: a folder may hold the interfaces it includes
        run_component(gen, args.include, args.wait)
    binding_cost(args.calls)
    return 0


if __name__ == "__main__":
    sys.exit(main())
