"""The response-time distributions of an SMC report as a picture: one histogram per task and service that ended
at least once, its mean, 99th percentile and largest value marked."""
from __future__ import annotations

import os
from pathlib import Path

#: Panels per row.
COLUMNS = 3


def figure(report):
    """A matplotlib Figure (the object API: no pyplot state, no window)."""
    from matplotlib.figure import Figure

    shown = [d for d in report.responses if d.samples]
    rows = max(1, -(-len(shown) // COLUMNS))
    cols = min(COLUMNS, max(1, len(shown)))
    fig = Figure(figsize=(4.2 * cols, 3.0 * rows))
    title = (f"response times over {report.runs:,} runs of {report.horizon_ms:g} ms "
             f"(seed {report.seed})")
    fig.suptitle(title, fontsize=10)
    if not shown:
        ax = fig.add_subplot(1, 1, 1)
        ax.text(0.5, 0.5, "no response ended within the time bound", ha="center", va="center")
        ax.set_axis_off()
        return fig
    for k, d in enumerate(shown, 1):
        ax = fig.add_subplot(rows, cols, k)
        values = sorted(d.counts)
        ms = [d.ms(t) for t in values]
        width = d.tick_us / 1000 * 0.9
        ax.bar(ms, [d.counts[t] / d.samples for t in values], width=width, color="#5c7cfa")
        for x, style, name in ((d.mean_ms, "--", "mean"), (d.percentile_ms(), ":", "p99"), (d.max_ms, "-", "max")):
            ax.axvline(x, color="#c62828", linestyle=style, linewidth=1, label=f"{name} {x:.3g} ms")
        ax.set_title(f"{d.owner} ({d.kind}, {d.samples:,})", fontsize=9)
        ax.set_xlabel("ms", fontsize=8)
        ax.set_ylabel("share", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def draw(report, path: Path) -> Path:
    """Write the picture to ``path`` (.png or .svg) whole or not at all."""
    fig = figure(report)
    partial = path.with_name(f".{path.name}.{os.getpid()}.partial")
    try:
        fig.savefig(partial, dpi=110, format=path.suffix.lower().lstrip(".") or "png", bbox_inches="tight")
        os.replace(partial, path)
    finally:
        partial.unlink(missing_ok=True)
    return path
