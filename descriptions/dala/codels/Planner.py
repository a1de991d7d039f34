"""Planner: the map seen in the world frame, a global path to NDD's goal over it (planning.py), NDD's next goal.

Run keeps every sweep of Aspect's map (its cells at OCCUPIED, placed at the
pose of the sweep) and, while NDD publishes an active goal in Nav, plans to
it when the map grew, the goal changed, NDD asked for a way round (Nav's
``stalls``: the cells of the way it could not follow then cost AVOID times
more) or the robot left the path; every period it publishes in Way the
farthest point of the path within the lookahead that the robot reaches in a
straight line keeping its radius from what the laser saw, and the length of
the path left.  No path: Way is invalid,
``blocked``, with the reason.  Plan answers once whether a way exists.
"""
import math

from runtime.genom import Throw

from . import grid, memory, planning

SIDE = 64  # dala::map_cells
AVOID = 4.0  # the cost, on the cells of a way NDD could not follow, over the others
AVOID_WIDTH = 0.5  # m round that way's path
OFF_PATH = 1.0  # m from the path: plan again
DEFAULTS = {"robot_radius": 0.35, "clearance": 0.6, "lookahead": 2.0}  # as Planner.gen's SetParams
_state: dict = {}


def _idle(reason: str = "") -> dict:
    return {"valid": False, "blocked": bool(reason), "target": {"x": 0.0, "y": 0.0, "theta": 0.0},
            "remaining": 0.0, "seq": 0, "stalls": 0, "plans": 0, "reason": reason[:127]}


def _clear() -> None:
    _state.update(seen=planning.Seen(), poses=[], obs_seq=None, plan=None, version=-1, seq=None, stalls=0,
                  avoid=set())


_clear()


def plnCheckParams(params):
    if not 0 < params["robot_radius"] <= params["clearance"] or params["lookahead"] <= 0:
        raise Throw("e_bad_params", value=params["robot_radius"])


def plnCheckGoal(goal):
    if not all(math.isfinite(goal[k]) for k in ("x", "y", "theta")):
        raise Throw("e_no_path", where=dict(goal), reason="the goal is not a finite pose")


def see(obs, pos) -> None:
    """Place Obs's last sweep (its cells at OCCUPIED) in the world frame, at the pose of the sweep."""
    poses = _state["poses"]
    now, here = pos["stamp"], pos["estimate"]
    if not poses or now > poses[-1][0]:
        poses.append((now, dict(here)))
    _state["poses"] = [(t, p) for t, p in poses if now - t <= memory.HISTORY]
    if obs is None or obs["seq"] == _state["obs_seq"] or obs["seq"] == 0:
        return
    _state["obs_seq"] = obs["seq"]
    seen = _state["seen"]
    if obs["resolution"] != seen.resolution:
        _state["seen"] = seen = planning.Seen(obs["resolution"])
    at = memory.pose_at(_state["poses"], obs["stamp"])
    points = grid.points(obs["cells"], obs["resolution"], SIDE, threshold=grid.OCCUPIED)
    c, s = math.cos(at["theta"]), math.sin(at["theta"])
    seen.add([(at["x"] + c * x - s * y, at["y"] + s * x + c * y) for x, y in points])


def parameters(params: dict) -> dict:
    """SetParams' values, or the defaults before it (robot_radius still 0)."""
    return params if params["robot_radius"] > 0 else DEFAULTS


def plnReset(Way):
    _clear()
    Way.value = _idle()
    return "watch"


def _replan(params, nav, here, plans) -> None:
    goal = (nav["goal"]["x"], nav["goal"]["y"])
    _state["plan"] = planning.plan(_state["seen"], here, goal, params["robot_radius"], params["clearance"],
                                   _state["avoid"], AVOID)
    _state["version"] = _state["seen"].version
    plans.value = plans.value + 1


def plnWatch(params, plans, Obs, Pos, Nav, Way):
    """One period: see the new sweep, plan again when needed, publish the intermediate goal."""
    if Pos is None:
        return "pause::watch"
    params = parameters(params)
    see(Obs, Pos)
    if Nav is None or not Nav["active"]:
        _state.update(plan=None, seq=None, avoid=set(), stalls=0)
        Way.value = _idle()
        return "pause::watch"
    est = Pos["estimate"]
    here = (est["x"], est["y"])
    p = _state["plan"]
    if Nav["seq"] != _state["seq"]:
        _state.update(seq=Nav["seq"], stalls=0, avoid=set(), plan=None)
        p = None
    if Nav["stalls"] != _state["stalls"]:
        if p is not None:
            _state["avoid"] |= planning.corridor(p, here, AVOID_WIDTH)
        _state["stalls"], p = Nav["stalls"], None
    off = p is not None and min(math.dist(here, q) for q in p.points) > OFF_PATH
    if p is None or off or _state["version"] != _state["seen"].version:
        try:
            _replan(params, Nav, here, plans)
        except planning.NoPath as e:
            _state["plan"] = None
            Way.value = {**_idle(str(e)), "seq": Nav["seq"], "stalls": Nav["stalls"], "plans": plans.value}
            return "pause::watch"
    point, left = planning.target(_state["plan"], here, params["lookahead"])
    Way.value = {"valid": True, "blocked": False, "target": {"x": point[0], "y": point[1], "theta": 0.0},
                 "remaining": left, "seq": Nav["seq"], "stalls": Nav["stalls"], "plans": plans.value, "reason": ""}
    return "pause::watch"


def plnStop(Way):
    Way.value = _idle()
    return "ether"


def plnPlan(goal, params, Pos):
    """Throws e_no_path when no way joins the robot to ``goal`` on the map seen."""
    if Pos is None:
        raise Throw("e_no_path", where=dict(goal), reason="no position yet (POM's Pos)")
    est, params = Pos["estimate"], parameters(params)
    try:
        planning.plan(_state["seen"], (est["x"], est["y"]), (goal["x"], goal["y"]), params["robot_radius"],
                      params["clearance"])
    except planning.NoPath as e:
        raise Throw("e_no_path", where=dict(est), reason=str(e)[:127]) from None
    return "ether"
