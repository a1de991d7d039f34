"""A generated world as an ir-sim world file: walls round it, its obstacle cells merged into polygons, the robot."""
from __future__ import annotations

import copy
from typing import Any

import shapely
import yaml

from genom2bip.mission.worlds.families import GridWorld


def polygons(world: GridWorld) -> list[list[tuple[float, float]]]:
    """The outlines of the world's obstacles: its occupied cells merged, collinear vertices dropped."""
    rows, cols = world.occupied.nonzero()
    c = world.cell
    boxes = shapely.box(cols * c, rows * c, (cols + 1) * c, (rows + 1) * c)
    merged = shapely.union_all(boxes).simplify(0.0)
    parts = getattr(merged, "geoms", [merged]) if not merged.is_empty else []
    out = []
    for part in parts:
        ring = [(round(x, 3), round(y, 3)) for x, y in part.exterior.coords[:-1]]
        out.append(ring)
    return out


def text(world: GridWorld, robot: dict[str, Any]) -> str:
    """The ir-sim YAML of ``world`` with ``robot`` (an ir-sim robot entry, e.g. a DALA world's) at its start."""
    robot = copy.deepcopy(robot)
    robot["state"] = [round(v, 3) for v in world.start]
    w, h = round(world.width, 3), round(world.height, 3)
    obstacles: list[dict[str, Any]] = [{
        "name": "walls", "shape": {"name": "linestring", "vertices": [[0, 0], [w, 0], [w, h], [0, h], [0, 0]]},
        "state": [0, 0, 0]}]
    for k, ring in enumerate(polygons(world)):
        obstacles.append({"name": f"block_{k}", "shape": {"name": "polygon", "vertices": [list(p) for p in ring]},
                          "state": [0, 0, 0]})
    data = {"world": {"width": w, "height": h, "step_time": 0.025, "sample_time": 0.1, "offset": [0, 0],
                      "collision_mode": "stop"},
            "robot": [robot], "obstacle": obstacles}
    d = world.difficulty.as_dict() if world.difficulty else {}
    head = (f"# A generated {world.family} world, seed {world.seed}: from ({world.start[0]:g}, {world.start[1]:.2f}) "
            f"to ({world.goal[0]:g}, {world.goal[1]:.2f}); shortest path with {world.clearance:g} m of clearance "
            f"{world.length:.2f} m.\n# difficulty: " + ", ".join(f"{k} {v:g}" for k, v in d.items()) + "\n")
    return head + yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=120)
