"""A picture per numeric axis of a sweep: each check's verdict at each value (which period breaks it?) and what the
search cost there (states), one row and one line per check; figures a kind of check gives (response times) too."""
from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

from genom2bip.campaign.axes import axis_kind, shown
from genom2bip.campaign.jobs import Job

#: Colours and markers of the answers.
STYLE = {"holds": ("#2e7d32", "o"), "violated": ("#c62828", "X"), "inconclusive": ("#9e9e9e", "s"),
         "error": ("#6a1b9a", "D"), "failed": ("#000000", "P"), "crashed": ("#000000", "P")}


def numeric_axes(jobs: list[Job]) -> list[str]:
    """The axes of the jobs whose every value is a number (durations and factors included)."""
    values: dict[str, list[Any]] = {}
    for job in jobs:
        for key, value in job.point:
            values.setdefault(key, []).append(value)
    out = []
    for key, items in values.items():
        kind, _ = axis_kind(key)
        if len(set(map(repr, items))) > 1 and all(shown(kind, kind.read(v)) is not None for v in items):
            out.append(key)
    return out


def draw(jobs: list[Job], records: dict[str, dict[str, Any]], directory: Path) -> list[Path]:
    """One PNG per numeric axis in ``directory``; the files written."""
    return [_axis_picture(key, jobs, records, directory) for key in numeric_axes(jobs)]


#: Where a legend goes: beside its panel, right of the data, never over it.
OUTSIDE = {"loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "borderaxespad": 0.0, "fontsize": 7}


def _axis_picture(key: str, jobs: list[Job], records: dict[str, dict[str, Any]], directory: Path) -> Path:
    """The picture of ``key`` written to ``directory``; its path."""
    fig = figure(key, jobs, records)
    path = directory / f"{re.sub(r'[^A-Za-z0-9_.-]', '_', key)}.png"
    partial = path.with_name(f".{path.name}.{os.getpid()}.partial")
    try:  # a picture cut by a full disk is never left: written aside, then renamed over the old one
        fig.savefig(partial, dpi=110, format="png", bbox_inches="tight")  # the legends beside the panels kept in
        os.replace(partial, path)
    except OSError as exc:
        partial.unlink(missing_ok=True)
        from genom2bip.campaign.output import OutputError

        raise OutputError(f"cannot write {path}: {exc.strerror or exc}; it is left as it was") from None
    return path


def figure(key: str, jobs: list[Job], records: dict[str, dict[str, Any]]):
    """Top: a row per check, the answer at each value; below: states (log) per check; then a kind's own figures.
    Legends stand right of their panel (:data:`OUTSIDE`), so that no line or point is hidden under one."""
    from matplotlib.figure import Figure  # the object API: no pyplot state, no window

    kind, _ = axis_kind(key)
    series: dict[str, list[tuple[float, dict[str, Any] | None]]] = {}
    for job in sorted(jobs, key=lambda j: j.index):
        point = dict(job.point)
        if key not in point:
            continue
        rest = " ".join(f"{k}={v}" for k, v in job.point if k != key)
        what = job.target if job.target.startswith(job.model) else f"{job.model} {job.target}"
        name = what + (f" [{rest}]" if rest else "")
        series.setdefault(name, []).append((shown(kind, kind.read(point[key])), records.get(job.id)))
    extra = _figures(jobs, records, key, kind)
    panels = 2 + bool(extra)
    height = max(2.5, 0.35 * len(series) + 1.2)
    fig = Figure(figsize=(9, height + 3 * (panels - 1)))
    axes = fig.subplots(panels, 1, sharex=True, gridspec_kw={"height_ratios": [height] + [3] * (panels - 1)})
    top, states = axes[0], axes[1]
    names = list(series)
    for row, name in enumerate(names):
        points = sorted(series[name], key=lambda p: p[0])
        for x, record in points:
            answer = (record.get("verdict") or record.get("status")) if record else None
            colour, marker = STYLE.get(answer or "", ("#ffffff", "o"))
            top.scatter([x], [row], c=colour, marker=marker, s=70, edgecolors="#424242", linewidths=0.5, zorder=3)
        xs = [x for x, r in points if r and (r.get("figures") or {}).get("states")]
        ys = [r["figures"]["states"] for _, r in points if r and (r.get("figures") or {}).get("states")]
        if xs:
            states.plot(xs, ys, marker="o", label=name)
    top.set_yticks(range(len(names)), names, fontsize=8)
    top.set_ylim(len(names) - 0.5, -0.5)
    top.grid(axis="x", alpha=0.3)
    top.set_title(f"{key}: answer of each check (green holds, red violated, grey inconclusive, black failed)",
                  fontsize=9)
    states.set_yscale("log")
    states.set_ylabel("states")
    states.grid(alpha=0.3)
    if len(names) <= 12 and states.lines:
        states.legend(**OUTSIDE)
    if extra:
        _draw_figures(axes[2], extra)
    if all(float(x).is_integer() for points in series.values() for x, _ in points):
        from matplotlib.ticker import MaxNLocator
        axes[-1].xaxis.set_major_locator(MaxNLocator(integer=True))  # cores: 1, 2, 3, not 1.2
    axes[-1].set_xlabel(f"{key}" + (f" ({kind.unit})" if kind.unit else ""))
    fig.tight_layout()
    return fig


def _draw_figures(ax, extra: dict[str, list[tuple[float, float | str]]]) -> None:
    """A line per figure (a task's response time) through its numbers; a value that is a word (``unbounded``) is a
    triangle on the top edge, in the line's colour, with the word beside it."""
    top = 0.0
    last = max((x for points in extra.values() for x, _ in points), default=0.0)
    said: dict[float, int] = {}  # words already written at an x: the next goes under them
    for n, (name, points) in enumerate(extra.items()):
        numbers = sorted((x, y) for x, y in points if not isinstance(y, str))
        words = [(x, y) for x, y in points if isinstance(y, str)]
        colour, marker = f"C{n % 10}", "osD^vP*X"[n // 10 % 8]
        if numbers:
            ax.plot(*zip(*numbers), marker=marker, color=colour, label=name,
                    linestyle=("-", "--", ":", "-.")[n % 4], markersize=max(3, 8 - n % 4))  # equal lines stay seen
            top = max(top, max(y for _, y in numbers))
        for k, (x, word) in enumerate(words):
            ax.plot([x], [1], marker="^", color=colour, markersize=9, linestyle="", clip_on=False,
                    transform=ax.get_xaxis_transform(), label=None if numbers or k else f"{name} ({word})")
            below = said[x] = said.get(x, -1) + 1
            right = x >= last  # at the last value the word goes left of its mark, away from the legend
            ax.annotate(word, (x, 1), xycoords=ax.get_xaxis_transform(), xytext=(-8 if right else 6, -10 - 9 * below),
                        textcoords="offset points", fontsize=7, color=colour, ha="right" if right else "left")
    ax.set_ylabel("response time (ms)")
    ax.set_ylim(0, top * 1.2 or 1)  # room under the top edge, where the words are
    ax.grid(alpha=0.3)
    ax.legend(**OUTSIDE)


def _figures(jobs, records, key, kind) -> dict[str, list[tuple[float, float | str]]]:
    """The values a kind of check gives (a record's ``values``: ``CheckKind.figures``), against the axis."""
    out: dict[str, list[tuple[float, float | str]]] = {}
    for job in jobs:
        record = records.get(job.id)
        point = dict(job.point)
        if record is None or key not in point or not record.get("values"):
            continue
        for name, value in record["values"].items():
            out.setdefault(f"{job.model} {name}", []).append((shown(kind, kind.read(point[key])), value))
    return out
