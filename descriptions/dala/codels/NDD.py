"""NDD, simulated: heads for the goal, slows down near obstacles of the map, throws e_blocked when stuck."""
import math

from runtime.genom import Throw

STILL = {"v": 0.0, "w": 0.0}
SIDE = 64


def nddInit(navigating, Speed):
    navigating.value = False
    Speed.value = dict(STILL)
    return "publish"


def nddPublishIdle(navigating, Speed):
    if not navigating:
        Speed.value = dict(STILL)
    return "pause::publish"


def nddShutdown(Speed):
    Speed.value = dict(STILL)
    return "ether"


def nddCheckParams(params):
    if params["robot_radius"] <= 0 or params["goal_tolerance"] <= 0:
        raise Throw("e_bad_params", value=min(params["robot_radius"], params["goal_tolerance"]))


def nddCheckSpeed(max_speed):
    if not 0 < max_speed["v"] <= 1.5 or not 0 < max_speed["w"] <= 3:
        raise Throw("e_bad_params", value=max_speed["v"])


def nddSetDataSource(obs, pos, obs_source, pos_source):
    obs_source.value, pos_source.value = obs, pos
    return "ether"


def nddCheckGoal(goal):
    if not all(math.isfinite(goal[k]) for k in ("x", "y", "theta")):
        raise Throw("e_no_goal")


def nddStartGoTo(local_goal, ids_goal, navigating):
    ids_goal.value = dict(local_goal)
    navigating.value = True
    return "plan"


def _clearance(obs, heading):
    """Distance to the nearest occupied cell within 15 degrees of ``heading`` (robot frame), in m."""
    if obs is None:
        return math.inf
    res, best = obs["resolution"], math.inf
    for k, cell in enumerate(obs["cells"]):
        if cell:
            x, y = (k % SIDE - SIDE // 2) * res, (k // SIDE - SIDE // 2) * res
            if abs(math.atan2(y, x) - heading) < math.pi / 12:
                best = min(best, math.hypot(x, y))
    return best


def nddPlan(goal, params, max_speed, Obs, Pos, Speed):
    if Pos is None:
        raise Throw("e_no_goal")
    p = Pos["estimate"]
    dx, dy = goal["x"] - p["x"], goal["y"] - p["y"]
    distance = math.hypot(dx, dy)
    if distance <= params["goal_tolerance"]:
        return "arrived"
    heading = math.atan2(math.sin(math.atan2(dy, dx) - p["theta"]), math.cos(math.atan2(dy, dx) - p["theta"]))
    room = _clearance(Obs, heading) - params["robot_radius"]
    if room < params["security_distance"] / 2:
        Speed.value = dict(STILL)
        raise Throw("e_blocked", where=dict(p))
    v = min(max_speed["v"], max(distance, 0.2), max(0.0, room - params["security_distance"]))
    v *= max(0.0, math.cos(heading))
    Speed.value = {"v": v, "w": max(-max_speed["w"], min(max_speed["w"], 1.5 * heading))}
    return "pause::plan"


def nddArrived(navigating, Speed):
    navigating.value = False
    Speed.value = dict(STILL)
    return "ether"


def nddStopGoTo(navigating, Speed):
    navigating.value = False
    Speed.value = dict(STILL)
    return "ether"


def nddStop(Speed):
    Speed.value = dict(STILL)
    return "ether"
