"""The trajectory picture: the world's obstacles, the laser's hits, the robot's path, its start, end and goals."""
from __future__ import annotations

from pathlib import Path

from genom2bip.mission.report import goals
from genom2bip.mission.session import Run


def draw(run: Run, path: Path):
    """Write a PNG of ``run`` (which must have a world) to ``path``; returns (x, y) -> (column, row) in it."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    w = run.world
    xmin, ymin, xmax, ymax = w.bounds()
    scale = 8.0 / max(xmax - xmin, ymax - ymin)
    fig = Figure(figsize=(max(4.0, (xmax - xmin) * scale + 1.5), max(3.0, (ymax - ymin) * scale + 1.2)), dpi=110)
    ax = fig.add_subplot(1, 1, 1)
    for g in w.obstacles():
        if g.geom_type == "Polygon":
            xs, ys = g.exterior.xy
            ax.fill(xs, ys, color="0.55", zorder=1)
        else:
            for part in getattr(g, "geoms", [g]):
                xs, ys = part.xy
                ax.plot(xs, ys, color="0.3", linewidth=3, zorder=1)
    hits = w.hit_points()
    if hits:
        ax.scatter([p[0] for p in hits], [p[1] for p in hits], s=2, color="tab:red", label="laser hits", zorder=2)
    t = w.trajectory
    ax.plot([s.x for s in t], [s.y for s in t], color="tab:blue", linewidth=2, label="trajectory", zorder=3)
    ax.plot(t[0].x, t[0].y, "o", color="tab:green", markersize=9, label="start", zorder=4)
    ax.plot(t[-1].x, t[-1].y, "s", color="black", markersize=7, label="end", zorder=4)
    for g in (g for g in goals(run) if g["point"] is not None):
        ok = g["reached"]
        ax.plot(*g["point"], "*", markersize=15, zorder=5,
                color="gold" if ok else "magenta", markeredgecolor="black")
    ax.set_xlim(xmin - 0.2, xmax + 0.2)
    ax.set_ylim(ymin - 0.2, ymax + 0.2)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    reached = sum(1 for g in goals(run) if g["reached"])
    ax.set_title(f"{run.mission.name}: {reached}/{len(goals(run))} goals reached (stars: gold reached, magenta not)",
                 fontsize=9)
    ax.legend(loc="upper right", fontsize=7)
    fig.tight_layout()
    tmp = path.with_name(path.name + ".tmp.png")
    fig.savefig(tmp)
    tmp.replace(path)
    height = fig.bbox.height

    def to_pixel(x: float, y: float) -> tuple[int, int]:
        col, row = ax.transData.transform((x, y))
        return round(col), round(height - row)
    return to_pixel
