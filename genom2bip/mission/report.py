"""The short report of a mission run: goals reached or not and why, distance and time, every request's end."""
from __future__ import annotations

import math
from itertools import pairwise
from typing import Any

from genom2bip.mission.session import Run
from genom2bip.mission.spec import GOAL_SERVICE, goal_point
from runtime.controller.codel_times import table


def distance_driven(run: Run) -> float:
    t = run.world.trajectory if run.world is not None else []
    return sum(math.hypot(b.x - a.x, b.y - a.y) for a, b in pairwise(t))


def _shown(goal: Any) -> str:
    point = goal_point(goal)
    return f"({point[0]:g}, {point[1]:g})" if point is not None else repr(goal)


def goals(run: Run) -> list[dict[str, Any]]:
    """Each GoTo accepted: its goal, whether it was reached, why not, and how far from it the robot ended.

    A GoTo a rule rejected is no goal of the drive: the report lists it with the rejected requests.
    """
    out = []
    for o in run.outcomes:
        if o.step.kind != "send" or o.step.target != GOAL_SERVICE:
            continue
        goal = o.step.inputs.get("goal", {})
        r = final_report(run, o.request) or o.report
        status = r.get("status")
        if status == "rejected" and r.get("reason") == "rule":
            continue
        end = _pose_at(run, r.get("time"))
        point = goal_point(goal)
        gap = math.hypot(point[0] - end[0], point[1] - end[1]) if end and point else None
        if status == "ok":
            when = f" at {r['time']:.1f} s" if r.get("time") is not None else ""
            within = f", {gap:.2f} m from it (GoTo ends within goal_tolerance)" if gap is not None else ""
            why = f"reached{when}{within}"
        elif status == "failed":
            detail = r.get("detail") or {}
            where = detail.get("where") or {}
            at = f" at ({where.get('x', 0):.2f}, {where.get('y', 0):.2f})" if where else ""
            why = f"not reached: {r.get('exception')}{at}"
        elif status == "rejected":
            why = f"not reached: rejected by {r.get('rule') or r.get('exception') or r.get('reason')}"
        elif status == "interrupted":
            why = f"not reached: interrupted by {r.get('by')}"
        else:
            why = f"not reached: {status}"
        reason = (r.get("detail") or {}).get("reason") if status == "failed" else None
        out.append({"goal": goal, "point": point, "status": status, "why": why, "distance_left": gap,
                    "request": o.request, "reason": reason})
    return out


def final_report(run: Run, request: int | None) -> dict[str, Any] | None:
    """The final report of ``request`` among the controller's events (it may come after the step that sent it)."""
    finals = [e for e in run.events if e.get("event") == "report" and e.get("request") == request and e.get("final")]
    return finals[-1] if finals else None


def _pose_at(run: Run, t: float | None) -> tuple[float, float] | None:
    if run.world is None or not run.world.trajectory:
        return None
    samples = run.world.trajectory
    if t is None:
        s = samples[-1]
    else:
        s = min(samples, key=lambda s: abs(s.t - t))
    return s.x, s.y


def text(run: Run) -> str:
    """The report printed at the end of ``genom2bip mission``."""
    lines = [f"mission {run.mission.name}" + (f" in {run.world_path.name}" if run.world_path else "") + ":"]
    for g in goals(run):
        left = f", {g['distance_left']:.2f} m from it" if g["distance_left"] is not None and g["status"] != "ok" else ""
        reason = f": {g['reason']}" if g["reason"] else ""
        lines.append(f"  goal {_shown(g['goal'])}: {g['why']}{left}{reason}")
    if run.world is not None:
        collisions = run.world.collisions
        lines.append(f"  driven {distance_driven(run):.2f} m in {run.sim_time:.1f} s of robot time "
                     f"({run.wall_time:.1f} s wall clock); collisions: {collisions}")
        if getattr(run.world, "display", False):
            window = run.world.window()
            lines.append(f"  shown live: {run.world.frames} frames in a {window} window" if window
                         else "  not shown live: no window could open on this display (headless backend)")
    lines.append("  requests:")
    for o in run.outcomes:
        if o.step.kind == "wait":
            continue
        r = (final_report(run, o.request) or o.report) if o.step.kind == "send" else o.report
        label = f"{r.get('component')}.{r.get('service')}" if r.get("component") else o.step.target
        detail = r.get("rule") or r.get("exception") or (f"by {r['by']}" if r.get("by") else "") or ""
        if r.get("status") == "interrupted" and not r.get("by") and o.report.get("status") in ("started", "running"):
            r, detail = o.report, "(ran until the controller stopped)"  # an activity the mission left running
        mark = "" if o.ok else f"   UNEXPECTED: {o.problem}"
        lines.append(f"    [{o.request if o.request is not None else '-'}] {label}: {r.get('status')} {detail}".rstrip()
                     + mark)
    rejected = [o for o in run.outcomes if o.report.get("status") == "rejected" and o.report.get("reason") == "rule"]
    lines.append("  rejected by rules: " + (", ".join(
        f"[{o.request}] {o.report.get('component')}.{o.report.get('service')} by {o.report.get('rule')}"
        for o in rejected) or "none"))
    if run.error:
        lines.append(f"  controller: {run.error}")
    failed = sum(1 for o in run.outcomes if not o.ok)
    lines.append("  every expectation met" if not failed and not run.error else f"  {failed} step(s) not as expected")
    if run.codel_times is not None:
        lines.append(f"  codel times ({run.codel_times['clock']} clock; cpu: the codel thread's CPU time, "
                     "wall: wall time):")
        lines += ["    " + line for line in table(run.codel_times)]
    return "\n".join(lines)
