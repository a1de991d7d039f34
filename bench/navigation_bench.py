"""How well DALA navigates worlds it was not tuned on: seeded generated worlds driven by the real controller.

    python bench/navigation_bench.py [--worlds 100] [--first 0] [--family F] [--workers 1]
                                     [--package gen/dala] [--codels descriptions/dala/codels] [--out out/navigation]
    python bench/navigation_bench.py --barn DIR [--worlds 300] [--first 0] [--every 1] [--workers 1] ...

Each seed gives a world (genom2bip/mission/worlds: a cellular automaton's field, a doorway or a corridor
by default, seed by seed; ``--family u_trap`` for U-shaped traps), kept only when a path with the robot's
clearance exists.  Its mission is descriptions/dala/missions/doorway.yaml's bring-up, POM anchored at the
start and one GoTo to the goal, run as ``genom2bip mission`` runs it: the generated package, the codels,
ir-sim, the services client, on the virtual clock; the Planner is brought up after POM.Run
(``--no-planner``: ND alone, as before the Planner).  The GoTo's timeout is the time NDD's progress rule
allows the distance (NDD.PROGRESS closer within NDD.PROGRESS_TIMEOUT), plus 30 s: a GoTo still running then is a mission
timeout, a failure of its own.

Prints, and writes to ``--out`` (summary.txt, results.jsonl, navigation.png, the worlds and missions):
the success rate, collisions, time to goal, path length over the shortest path with the clearance, the
failures by reason, and success against each difficulty metric, as a table and a plot.  ``--workers N``
runs N worlds at a time in separate processes (the default, 1, runs them in this one).

``--barn DIR`` runs the worlds of the BARN challenge instead, from a fetched copy of its repository
(Daffan/the-barn-challenge; it stays outside this one): worlds ``--first`` to ``--first + --worlds - 1``
(default all 300) whose index is a multiple of ``--every`` (6: the 50 on which the challenge ran DWA), at
true scale (genom2bip/mission/worlds/barn.py), with the challenge's start, goal and
success rule (within 1 m of the goal, no collision, 100 s), its navigation metric, and its DWA baseline's
success beside ours, world by world and by tercile of the world index and of each difficulty metric.
"""
from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

TEMPLATE = ROOT / "descriptions/dala/missions/doorway.yaml"
BARN_ROBOT_RADIUS = 0.215  # m: the Jackal's half-width (docs/missions.md, *The robot's footprint in BARN*)
MAP_CELL = 0.1  # m: Aspect's cell in these missions (its default)
# NDD's R is the robot's radius plus half a map cell (the rule of the shipped missions, 0.3 + 0.05): ND's obstacle
# points are cell centres, and a return lies up to half a cell nearer than its cell's centre.
BARN_NDD = {"params": {"robot_radius": round(BARN_ROBOT_RADIUS + MAP_CELL / 2, 3), "security_distance": 0.1,
                       "goal_tolerance": 0.9}}
# The generated worlds' robot, a disc of 0.3 m (doorway.yaml's): the Planner takes the robot's own radius and
# counts the map's precision itself, where NDD's robot_radius (0.35) is the disc plus half a cell.
PLANNER_PARAMS = {"robot_radius": 0.3, "clearance": 0.6, "lookahead": 2.0}
# The Planner's robot_radius is the robot's own: it counts the map's precision itself (planning.precision).
BARN_PLANNER_PARAMS = {"robot_radius": BARN_ROBOT_RADIUS, "clearance": 0.45, "lookahead": 2.0}


def planner_steps(params: dict | None) -> list[dict]:
    """The Planner's bring-up (after POM.Run, as the rule planner-after-pom-run wants), none without ``params``."""
    if params is None:
        return []
    return [{"send": "Planner.SetParams", "with": {"params": params}, "expect": "ok"},
            {"send": "Planner.Run", "until": "started"}]
ROBOT_WORLD = ROOT / "descriptions/dala/worlds/doorway.yaml"  # whose robot every generated world carries
METRICS = ("closest", "dispersion", "dimension", "visibility", "tortuosity")
LABELS = {"closest": "distance to the closest obstacle (m)", "dispersion": "dispersion (openings around)",
          "dimension": "characteristic dimension (m)", "visibility": "visibility (m)",
          "tortuosity": "tortuosity (path / straight)"}


def give_up_bound(distance: float, codels: str) -> float:
    """Robot seconds within which NDD's progress rule ends a GoTo that starts ``distance`` m from its goal."""
    from runtime.controller.codels import load_codels

    ndd = load_codels(codels, ["NDD"]).modules["NDD"]
    return (distance / ndd.PROGRESS + 1) * ndd.PROGRESS_TIMEOUT + ndd.NO_WAY_TIMEOUT


def _goto_outcome(run, world) -> dict:
    """What became of the world's GoTo: reached, e_blocked (and why), mission timeout, or another failure."""
    from genom2bip.mission.report import final_report

    goto = run.outcomes[-1]
    final = final_report(run, goto.request) or {}
    started = next((e["time"] for e in run.events if e.get("event") == "report" and e.get("request") == goto.request
                    and e.get("status") == "started"), None)
    status, exception = final.get("status"), str(final.get("exception") or "").split("::")[-1]
    if status == "ok":
        outcome, reason = "reached", ""
    elif exception == "e_blocked":
        outcome, reason = "e_blocked", (final.get("detail") or {}).get("reason") or "(no reason given)"
    elif not final:
        outcome, reason = "timeout", goto.problem or "no final report"
    else:
        outcome, reason = str(status), final.get("message") or exception or str(status)
    end = final.get("time", run.sim_time)
    samples = [s for s in run.world.trajectory if started is not None and started <= s.t <= end]
    driven = sum(math.hypot(b.x - a.x, b.y - a.y) for a, b in zip(samples, samples[1:]))
    last = run.world.trajectory[-1]
    return {"outcome": outcome, "reason": reason, "collisions": run.world.collisions,
            "time": round(end - started, 2) if started is not None else None, "driven": round(driven, 2),
            "left": round(math.dist((last.x, last.y), world.goal), 2), "controller_error": run.error}


def run_world(seed: int, family: str | None, package: str, codels: str, out: str, planner: bool = True) -> dict:
    """Generate the world of ``seed``, write it and its mission under ``out``, run it; one result row."""
    from genom2bip.mission.session import load_package, run_mission
    from genom2bip.mission.spec import read_mission
    from genom2bip.mission.worlds import generate, mission_file, world_file
    import yaml

    world = generate(seed, family)
    folder = Path(out) / "worlds"
    folder.mkdir(parents=True, exist_ok=True)
    robot = yaml.safe_load(ROBOT_WORLD.read_text())["robot"][0]
    world_path = folder / f"{world.name}.yaml"
    world_path.write_text(world_file.text(world, robot))
    bound = give_up_bound(math.dist(world.start[:2], world.goal), codels)
    mission_path = folder / f"{world.name}.mission.yaml"
    mission_path.write_text(mission_file.text(world, world_path.resolve(), TEMPLATE, bound + 30,
                                              after_origin=planner_steps(PLANNER_PARAMS if planner else None)))
    mission = read_mission(mission_path)
    wall = time.perf_counter()
    run = run_mission(mission, load_package(package), codels, mission.world)
    row = {"seed": seed, "family": world.family, "world": world.name, "shortest": round(world.length, 2),
           "bound": round(bound, 1), **_goto_outcome(run, world), "robot_time": round(run.sim_time, 1),
           "wall": round(time.perf_counter() - wall, 1), **world.difficulty.as_dict()}
    row["ratio"] = round(row["driven"] / world.length, 3) if row["outcome"] == "reached" else None
    return row


def barn_outcome(trajectory, world) -> dict:
    """The challenge's verdict on a run from the true trajectory: time from the first 0.1 m moved to within 1 m."""
    from genom2bip.mission.worlds import barn

    moved = next((s.t for s in trajectory if math.dist((s.x, s.y), world.start[:2]) >= 0.1), None)
    near = next((s.t for s in trajectory if math.dist((s.x, s.y), world.goal) <= barn.SUCCESS_RADIUS), None)
    time_taken = (near - moved) if near is not None and moved is not None else None
    return {"barn_time": round(time_taken, 2) if time_taken is not None else None,
            "barn_within_limit": time_taken is not None and time_taken <= barn.TIME_LIMIT}


def run_barn_world(index: int, root: str, package: str, codels: str, out: str, planner: bool = True) -> dict:
    """Convert BARN world ``index`` of the challenge copy at ``root``, write it and its mission, run it: its row."""
    return barn_run(index, root, package, codels, out, planner)[2]


def barn_run(index: int, root: str, package: str, codels: str, out: str, planner: bool = True):
    """(the BARN world, the mission's run, the result row) of world ``index``."""
    from genom2bip.mission.session import load_package, run_mission
    from genom2bip.mission.spec import read_mission
    from genom2bip.mission.worlds import barn, mission_file
    import yaml

    root_path = Path(root)
    dwa = barn.dwa_runs(root_path / barn.DWA_RUNS) if (root_path / barn.DWA_RUNS).is_file() else {}
    world = barn.load(root_path, index, dwa)
    folder = Path(out) / "worlds"
    folder.mkdir(parents=True, exist_ok=True)
    robot = yaml.safe_load(ROBOT_WORLD.read_text())["robot"][0]
    robot["shape"] = {"name": "circle", "radius": BARN_ROBOT_RADIUS}
    world_path = folder / f"{world.name}.yaml"
    world_path.write_text(barn.world_text(world, robot))
    mission_path = folder / f"{world.name}.mission.yaml"
    mission_path.write_text(mission_file.text(world, world_path.resolve(), TEMPLATE, barn.TIME_LIMIT + 15,
                                              note=f"BARN world {index}", inputs={"NDD.SetParams": BARN_NDD},
                                              after_origin=planner_steps(BARN_PLANNER_PARAMS if planner else None)))
    mission = read_mission(mission_path)
    wall = time.perf_counter()
    run = run_mission(mission, load_package(package), codels, mission.world)
    row = {"index": index, "world": world.name, "shortest": round(world.length, 2),
           "optimal_time": round(world.optimal_time, 2), **_goto_outcome(run, world),
           **barn_outcome(run.world.trajectory, world), "robot_time": round(run.sim_time, 1),
           "wall": round(time.perf_counter() - wall, 1), **world.difficulty.as_dict()}
    row["success"] = bool(row["barn_within_limit"] and row["collisions"] == 0)
    row["metric"] = round(barn.nav_metric(row["success"], row["barn_time"] or barn.TIME_LIMIT, world.optimal_time), 4)
    if world.dwa is not None:
        row.update(dwa_success=round(world.dwa.success, 3), dwa_metric=round(world.dwa.metric(world.optimal_time), 4),
                   dwa_runs=world.dwa.runs)
    row["ratio"] = round(row["driven"] / world.length, 3) if row["success"] else None
    return world, run, row


def _quantiles(values: list[float]) -> str:
    if not values:
        return "-"
    return f"median {statistics.median(values):.2f}, mean {statistics.fmean(values):.2f}, max {max(values):.2f}"


def _difficulty_table(rows: list[dict]) -> list[str]:
    """Success by tertile of each difficulty metric."""
    lines = [f"  {'metric':<44} {'lower third':>24} {'middle third':>24} {'upper third':>24}"]
    for m in METRICS:
        ranked = sorted(rows, key=lambda r: r[m])
        k = len(ranked)
        cells = []
        for part in (ranked[: k // 3], ranked[k // 3: 2 * k // 3], ranked[2 * k // 3:]):
            if not part:
                cells.append("-")
                continue
            ok = sum(r["outcome"] == "reached" for r in part)
            cells.append(f"{part[0][m]:.2f}-{part[-1][m]:.2f}: {ok}/{len(part)}")
        lines.append(f"  {LABELS[m]:<44} " + " ".join(f"{c:>24}" for c in cells))
    return lines


def summary(rows: list[dict], args: argparse.Namespace) -> str:
    """The bench's report: success, collisions, times, path ratios, failures by reason, success by difficulty."""
    n = len(rows)
    reached = [r for r in rows if r["outcome"] == "reached"]
    families = Counter(r["family"] for r in rows)
    seeds = f"{args.first}-{args.first + args.worlds - 1}"
    lines = [f"navigation bench: {n} worlds, seeds {seeds} ("
             + ", ".join(f"{f} {c}" for f, c in sorted(families.items())) + f"); package {args.package}, "
             f"codels {args.codels}",
             f"  reached: {len(reached)}/{n} ({100 * len(reached) / max(n, 1):.0f} %)",
             f"  collisions: in {sum(1 for r in rows if r['collisions'])} worlds "
             f"({sum(r['collisions'] for r in rows)} simulation steps of 25 ms in contact)",
             f"  time to goal (s, robot time, reached): {_quantiles([r['time'] for r in reached])}",
             f"  path length / shortest with clearance (reached): {_quantiles([r['ratio'] for r in reached])}",
             "  by family: " + ", ".join(
                 f"{f} {sum(r['outcome'] == 'reached' for r in rows if r['family'] == f)}/{c}"
                 for f, c in sorted(families.items())),
             "  failures by reason:"]
    failures = Counter(f"{r['outcome']}: {r['reason']}" for r in rows if r["outcome"] != "reached")
    lines += [f"    {c:3d}  {why}" for why, c in failures.most_common()] or ["    none"]
    failed = [r["world"] for r in rows if r["outcome"] != "reached"]
    if failed:
        lines.append("  worlds not reached: " + ", ".join(failed))
    lines.append("  success by difficulty (each metric's worlds in thirds, low to high: range, reached/worlds):")
    lines += _difficulty_table(rows)
    return "\n".join(lines)


def _thirds(rows: list[dict], key) -> list[list[dict]]:
    ranked = sorted(rows, key=key)
    k = len(ranked)
    return [ranked[: k // 3], ranked[k // 3: 2 * k // 3], ranked[2 * k // 3:]]


def _barn_cell(part: list[dict]) -> str:
    """Ours (reached/worlds) and DWA's mean success on those of the worlds it was run on."""
    if not part:
        return "-"
    ok = sum(r["success"] for r in part)
    dwa = [r["dwa_success"] for r in part if r.get("dwa_success") is not None]
    ours_there = [r["success"] for r in part if r.get("dwa_success") is not None]
    beside = (f"; on DWA's {len(dwa)}: ours {statistics.fmean(ours_there):.2f}, DWA {statistics.fmean(dwa):.2f}"
              if dwa else "")
    return f"{ok}/{len(part)}{beside}"


def barn_summary(rows: list[dict], args: argparse.Namespace) -> str:
    """The BARN report: success by the challenge's rule, collisions, its metric, DWA beside, by index and difficulty."""
    n = len(rows)
    ok = [r for r in rows if r["success"]]
    with_dwa = [r for r in rows if r.get("dwa_success") is not None]
    lines = [f"navigation bench on BARN: {n} worlds ({rows[0]['index'] if rows else '-'}-"
             f"{rows[-1]['index'] if rows else '-'}, every {args.every}), from {args.barn}; package {args.package}",
             f"  success (within 1 m of the goal, no collision, 100 s): {len(ok)}/{n} "
             f"({100 * len(ok) / max(n, 1):.1f} %)",
             f"  collisions: in {sum(1 for r in rows if r['collisions'])} worlds "
             f"({sum(r['collisions'] for r in rows)} simulation steps of 25 ms in contact)",
             f"  navigation metric (the challenge's), mean: {statistics.fmean([r['metric'] for r in rows]):.4f}"
             if rows else "  navigation metric: -",
             f"  time to within 1 m (s, successes): {_quantiles([r['barn_time'] for r in ok])}"]
    if with_dwa:
        lines.append(f"  on the {len(with_dwa)} worlds with DWA runs: ours "
                     f"{statistics.fmean(r['success'] for r in with_dwa):.3f} success, metric "
                     f"{statistics.fmean(r['metric'] for r in with_dwa):.4f}; DWA "
                     f"{statistics.fmean(r['dwa_success'] for r in with_dwa):.3f} success, metric "
                     f"{statistics.fmean(r['dwa_metric'] for r in with_dwa):.4f}")
    lines.append("  failures by reason:")
    failures = Counter(("collision" if r["collisions"] else f"{r['outcome']}: {r['reason']}"
                        if r["outcome"] != "reached" else "reached after 100 s") for r in rows if not r["success"])
    lines += [f"    {c:3d}  {why}" for why, c in failures.most_common()] or ["    none"]
    failed = [r["world"] for r in rows if not r["success"]]
    if failed:
        lines.append("  worlds not reached: " + ", ".join(failed))
    lines.append("  by tercile of the world index (the challenge orders its worlds by difficulty):")
    for name, part in zip(("first", "second", "third"), _thirds(rows, lambda r: r["index"])):
        span = f"{part[0]['index']}-{part[-1]['index']}" if part else "-"
        lines.append(f"    {name:<7} {span:>8}: {_barn_cell(part)}")
    lines.append("  by tercile of each difficulty metric (along the challenge's optimal path), low to high:")
    for m in METRICS:
        cells = [f"{p[0][m]:.2f}-{p[-1][m]:.2f}: {_barn_cell(p)}" if p else "-"
                 for p in _thirds(rows, lambda r, m=m: r[m])]
        lines.append(f"    {LABELS[m]}: " + " | ".join(cells))
    return "\n".join(lines)


def plot(rows: list[dict], path: Path) -> None:
    """One panel per metric: path length over shortest for the worlds reached, the others marked above."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(15, 8.5), dpi=90)
    reached = [r for r in rows if r["outcome"] == "reached"]
    top = max([r["ratio"] for r in reached] + [1.2]) * 1.08
    colours = {"e_blocked": "tab:orange", "timeout": "tab:red"}
    for k, m in enumerate(METRICS):
        ax = fig.add_subplot(2, 3, k + 1)
        ax.scatter([r[m] for r in reached], [r["ratio"] for r in reached], s=18, color="tab:blue", label="reached")
        for outcome in sorted({r["outcome"] for r in rows} - {"reached"}):
            bad = [r for r in rows if r["outcome"] == outcome]
            ax.scatter([r[m] for r in bad], [top] * len(bad), marker="x", s=40,
                       color=colours.get(outcome, "black"), label=f"not reached: {outcome}")
        ax.axhline(1.0, color="0.7", linewidth=0.8)
        ax.set_xlabel(LABELS[m])
        ax.set_ylabel("path length / shortest")
    ax = fig.add_subplot(2, 3, 6)
    families = sorted({r["family"] for r in rows})
    rates = [100 * sum(r["outcome"] == "reached" for r in rows if r["family"] == f) /
             sum(r["family"] == f for r in rows) for f in families]
    ax.bar(families, rates, color="tab:blue")
    for x, (f, rate) in enumerate(zip(families, rates)):
        ax.text(x, rate + 1, f"{rate:.0f} % of {sum(r['family'] == f for r in rows)}", ha="center", fontsize=8)
    ax.set_ylim(0, 110)
    ax.set_ylabel("reached (%)")
    ax.set_title("success by family", fontsize=9)
    n, ok = len(rows), len(reached)
    fig.suptitle(f"DALA navigation on {n} generated worlds: {ok} reached ({100 * ok / max(n, 1):.0f} %), "
                 f"collisions in {sum(1 for r in rows if r['collisions'])} worlds", fontsize=11)
    handles, labels = fig.axes[0].get_legend_handles_labels()  # one legend for the panels: none hides a mark
    fig.legend(handles, labels, loc="upper right", fontsize=8, ncol=len(labels))
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    fig.savefig(path)


def main() -> None:
    """Run the seeds' worlds (in --workers processes), print and write the summary, the rows and the plot."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worlds", type=int, help="how many seeds (default 100), or BARN worlds (default all)")
    parser.add_argument("--first", type=int, default=0, help="the first seed (default 0)")
    parser.add_argument("--family", help="one family for every seed (default: the mix, seed by seed)")
    parser.add_argument("--no-planner", action="store_true", help="ND alone: the missions bring up no Planner")
    parser.add_argument("--barn", help="a copy of the BARN challenge repository: run its worlds instead")
    parser.add_argument("--every", type=int, default=1,
                        help="with --barn: the worlds whose index is a multiple of N (default 1; 6: DWA's 50)")
    parser.add_argument("--offset", type=int, default=0, help="with --every N: the indices i with i %% N == offset")
    parser.add_argument("--workers", type=int, default=1, help="worlds run at a time, each in a process (default 1)")
    parser.add_argument("--package", default=str(ROOT / "gen/dala"), help="the generated package (default gen/dala)")
    parser.add_argument("--codels", default=str(ROOT / "descriptions/dala/codels"), help="the codels' directory")
    parser.add_argument("--out", default=str(ROOT / "out/navigation"), help="where the results go")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.barn:
        from genom2bip.mission.worlds import barn

        last = args.first + (args.worlds if args.worlds is not None else 10 ** 6)
        indices = [i for i in barn.available(Path(args.barn))
                   if args.first <= i < last and i % args.every == args.offset % args.every]
        jobs = [(i, args.barn, args.package, args.codels, str(out), not args.no_planner) for i in indices]
        work = run_barn_world
    else:
        args.worlds = 100 if args.worlds is None else args.worlds
        seeds = range(args.first, args.first + args.worlds)
        jobs = [(s, args.family, args.package, args.codels, str(out), not args.no_planner) for s in seeds]
        work = run_world
    rows: list[dict] = []
    started = time.perf_counter()

    partial = out / "results.partial.jsonl"  # each row as it comes: a long run cut short keeps what it measured
    partial.write_text("")

    def done(row: dict) -> None:
        rows.append(row)
        with partial.open("a") as f:
            f.write(json.dumps(row) + "\n")
        why = f" ({row['reason']})" if row["reason"] else ""
        if args.barn:
            dwa = f", DWA {row['dwa_success']:.1f}" if row.get("dwa_success") is not None else ""
            print(f"[{len(rows):3d}/{len(jobs)}] {row['world']}: {'success' if row['success'] else 'failure'} "
                  f"({row['outcome']}{why}) in {row['barn_time']} s, metric {row['metric']}{dwa}, collisions "
                  f"{row['collisions']}, wall {row['wall']} s", flush=True)
            return
        print(f"[{len(rows):3d}/{len(jobs)}] {row['world']}: {row['outcome']}{why} in {row['time']} s, "
              f"driven {row['driven']} m (shortest {row['shortest']} m), collisions {row['collisions']}, "
              f"wall {row['wall']} s", flush=True)

    if args.workers <= 1:
        for job in jobs:
            done(work(*job))
    else:
        with ProcessPoolExecutor(max_workers=args.workers, mp_context=get_context("spawn")) as pool:
            for row in pool.map(work, *zip(*jobs)):
                done(row)
    rows.sort(key=lambda r: r["index"] if args.barn else r["seed"])
    (out / "results.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    partial.unlink()
    if args.barn:
        text = barn_summary(rows, args) + f"\n  wall clock: {time.perf_counter() - started:.0f} s"
        (out / "summary.txt").write_text(text + "\n")
        print(text)
        print(f"  wrote {out / 'summary.txt'}, {out / 'results.jsonl'}, {out / 'worlds'}/")
        return
    text = summary(rows, args) + f"\n  wall clock: {time.perf_counter() - started:.0f} s with {args.workers} worker(s)"
    (out / "summary.txt").write_text(text + "\n")
    plot(rows, out / "navigation.png")
    print(text)
    print(f"  wrote {out / 'summary.txt'}, {out / 'results.jsonl'}, {out / 'navigation.png'}, {out / 'worlds'}/")


if __name__ == "__main__":
    main()
