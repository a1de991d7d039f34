"""A mission for a generated world: a template mission's bring-up, POM anchored at the start, one GoTo to the goal."""
from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from genom2bip.mission.worlds.families import GridWorld

GOAL_SERVICE = "NDD.GoTo"
ORIGIN_SERVICE = "POM.Run"


def text(world: GridWorld, world_path: Path, template: Path, timeout: float, note: str | None = None,
         inputs: dict[str, dict[str, Any]] | None = None, after_origin: list[dict[str, Any]] | None = None) -> str:
    """The mission YAML: ``template``'s steps before its first GoTo, POM.Run at the start, a GoTo expected ``ok``.

    ``timeout`` (controller seconds) bounds the GoTo; the template must run
    POM.Run before its first GoTo (as the rule goto-after-pom-run requires).
    ``inputs`` replaces the inputs of the bring-up's requests by service
    (e.g. NDD.SetParams' for another robot); ``after_origin`` are steps sent
    right after POM.Run (the Planner's bring-up); ``note`` is the file's first line.
    """
    data = yaml.safe_load(template.read_text(encoding="utf-8"))
    steps: list[dict[str, Any]] = data.get("steps") or []
    first = next((k for k, s in enumerate(steps) if s.get("send") == GOAL_SERVICE), None)
    if first is None or not any(s.get("send") == ORIGIN_SERVICE for s in steps[:first]):
        raise ValueError(f"{template}: no {ORIGIN_SERVICE} before a first {GOAL_SERVICE}")
    x, y, theta = world.start
    bringup = []
    for s in steps[:first]:
        s = dict(s)
        if s.get("send") in (inputs or {}):
            s["with"] = inputs[s["send"]]
        if s.get("send") == ORIGIN_SERVICE:
            s["with"] = {"origin": {"x": round(x, 3), "y": round(y, 3), "theta": round(theta, 3)}}
        bringup.append(s)
        if s.get("send") == ORIGIN_SERVICE:
            bringup += [dict(a) for a in after_origin or ()]
    goto = {"send": GOAL_SERVICE, "with": {"goal": {"x": round(world.goal[0], 3), "y": round(world.goal[1], 3),
                                                    "theta": 0.0}},
            "expect": "ok", "timeout": round(timeout, 1)}
    mission = {"mission": world.name, "world": str(world_path), "steps": [*bringup, goto]}
    note = note or f"{world.family} world, seed {world.seed}"
    return (f"# {note}: {template.name}'s bring-up, then one GoTo to the goal.\n"
            + yaml.safe_dump(mission, sort_keys=False, default_flow_style=None, width=120))
