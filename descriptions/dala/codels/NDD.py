"""NDD: nearness-diagram navigation (nd.py) towards the goal over Aspect's map Obs, from POM's position Pos.

GoTo fails with e_blocked, its ``reason`` saying which, when no gap leads
towards the goal for NO_WAY_TIMEOUT seconds, or when the robot has not got
PROGRESS metres closer to the goal for PROGRESS_TIMEOUT seconds (simulated
time, from the Pos stamps): a dead end, a goal inside an obstacle or behind a
wall, a trap that holds a reactive method.  A GoTo that starts d metres from
its goal therefore ends within (d / PROGRESS + 1) * PROGRESS_TIMEOUT seconds.

With the Planner running, GoTo publishes its goal in Nav; while the
Planner's Way answers it (``valid`` for this GoTo's ``seq``), ND drives to
Way's intermediate goal, and progress is the path left (Way's ``remaining``)
getting shorter, not the straight distance; a path that grows longer (the
map showed an obstacle on it) starts the progress count afresh.  When no
progress (or no gap) lasts too long and the Planner answers, GoTo asks it for
a way round (``stalls`` one more: it plans again, the way just failed costing
more) up to ASKS times before it throws e_blocked.  Without the Planner, Way
is never valid and GoTo behaves as ND alone.

ND sees the obstacles of Aspect's map within the disc inscribed in it: the
square map holds every return the laser gave within that radius, and only
some beyond it (towards its corners), so the range of ND's information,
``dmax``, is the disc's radius.  Each sweep's returns are remembered in the
world frame for MEMORY seconds (memory.py): what the robot passed, out of
the laser's 180 degrees, still counts.
"""
import math

from runtime.genom import Throw

from . import memory, nd, odometry

STILL = {"v": 0.0, "w": 0.0}
SIDE = 64  # dala::map_cells
NO_WAY_TIMEOUT = 3.0  # s
PROGRESS = 0.2  # m
PROGRESS_TIMEOUT = 20.0  # s: in clutter ND may hesitate between two ways of about the same worth that long
MEMORY = 10.0  # s an obstacle out of sight is remembered
ASKS = 3  # ways round a GoTo asks the Planner for before it gives up
_progress = {"best": math.inf, "since": None, "no_way_since": None, "situation": None, "remaining": None}
_memory = memory.Memory()


def _nav(goal: dict | None = None, active: bool = False, seq: int = 0, stalls: int = 0) -> dict:
    return {"goal": dict(goal or {"x": 0.0, "y": 0.0, "theta": 0.0}), "active": active, "seq": seq, "stalls": stalls}


def _idle(Nav) -> None:
    """Nav with no GoTo running, its goal and counts kept."""
    Nav.value = {**(Nav.value or _nav()), "active": False}


def nddInit(navigating, Speed, Nav):
    navigating.value = False
    Speed.value = dict(STILL)
    Nav.value = _nav()
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


def nddStartGoTo(local_goal, ids_goal, navigating, Nav):
    ids_goal.value = dict(local_goal)
    navigating.value = True
    Nav.value = _nav(local_goal, True, (Nav.value or _nav())["seq"] + 1)
    _progress.update(best=math.inf, since=None, no_way_since=None, remaining=None)
    _memory.clear()  # POM may have been anchored anew since the last GoTo
    return "plan"


def blocked(progress: dict, distance: float, way: bool, now: float) -> str | None:
    """Why the robot is blocked at ``now`` (sim seconds), or None: no navigable valley, or no progress, too long."""
    if progress["since"] is None or distance < progress["best"] - PROGRESS:
        progress.update(best=min(distance, progress["best"]), since=now)
    if way:
        progress["no_way_since"] = None
    elif progress["no_way_since"] is None:
        progress["no_way_since"] = now
    if progress["no_way_since"] is not None and now - progress["no_way_since"] > NO_WAY_TIMEOUT:
        return f"no navigable gap towards the goal for {NO_WAY_TIMEOUT:g} s"
    if now - progress["since"] > PROGRESS_TIMEOUT:
        return (f"no progress of {PROGRESS:g} m towards the goal in {PROGRESS_TIMEOUT:g} s: a local minimum "
                "(a trap, or a way round that the local map does not show)")
    return None


def planned(way: dict | None, nav: dict) -> dict | None:
    """The Planner's answer to this GoTo, or None (no Planner, no path, or an answer to an older request)."""
    if way is None or not way["valid"] or way["seq"] != nav["seq"] or way["stalls"] != nav["stalls"]:
        return None
    return way


def ask_for_way_round(progress: dict, nav, now: float) -> bool:
    """Ask the Planner for a way round (Nav's stalls one more, the progress count afresh); False when asked enough."""
    if nav.value["stalls"] >= ASKS:
        return False
    nav.value = {**nav.value, "stalls": nav.value["stalls"] + 1}
    progress.update(best=math.inf, since=now, no_way_since=None, remaining=None)
    return True


def nddPlan(goal, params, max_speed, Obs, Pos, Way, Speed, Nav):
    """One ND step towards the goal, or the Planner's intermediate goal (nd.py); e_blocked when it cannot get closer."""
    if Pos is None:
        _idle(Nav)
        raise Throw("e_no_goal")
    here = Pos["estimate"]
    target = odometry.between(here, goal)
    distance = math.hypot(target["x"], target["y"])
    if distance <= params["goal_tolerance"]:
        return "arrived"
    way = planned(Way, Nav.value or _nav())
    if way is not None:
        if _progress["remaining"] is not None and way["remaining"] > _progress["remaining"] + PROGRESS:
            _progress.update(best=math.inf, since=None)  # a longer way than before: the map showed an obstacle
        _progress["remaining"] = way["remaining"]
        target = odometry.between(here, way["target"])
        distance = way["remaining"]
    cell = Obs["resolution"] if Obs else 0.1
    dmax = SIDE / 2 * cell
    points = memory.update(_memory, Obs, Pos, SIDE, MEMORY, 2 * dmax)
    setting = nd.Params(radius=params["robot_radius"], security=params["security_distance"], dmax=dmax,
                        vmax=max_speed["v"], wmax=max_speed["w"], cell=cell)
    kept = odometry.between(here, _memory.heading_for) if _memory.heading_for else None
    decision = nd.decide(points, (target["x"], target["y"]), setting, (kept["x"], kept["y"]) if kept else None)
    _memory.heading_for = None
    if decision is not None and not decision.area.goal_region:
        x, y = decision.area.target
        _memory.heading_for = odometry.compose(here, {"x": x, "y": y, "theta": 0.0})
    why = blocked(_progress, distance, decision is not None, Pos["stamp"])
    if why and way is not None and ask_for_way_round(_progress, Nav, Pos["stamp"]):
        why = None
    elif why and Nav.value and Nav.value["stalls"]:
        why = why.split(":")[0] + f", after {Nav.value['stalls']} way(s) round from the planner"
    if decision is None or why:
        Speed.value = dict(STILL)
    else:
        Speed.value = {"v": decision.v, "w": decision.w}
        _progress["situation"] = decision.situation
    if why:
        _idle(Nav)
        raise Throw("e_blocked", where=dict(here), reason=why)
    return "pause::plan"


def nddArrived(navigating, Speed, Nav):
    navigating.value = False
    Speed.value = dict(STILL)
    _idle(Nav)
    return "ether"


def nddStopGoTo(navigating, Speed, Nav):
    navigating.value = False
    Speed.value = dict(STILL)
    _idle(Nav)
    return "ether"


def nddStop(Speed, Nav):
    Speed.value = dict(STILL)
    _idle(Nav)
    return "ether"
