"""Pictures of a few BARN runs with the Planner: the cylinders, what the laser saw, the trajectory and a plan.

    python bench/barn_pictures.py --barn DIR --worlds 30 132 138 [--out docs/images/barn_runs.png]

Each world is run as ``navigation_bench.py --barn`` runs it (the Planner brought up); the picture shows, per
world, the cylinders (grey), the laser's hits (red), the robot's true trajectory (blue), the start and the
goal with its 1 m success circle, and the path the Planner's method finds from the start to the goal over
everything the laser saw in the run (dashed green: the last plan, replayed on the whole map seen).
"""
from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--barn", required=True, help="a copy of the BARN challenge repository")
    parser.add_argument("--worlds", type=int, nargs="+", default=[30, 132, 138])
    parser.add_argument("--package", default=str(ROOT / "gen/dala"))
    parser.add_argument("--codels", default=str(ROOT / "descriptions/dala/codels"))
    parser.add_argument("--out", default=str(ROOT / "docs/images/barn_runs.png"))
    args = parser.parse_args()
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle

    from runtime.controller.codels import load_codels
    import navigation_bench as nb

    planning = importlib.import_module(f"{load_codels(args.codels, ['Planner']).modules['Planner'].__package__}"
                                       ".planning")
    work = Path("/tmp") / "barn_pictures"
    fig = Figure(figsize=(4.2 * len(args.worlds), 9.0), dpi=100)
    for k, index in enumerate(args.worlds):
        world, result, row = nb.barn_run(index, args.barn, args.package, args.codels, str(work))
        ax = fig.add_subplot(1, len(args.worlds), k + 1)
        for x, y in world.cylinders:
            ax.add_patch(Circle((x, y), 0.075, color="0.6", zorder=1))
        hits = result.world.hit_points()
        ax.scatter([p[0] for p in hits], [p[1] for p in hits], s=1.5, color="tab:red", zorder=2, label="laser hits")
        seen = planning.Seen(0.1)
        seen.add(hits)
        p = nb.BARN_PLANNER_PARAMS
        try:
            plan = planning.plan(seen, world.start[:2], world.goal, p["robot_radius"], p["clearance"])
            ax.plot([q[0] for q in plan.points], [q[1] for q in plan.points], "--", color="tab:green", linewidth=1.5,
                    zorder=3, label="plan over the map seen")
        except planning.NoPath:
            pass
        t = result.world.trajectory
        ax.plot([s.x for s in t], [s.y for s in t], color="tab:blue", linewidth=1.8, zorder=4, label="trajectory")
        ax.plot(*world.start[:2], "o", color="tab:green", markersize=8, zorder=5)
        ax.add_patch(Circle(world.goal, 1.0, fill=False, color="gold", linewidth=1.5, zorder=5))
        ax.plot(*world.goal, "*", color="gold", markeredgecolor="black", markersize=14, zorder=6)
        ax.set_xlim(-5.5, 1.0)
        ax.set_ylim(-0.5, 14.5)
        ax.set_aspect("equal")
        verdict = "success" if row["success"] else f"failure ({row['outcome']})"
        ax.set_title(f"BARN world {index}: {verdict}\n{row['barn_time']} s, metric {row['metric']}"
                     + (f", DWA {row['dwa_success']:.1f}" if row.get("dwa_success") is not None else ""), fontsize=9)
        if k == 0:
            ax.legend(loc="lower left", fontsize=7)
    fig.tight_layout()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
