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


def goal_tolerance(run: Run, before: int) -> float | None:
    """The ``goal_tolerance`` of the last NDD.SetParams the mission sent, and that ended ok, before step ``before``."""
    tolerance = None
    for o in run.outcomes[:before]:
        if o.step.kind == "send" and o.step.target == "NDD.SetParams" and o.report.get("status") == "ok":
            params = o.step.inputs.get("params")
            value = params.get("goal_tolerance") if isinstance(params, dict) else None
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                tolerance = float(value)
    return tolerance


def goals(run: Run) -> list[dict[str, Any]]:
    """Each GoTo the mission sent with a goal: the goal, whether it was reached, why not, how far the robot ended.

    A GoTo a rule rejected is no goal of the drive: the report lists it with the rejected requests.  A GoTo sent
    without a goal has none to report (no default is made one), and a refused one has no distance: it never drove.
    "Reached" is said only when the robot truly ended within the tolerance NDD was given: a GoTo that ended ok
    farther than that is "not reached", with both figures.
    """
    out = []
    for index, o in enumerate(run.outcomes):
        if o.step.kind != "send" or o.step.target != GOAL_SERVICE or "goal" not in o.step.inputs:
            continue
        goal = o.step.inputs["goal"]
        point = goal_point(goal)
        r = final_report(run, o.request) or o.report
        status = r.get("status")
        if status == "rejected" and r.get("reason") == "rule":
            continue
        refused = status in ("rejected", "error")  # it never drove: no distance
        end = None if refused or o.request is None else run.goal_ends.get(o.request)
        end = end or (_pose_at(run, r.get("time")) if not refused else None)
        gap = math.hypot(point[0] - end[0], point[1] - end[1]) if end and point else None
        tolerance = goal_tolerance(run, index)
        reached = False
        if status == "ok":
            when = f" at {r['time']:.1f} s" if r.get("time") is not None else ""
            if gap is None:
                why = f"GoTo ended ok{when} (where the robot is, is not known)"
            elif tolerance is None:
                why = f"GoTo ended ok{when}, {gap:.2f} m from it (no goal_tolerance was set by the mission)"
            elif gap <= tolerance:
                why, reached = f"reached{when}, {gap:.2f} m from it (within goal_tolerance {tolerance:g} m)", True
            else:
                why = (f"not reached: GoTo ended ok{when}, but {gap:.2f} m from it, beyond goal_tolerance "
                       f"{tolerance:g} m")
        elif status == "failed":
            detail = r.get("detail") or {}
            where = detail.get("where") or {}
            at = f" at ({where.get('x', 0):.2f}, {where.get('y', 0):.2f})" if where else ""
            why = f"not reached: {r.get('exception')}{at}"
        elif status == "rejected":
            why = f"refused: {r.get('rule') or r.get('exception') or r.get('reason')}"
        elif status == "error":
            why = f"refused: {r.get('message')}"
        elif status == "interrupted":
            why = f"not reached: interrupted by {r.get('by')}"
        else:
            why = f"not reached: {status}"
        reason = (r.get("detail") or {}).get("reason") if status == "failed" else None
        out.append({"goal": goal, "point": point, "status": status, "why": why, "distance_left": gap,
                    "request": o.request, "reason": reason, "reached": reached, "tolerance": tolerance})
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


def timing_lines(run: Run) -> list[str]:
    """Each task's periods, those missed and those that overran, its codels past their bound, against the run's
    length; then one line: did real time hold?"""
    if not run.timing:
        return []
    codels: dict[str, int] = {}
    for e in run.events:
        if e.get("event") == "codel_overrun":
            owner = e.get("task") or e.get("service") or "?"
            codels[owner] = codels.get(owner, 0) + 1
    lines = [f"  timing over {run.sim_time:.1f} s of controller time ({run.clock} clock):"]
    width = max(len(t["task"]) for t in run.timing)
    lines.append(f"    {'task':<{width}}   period   periods   missed   overran   codels late")
    for t in run.timing:
        due = t["periods"] + t["missed"]  # those it ran and those it skipped: the run's length over the period
        lines.append(f"    {t['task']:<{width}}  {t['period_ms']:>4g} ms  {due:>8}  {t['missed']:>7}  "
                     f"{t['overruns']:>8}  {codels.get(t['task'], 0):>12}")
    others = {k: v for k, v in codels.items() if k not in {t["task"] for t in run.timing}}
    for owner, n in sorted(others.items()):
        lines.append(f"    {owner}: {n} codel(s) past their bound")
    missed = sum(t["missed"] for t in run.timing)
    overran = sum(t["overruns"] for t in run.timing)
    late = sum(codels.values())
    if run.real_time_held:
        lines.append(f"  real time held: no period missed or overrun, no codel late ({len(run.timing)} task(s))")
    else:
        lines.append(f"  real time NOT held: {missed} period(s) missed, {overran} overran, "
                     f"{late} codel(s) late (past their WCET, else their task's period)")
    return lines


def text(run: Run) -> str:
    """The report printed at the end of ``genom2bip mission``."""
    lines = [f"mission {run.mission.name}" + (f" in {run.world_path.name}" if run.world_path else "") + ":"]
    for g in goals(run):
        left = f", {g['distance_left']:.2f} m from it" if g["distance_left"] is not None and g["status"] not in (
            "ok", "rejected", "error") else ""
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
    lines += timing_lines(run)
    failed = sum(1 for o in run.outcomes if not o.ok)
    if failed or run.error:
        lines.append(f"  {failed} step(s) not as expected" + ("" if run.real_time_held else "; real time not held"))
    elif run.real_time_held:
        lines.append("  every expectation met")
    else:
        lines.append("  every step ended as expected, but real time did not hold: the mission fails "
                     "(what a late controller did is not what the robot would do on time)")
    if run.codel_times is not None:
        lines.append(f"  codel times ({run.codel_times['clock']} clock; cpu: the codel thread's CPU time, "
                     "wall: wall time):")
        lines += ["    " + line for line in table(run.codel_times)]
    return "\n".join(lines)


def document(run: Run, written: list[str], status: int) -> dict[str, Any]:
    """The report as one JSON document (``genom2bip mission --json``; docs/output.md,
    genom2bip/cli/mission_schema.json): the same figures as :func:`text`, for a script."""
    codels: dict[str, int] = {}
    for e in run.events:
        if e.get("event") == "codel_overrun":
            owner = e.get("task") or e.get("service") or "?"
            codels[owner] = codels.get(owner, 0) + 1
    requests = []
    for o in run.outcomes:
        if o.step.kind == "wait":
            continue
        r = (final_report(run, o.request) or o.report) if o.step.kind == "send" else o.report
        requests.append({"request": o.request, "step": o.step.kind, "target": o.step.target,
                         "status": r.get("status"), "rule": r.get("rule"),
                         "exception": None if r.get("exception") is None else str(r.get("exception")),
                         "expected": o.ok, "problem": o.problem})
    return {
        "tool": "genom2bip mission", "schema": 1, "mission": run.mission.name,
        "world": str(run.world_path) if run.world_path else None,
        "ok": run.ok, "expectations_met": run.expectations_met, "real_time_held": run.real_time_held,
        "goals": [{"goal": _shown(g["goal"]), "point": list(g["point"]) if g["point"] is not None else None,
                   "status": g["status"], "reached": g["reached"], "why": g["why"],
                   "distance_left": g["distance_left"], "tolerance": g["tolerance"], "request": g["request"]}
                  for g in goals(run)],
        "driven_m": distance_driven(run) if run.world is not None else None,
        "collisions": run.world.collisions if run.world is not None else None,
        "robot_time_s": run.sim_time, "wall_time_s": run.wall_time, "clock": run.clock,
        "requests": requests,
        "rejected_by_rules": [{"request": o.request, "rule": o.report.get("rule"),
                               "service": f"{o.report.get('component')}.{o.report.get('service')}"}
                              for o in run.outcomes
                              if o.report.get("status") == "rejected" and o.report.get("reason") == "rule"],
        "timing": [{"task": t["task"], "period_ms": t["period_ms"], "periods": t["periods"] + t["missed"],
                    "missed": t["missed"], "overran": t["overruns"], "codels_late": codels.get(t["task"], 0)}
                   for t in run.timing],
        "controller_error": run.error, "files": list(written), "exit_status": status,
    }
