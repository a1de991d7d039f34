"""The nearness-diagram (ND) navigation method (Minguez & Montano, IEEE T-RA 20(1), 2004), in the robot frame.

One call, :func:`decide`, goes through the method's steps:

1. **Sectors**: the plane around the robot is cut into ``n`` angular sectors;
   each keeps its nearest obstacle point within ``dmax``, the range of the
   obstacle information.  A sector with none is free.
2. **PND**, the nearness diagram from the central point:
   ``PND[k] = dmax + 2R - d[k]`` for an occupied sector, 0 for a free one.
3. **Gaps** (discontinuities): between neighbouring sectors whose nearness
   differs by more than the robot's diameter 2R.  As every obstacle counted is
   within ``dmax``, an occupied sector beside a free one is always a gap.
4. **Regions** are the runs of sectors between two gaps; a **valley** is a
   region with a *rising* gap (the nearness rises when one leaves it).
5. The **free walking area**: the goal's own region when the goal is in sight
   and the robot can reach it, else the valley whose rising gap is nearest to
   the goal and that the robot can reach.  *Reachable* is the method's
   navigability test: along the way to the goal (or to the point where it
   passes the gap), no obstacle on the left stands closer than 2R to one on
   the right, and none within R of the point itself.
6. **Situations**: low safety (an obstacle nearer than the security distance Ds
   to the robot's boundary) LS1 (on one side of the free walking area's
   direction) or LS2 (on both sides); high safety HSGR (the goal is in the free
   walking area), HSWR (wide area, more than a quarter of the sectors) or HSNR
   (narrow).
7. **Actions**: HSGR the goal's direction; HSWR past the rising gap's obstacle
   with R + Ds to spare; HSNR the middle of the area; LS1 that direction of the
   area turned away from the closest obstacle, the more the deeper it is in
   the security zone; LS2 the area's direction turned towards the side whose
   closest obstacle is the farther, so that the robot keeps in the middle.
   Then the speeds: ``v = vmax · c · cos θ``, ``w = wmax · c · sin θ`` (θ
   bounded to ±90°), ``c`` the depth of the closest obstacle in the security
   zone (1 in high safety, no less than 0.2), ``v`` no more than ``wmax · d_goal
   / 2`` so that the turning radius keeps within half the distance left.

No reachable area gives ``None``: the robot cannot move towards the goal.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

TWO_PI = 2 * math.pi
SITUATIONS = ("HSGR", "HSWR", "HSNR", "LS1", "LS2")
CREEP = 0.2  # the least speed factor in low safety: the robot keeps moving away from what is near
KEEP = math.radians(30)  # a valley whose direction is this near the one the robot headed for still leads there
LOYALTY = math.radians(60)  # and it counts as this much nearer the goal than it is


@dataclass(frozen=True)
class Params:
    radius: float  # R, m
    security: float  # Ds: distance from the robot's boundary below which it is in low safety, m
    dmax: float  # range of the obstacle information: obstacles farther away are not counted, m
    sectors: int = 144
    cell: float = 0.0  # the size of the obstacle cells the points stand for, m
    vmax: float = 0.3
    wmax: float = 0.5


@dataclass(frozen=True)
class Area:
    """The free walking area: sectors first..last (counter-clockwise, inclusive) and the point the robot heads for."""

    first: int
    last: int
    rising: int  # the area's sector at its rising gap (the goal's sector for the goal's own region)
    outside: int  # the sector across the rising gap, whose obstacle the robot passes (-1 for the goal's region)
    target: tuple[float, float]  # the goal, or the point past the rising gap (robot frame)

    @property
    def goal_region(self) -> bool:
        return self.outside < 0


@dataclass(frozen=True)
class Decision:
    situation: str  # one of SITUATIONS
    direction: float  # rad, robot frame: the solution of the situation's action
    v: float
    w: float
    area: Area


def wrap(a: float) -> float:
    """The angle ``a`` in [-pi, pi)."""
    return (a + math.pi) % TWO_PI - math.pi


def sector_of(angle: float, n: int) -> int:
    return int((wrap(angle) + math.pi) / TWO_PI * n) % n


def angle_of(k: int, n: int) -> float:
    return -math.pi + (k + 0.5) * TWO_PI / n


@dataclass(frozen=True)
class Sectors:
    """Per sector, the distance of its nearest obstacle point within dmax (``inf``: free) and that point."""

    d: list[float]
    points: list[tuple[float, float] | None]

    def __len__(self) -> int:
        return len(self.d)


def sectorise(points: list[tuple[float, float]], n: int, size: float = 0.0, dmax: float = math.inf) -> Sectors:
    """The sectors' nearest points within ``dmax``.

    A point stands for an obstacle cell ``size`` wide: it fills every sector
    its width covers, so that a near wall leaves no false free sector between
    two cells; the sector keeps the point itself (its true direction), as the
    method's navigability test needs.
    """
    d: list[float] = [math.inf] * n
    nearest: list[tuple[float, float] | None] = [None] * n
    width = TWO_PI / n
    for x, y in points:
        r = math.hypot(x, y)
        if r > dmax:
            continue
        centre = math.atan2(y, x)
        half = math.atan2(size / 2, r) if size > 0 else 0.0
        for k in range(math.floor((centre - half) / width), math.floor((centre + half) / width) + 1):
            a = sector_of(k * width + width / 2, n)
            if r < d[a]:
                d[a], nearest[a] = r, (x, y)
    return Sectors(d, nearest)


def distances(points: list[tuple[float, float]], n: int, size: float = 0.0, dmax: float = math.inf) -> list[float]:
    """Per sector, the distance of its nearest point within ``dmax`` (``inf`` when the sector is free)."""
    return sectorise(points, n, size, dmax).d


def nearness(d: list[float], p: Params) -> list[float]:
    """The PND: high where an obstacle is near, 0 where the sector is free."""
    return [p.dmax + 2 * p.radius - r if r < math.inf else 0.0 for r in d]


def gaps(d: list[float], p: Params) -> list[int]:
    """Indices k such that sectors k and k+1 (cyclic) are separated by a discontinuity of the PND."""
    n, pnd = len(d), nearness(d, p)
    return [k for k in range(n) if (d[k] == math.inf) != (d[(k + 1) % n] == math.inf)
            or abs(pnd[k] - pnd[(k + 1) % n]) > 2 * p.radius]


def reachable(target: tuple[float, float], s: Sectors, p: Params) -> bool:
    """The navigability test: the robot fits all the way to ``target`` between the obstacles on each side of it.

    Two obstacles both beside the robot (less than R ahead of it) do not count
    as a pair: it already stands between them.
    """
    length = math.hypot(*target)
    if length < 1e-9:
        return True
    ux, uy = target[0] / length, target[1] / length
    left, right = [], []
    for point in s.points:
        if point is None:
            continue
        x, y = point
        along, across = x * ux + y * uy, -x * uy + y * ux
        if along < 0 or along >= length or abs(across) > 2 * p.radius:
            continue
        if math.hypot(x - target[0], y - target[1]) < p.radius:
            return False  # the point to reach is inside an obstacle's reach
        (left if across > 0 else right).append((x, y, along < p.radius))
    limit = (2 * p.radius) ** 2
    return not any((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 < limit and not (a[2] and b[2])
                   for a in left for b in right)


def clear(goal: tuple[float, float], s: Sectors, margin: float) -> bool:
    """Does the straight way to the goal keep ``margin`` from every obstacle ahead (the goal's surroundings included)?

    What is beside or behind the robot does not count: it is already there.
    """
    length = math.hypot(*goal)
    if length < 1e-9:
        return True
    ux, uy = goal[0] / length, goal[1] / length
    for point in s.points:
        if point is not None:
            along, across = point[0] * ux + point[1] * uy, -point[0] * uy + point[1] * ux
            if 0 < along < length + margin and abs(across) < margin:
                return False
    return True


def _run(first: int, last: int, n: int) -> int:
    return (last - first) % n + 1


def regions(d: list[float], p: Params) -> list[tuple[int, int]]:
    """The runs of sectors between consecutive gaps, as (first, last), counter-clockwise; one run without gaps."""
    n = len(d)
    cuts = gaps(d, p)
    if not cuts:
        return [(0, n - 1)]
    return [((cut + 1) % n, cuts[(i + 1) % len(cuts)]) for i, cut in enumerate(cuts)]


def _pass_point(inside: int, outside: int, s: Sectors, p: Params) -> tuple[float, float]:
    """Where the robot heads to go through a rising gap: between its two obstacles, or past the edge into free space."""
    (x2, y2) = s.points[outside]
    if s.points[inside] is not None:
        x1, y1 = s.points[inside]
        return (x1 + x2) / 2, (y1 + y2) / 2
    n = len(s)
    edge = math.atan2(y2, x2)
    a = edge + wrap(angle_of(inside, n) - edge) / 2
    reach = s.d[outside] + p.dmax  # into the free space, well past the edge
    return reach * math.cos(a), reach * math.sin(a)


def free_walking_area(s: Sectors, goal: tuple[float, float], p: Params,
                      keep: tuple[float, float] | None = None) -> Area | None:
    """The goal's region when the goal is in sight and reachable, else the reachable valley nearest the goal.

    When the straight way to a goal in sight passes nearer an obstacle than
    R + Ds/2 and the goal's region has a rising gap the robot can pass, that
    gap is the free walking area: the robot rounds the obstacle with room to
    spare instead of brushing it (the goal's region stays its way otherwise).
    ``keep``, the point the robot headed for at the last step, favours the
    valley that still leads there (within KEEP of its direction): it counts as
    LOYALTY nearer the goal than it is.  In clutter two valleys on either side of
    the goal are often about as near to it, and a robot that turns to one
    whenever the other is nearer by a sector goes nowhere.
    """
    n, d = len(s), s.d
    g_angle = math.atan2(goal[1], goal[0])
    g = sector_of(g_angle, n)
    runs = regions(d, p)
    home = next(r for r in runs if (g - r[0]) % n < _run(*r, n))
    goal_area = Area(home[0], home[1], g, -1, goal) if math.hypot(*goal) <= d[g] and reachable(goal, s, p) else None
    if goal_area is not None and clear(goal, s, p.radius + p.security / 2):
        return goal_area
    candidates = []
    for first, last in runs:
        if _run(first, last, n) == n:
            continue  # no gap at all: nothing to pass
        for inside, outside in ((first, (first - 1) % n), (last, (last + 1) % n)):
            if d[outside] < d[inside]:  # the nearness rises when leaving the region here: a rising gap
                edge = angle_of(inside, n) + wrap(angle_of(outside, n) - angle_of(inside, n)) / 2
                candidates.append((abs(wrap(edge - g_angle)), first, last, inside, outside))
    areas = []
    for off, first, last, inside, outside in sorted(candidates):
        target = _pass_point(inside, outside, s, p)
        if reachable(target, s, p):
            areas.append((off, Area(first, last, inside, outside, target)))
    if goal_area is not None:
        return next((a for _, a in areas if (a.first, a.last) == home), goal_area)
    if keep is not None and areas:
        towards = math.atan2(keep[1], keep[0])
        ranked = [(off - LOYALTY if abs(wrap(math.atan2(a.target[1], a.target[0]) - towards)) <= KEEP else off, i)
                  for i, (off, a) in enumerate(areas)]
        return areas[min(ranked)[1]][1]
    return areas[0][1] if areas else None


def _towards_area(area: Area, n: int) -> int:
    """+1 when the area lies counter-clockwise of its rising gap, else -1."""
    return 1 if area.rising == area.first else -1


def _depth(r: float, p: Params) -> float:
    """How far an obstacle at ``r`` is from the robot's boundary, as a fraction of Ds (0 touching, 1 safe)."""
    return max(0.0, min(1.0, (r - p.radius) / p.security))


def _high_safety(area: Area, s: Sectors, goal_angle: float, p: Params) -> tuple[str, float]:
    """The situation and direction when no obstacle is in the security zone."""
    n = len(s)
    if area.goal_region:
        return "HSGR", goal_angle
    width = _run(area.first, area.last, n)
    if width > n // 4:
        x, y = s.points[area.outside]
        side = _towards_area(area, n)
        return "HSWR", wrap(math.atan2(y, x) + side * math.atan2(p.radius + p.security, s.d[area.outside]))
    middle = angle_of(area.first, n) + (width - 1) / 2 * TWO_PI / n
    return "HSNR", wrap(middle)


def decide(points: list[tuple[float, float]], goal: tuple[float, float], p: Params,
           keep: tuple[float, float] | None = None) -> Decision | None:
    """The ND step: the situation, the motion direction and the speeds; None when no area is reachable."""
    n = p.sectors
    s = sectorise(points, n, p.cell, p.dmax)
    area = free_walking_area(s, goal, p, keep)
    if area is None:
        return None
    g_angle = math.atan2(goal[1], goal[0])
    situation, direction = _high_safety(area, s, g_angle, p)
    reference = math.atan2(area.target[1], area.target[0])
    near = [(r, math.atan2(pt[1], pt[0])) for r, pt in zip(s.d, s.points)
            if pt is not None and r - p.radius < p.security]
    left = min(((r, a) for r, a in near if wrap(a - reference) > 0), default=None)
    right = min(((r, a) for r, a in near if wrap(a - reference) <= 0), default=None)
    if left and right:
        situation = "LS2"
        cl, cr = _depth(left[0], p), _depth(right[0], p)
        share = (cl - cr) / (cl + cr) if cl + cr > 0 else 0.0
        bound = reference + math.pi / 2 if share > 0 else reference - math.pi / 2  # the freer side
        direction = wrap(reference + abs(share) * wrap(bound - reference))
    elif left or right:
        situation = "LS1"
        r, a = left or right
        c = _depth(r, p)
        off = wrap(direction - a)  # how far the direction already turns from the obstacle
        side = 1.0 if off >= 0 else -1.0
        bound = math.pi / 2 + (1 - c) * math.pi / 6  # past the obstacle's tangent, and away from it when deep
        if abs(off) < bound:  # turned towards that bound, the more the deeper the obstacle is
            direction = wrap(a + side * (abs(off) + (1 - c) * (bound - abs(off))))
    v, w = speeds(direction, near, math.hypot(*goal), s, p)
    return Decision(situation, direction, v, w, area)


def speeds(direction: float, near: list[tuple[float, float]], distance: float, s: Sectors,
           p: Params) -> tuple[float, float]:
    """v and w for the direction: slower the deeper an obstacle ahead of the motion is in the security zone.

    ``near`` holds the (distance, bearing) of the obstacles in the security zone;
    those behind the motion (more than 90 degrees from it) do not slow the robot,
    which moves away from them.  The direction is bounded to +-90 degrees: the
    robot turns in place towards what is behind it.  Near the goal v keeps the
    turning radius within half the distance left; v is also bounded by how far
    the robot can drive straight on, and when that is nothing it turns in place
    at full rate (a disc turns in place safely).
    """
    steer = max(-math.pi / 2, min(math.pi / 2, direction))
    c = min((_depth(r, p) for r, a in near if abs(wrap(a - steer)) < math.pi / 2), default=1.0)
    c = max(CREEP, c)
    room = max(0.0, min(1.0, ahead(s, p) / p.security))
    turn = max(c, abs(steer) / (math.pi / 2)) if room > 0 else 1.0  # arcs as at full speed; in place at full rate
    w = p.wmax * turn * max(-1.0, min(1.0, steer / (math.pi / 4)))
    v = max(0.0, p.vmax * c * math.cos(steer))
    bend = abs(math.sin(steer))
    if bend > 1e-9:  # the arc the robot drives on must not pass beyond the goal: radius v/w <= distance / (2 sin)
        v = min(v, abs(w) * distance / (2 * bend))
    return min(v, p.vmax * room), w


def ahead(s: Sectors, p: Params) -> float:
    """How far the robot can drive straight on before it touches an obstacle (0: it does).

    The robot is a disc of radius R less half a cell: an obstacle point (a
    cell's centre) beside the robot within that precision of R does not stop it.
    """
    body = p.radius - p.cell / 2
    free = math.inf
    for point in s.points:
        if point is not None and point[0] > 0 and abs(point[1]) < body:
            free = min(free, point[0] - math.sqrt(body ** 2 - point[1] ** 2))
    return max(0.0, free)
