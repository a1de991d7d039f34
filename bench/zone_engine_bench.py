"""The zone engine's speed: the C search beside the Python reference on the same models, in the same run.

Run ``python bench/zone_engine_bench.py [--states N] [--repeat R] [--full] [--reduce] [--robnav ARTEFACT_DIR]``.

Both searches store the same nodes in the same order (tests/test_zone_engine_c.py), so the first N symbolic
states of one are those of the other: each model is searched by both up to ``--states`` (default 20,000)
and the figures are printed side by side with their ratio.  ``--full`` then searches each model to the end
with the C engine alone (states, seconds, memory by kind).  Models:

* DALA's sensing half on one core (the README's response-time check: RFLEX, LaserRF, POM, the sensing mission);
* whole DALA, the five modules with their rules and the corridor mission as client, on one core and on two;
* RobNav at 4 cores, with ``--robnav DIR`` (the public schedulability artefact, as bench/robnav_bench.py reads it).

Times are the search alone (the model built and its step compiled beforehand), wall clock; with ``--repeat R``, the
fastest of R searches of each kind (on a shared machine one run can take twice as long as the next).  The C search
is timed twice: with the model's step built at -O0, what a first search steps with, and at -O2, what a search past
50,000 nodes takes over and later runs find in the cache (runtime/zones/csearch.py, OPTIMISE_AFTER); the Python
search steps at -O0.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from genom2bip.loading import TimeSettings  # noqa: E402
from genom2bip.verify.model import build_model  # noqa: E402
from genom2bip.verify.options import SearchOptions  # noqa: E402
from runtime.zones.search import ZoneExplorer  # noqa: E402

DALA = ROOT / "descriptions" / "dala"


def dala_models():
    sensing = [DALA / f"{m}.gen" for m in ("RFLEX", "LaserRF", "POM")]
    yield "DALA sensing, 1 core", lambda: build_model(
        sensing, time=TimeSettings(platform=DALA / "platforms/one-core.yaml", client=DALA / "missions/sensing.yaml",
                                   responses=True))
    for name, plat in (("1 core", "one-core"), ("2 cores", "two-cores")):
        yield f"whole DALA, {name}", lambda plat=plat: build_model(
            [DALA], time=TimeSettings(platform=DALA / f"platforms/{plat}.yaml", client=DALA / "missions/corridor.yaml",
                                      responses=True))


def robnav_model(artefact: Path):
    import robnav_bench as rb
    from genom2bip.parser import parse_paths

    paths = [str(artefact / c / f"{c}.gen") for c in rb.COMPONENTS]
    description = parse_paths(paths, [str(artefact)])
    execution, offsets, requests, ready = rb.read_artefact((artefact / "robnav-artefact-edf.xta").read_text(),
                                                           description)
    out = Path(tempfile.mkdtemp(prefix="zone-bench-"))
    (out / "client.yaml").write_text(rb.client_text(requests, ready, rb.request_inputs(description, requests)))
    (out / "edf4.yaml").write_text(rb.platform_text(4, execution, offsets))
    settings = TimeSettings(platform=out / "edf4.yaml", client=out / "client.yaml", responses=True, exceptions=False)
    return build_model(paths, include_dirs=[str(artefact)], no_rules=True, time=settings)


def search(model, engine: str, states: int | None, reduce: bool = False,
           step: str | None = None) -> tuple[object, object, float]:
    """A search to ``states``: its explorer, result and seconds.  ``step``: the compiled step's build, ``-O0`` (what
    a first search steps with) or ``-O2`` (what a search past OPTIMISE_AFTER nodes takes over, and later runs find
    in the cache); None: whichever the cache holds."""
    import runtime.native.compiled as compiled

    found = compiled.cached
    if step == "-O0":
        compiled.cached = lambda *args, **kw: None  # build the -O0 step even where an -O2 one is in the cache
    try:
        z = ZoneExplorer(model.package, model.root, SearchOptions().externs, engine=engine, reduce=reduce)
    finally:
        compiled.cached = found
    if step == "-O2" and z.compiled is not None and not z.compiled.optimised:
        z.compiled.optimise_later()
        z.compiled._later[1].join()
        z.compiled.adopt()
    z.successors(z.space.state(z.space.initial_ids[0]))  # the compiled step built before the clock starts
    start = time.perf_counter()
    result = z.explore(max_states=states)
    return z, result, time.perf_counter() - start


def fastest(model, engine: str, states: int, step: str, repeat: int) -> tuple[object, float]:
    """The result of ``repeat`` equal searches and the seconds of the fastest."""
    runs = [search(model, engine, states, step=step)[1:] for _ in range(max(1, repeat))]
    return runs[0][0], min(t for _, t in runs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--states", type=int, default=20_000, help="symbolic states both engines search (default 20,000)")
    ap.add_argument("--repeat", type=int, default=1, metavar="R",
                    help="time each search R times and keep the fastest (default 1)")
    ap.add_argument("--full", action="store_true", help="then search each model to the end with the C engine")
    ap.add_argument("--max-states", type=int, default=6_000_000, help="bound of the --full searches")
    ap.add_argument("--robnav", type=Path, metavar="ARTEFACT_DIR")
    ap.add_argument("--reduce", action="store_true",
                    help="also search each model with the partial-order reduction (to --states): what it left out")
    args = ap.parse_args()
    models = list(dala_models())
    if args.robnav:
        models.append(("RobNav, 4 cores", lambda: robnav_model(args.robnav)))
    print(f"{'model':24} {'states':>9} {'Python s':>9} {'Python st/s':>12} {'C s':>8} {'C st/s':>10} {'ratio':>7}"
          f" {'C, -O2 step':>12} {'ratio':>7}")
    built = []
    for name, make in models:
        model = make()
        built.append((name, model))
        rp, tp = fastest(model, "python", args.states, "-O0", args.repeat)
        rc, tc = fastest(model, "c", args.states, "-O0", args.repeat)
        r2, t2 = fastest(model, "c", args.states, "-O2", args.repeat)
        assert (rp.states, rp.transitions) == (rc.states, rc.transitions) == (r2.states, r2.transitions), name
        print(f"{name:24} {rc.states:>9,} {tp:>9.2f} {rp.states / tp:>12,.0f} {tc:>8.2f} {rc.states / tc:>10,.0f} "
              f"{tp / tc:>6.1f}x {r2.states / t2:>12,.0f} {tp / t2:>6.1f}x", flush=True)
    if args.reduce:
        print(f"\n{'model (C, reduction)':24} {'states':>9} {'off: discrete':>13} {'on: discrete':>12} "
              f"{'sets asked':>10} {'smaller':>8} {'steps left out':>14} {'off s':>6} {'on s':>6}")
        for name, model in built:
            _, off, t0 = search(model, "c", args.states)
            z, on, t1 = search(model, "c", args.states, reduce=True)
            asked, smaller, left = z.por.stats
            print(f"{name:24} {on.states:>9,} {off.discrete:>13,} {on.discrete:>12,} {asked:>10,} {smaller:>8,} "
                  f"{left:>14,} {t0:>6.1f} {t1:>6.1f}", flush=True)
    if not args.full:
        return
    print(f"\n{'model (C, to the end)':24} {'states':>10} {'discrete':>10} {'complete':>8} {'s':>8} {'st/s':>8} "
          f"{'zones MB':>9} {'states MB':>9} {'programs MB':>11}")
    for name, model in built:
        z, r, t = search(model, "c", args.max_states)
        counts = z.search.counts()
        mb = [counts[k] / 2 ** 20 for k in (12, 13, 14)]
        print(f"{name:24} {r.states:>10,} {r.discrete:>10,} {str(r.complete):>8} {t:>8.1f} {r.states / t:>8,.0f} "
              f"{mb[0]:>9.0f} {mb[1]:>9.0f} {mb[2]:>11.0f}", flush=True)


if __name__ == "__main__":
    main()
