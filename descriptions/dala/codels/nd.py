"""The nearness-diagram (ND) navigation method (Minguez & Montano, IEEE T-RA 20(1), 2004), in the robot frame.

One call, :func:`decide`, goes through the method's steps:

1. **Sectors**: the plane around the robot is cut into ``n`` angular sectors;
   each keeps the distance of its nearest obstacle point.
2. **PND**, the nearness diagram from the central point:
   ``PND[k] = dmax + 2R - d[k]`` for an occupied sector, 0 for a free one.
3. **Gaps** (discontinuities): between neighbouring sectors whose nearness
   differs by more than the robot's diameter 2R.
4. **Regions** are the runs of sectors between two gaps; a **valley** is a
   region with a *rising* gap (the nearness rises when one leaves it).
5. The **free walking area** is the navigable valley whose rising gap is
   closest to the goal: navigable when the gap is at least 2R wide.
6. **Situations**: low safety (an obstacle within the security distance)
   LS1 (on one side of the gap) or LS2 (on both sides); high safety HSGR
   (the goal is in the free walking area), HSWR (wide area) or HSNR (narrow).
7. **Actions**: the motion direction of the situation, then the speeds.

No navigable valley gives ``None``: the robot cannot move towards the goal.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

TWO_PI = 2 * math.pi


@dataclass(frozen=True)
class Params:
    radius: float  # R, m
    security: float  # Ds: distance from the robot's boundary below which it is in low safety, m
    dmax: float  # range of the obstacle information, m
    sectors: int = 144
    cell: float = 0.0  # the size of the obstacle cells the points stand for, m
    vmax: float = 0.3
    wmax: float = 0.5


@dataclass(frozen=True)
class Valley:
    first: int  # sectors first..last (cyclic), inclusive
    last: int
    rising: int  # the rising gap: index of the valley's sector next to it
    other: int  # the valley's sector at its other end


@dataclass(frozen=True)
class Decision:
    situation: str  # LS1, LS2, HSGR, HSWR, HSNR
    direction: float  # rad, robot frame
    v: float
    w: float
    valley: Valley


def wrap(a: float) -> float:
    """The angle ``a`` in [-pi, pi)."""
    return (a + math.pi) % TWO_PI - math.pi


def sector_of(angle: float, n: int) -> int:
    return int((wrap(angle) + math.pi) / TWO_PI * n) % n


def angle_of(k: int, n: int) -> float:
    return -math.pi + (k + 0.5) * TWO_PI / n


def distances(points: list[tuple[float, float]], n: int, size: float = 0.0) -> list[float]:
    """Per sector, the distance of its nearest point (``inf`` when the sector is free).

    A point stands for an obstacle cell ``size`` wide: it fills every sector
    its width covers, so that a near wall leaves no false free sector between
    two cells.
    """
    d = [math.inf] * n
    width = TWO_PI / n
    for x, y in points:
        r = math.hypot(x, y)
        centre = math.atan2(y, x)
        half = math.atan2(size / 2, r) if size > 0 else 0.0
        for k in range(math.floor((centre - half) / width), math.floor((centre + half) / width) + 1):
            a = sector_of(k * width + width / 2, n)
            d[a] = min(d[a], r)
    return d


def nearness(d: list[float], p: Params) -> list[float]:
    """The PND: high where an obstacle is near, 0 where the sector is free."""
    return [p.dmax + 2 * p.radius - r if r < math.inf else 0.0 for r in d]


def gaps(pnd: list[float], p: Params) -> list[int]:
    """Indices k such that sectors k and k+1 (cyclic) are separated by a discontinuity."""
    n = len(pnd)
    return [k for k in range(n) if abs(pnd[k] - pnd[(k + 1) % n]) > 2 * p.radius]


def valleys(pnd: list[float], p: Params) -> list[Valley]:
    """The regions between consecutive gaps that have a rising gap (both, when both rise)."""
    n = len(pnd)
    cuts = gaps(pnd, p)
    out: list[Valley] = []
    for i, cut in enumerate(cuts):
        first, last = (cut + 1) % n, cuts[(i + 1) % len(cuts)]
        before, after = cut, (last + 1) % n  # the sectors outside, across each gap
        if pnd[before] > pnd[first]:
            out.append(Valley(first, last, rising=first, other=last))
        if pnd[after] > pnd[last]:
            out.append(Valley(first, last, rising=last, other=first))
    return out


def members(v: Valley, n: int) -> list[int]:
    return [(v.first + i) % n for i in range((v.last - v.first) % n + 1)]


def _point(k: int, d: list[float]) -> tuple[float, float]:
    a = angle_of(k, len(d))
    return d[k] * math.cos(a), d[k] * math.sin(a)


def gap_width(v: Valley, d: list[float], p: Params) -> float:
    """How wide the rising gap is: from the obstacle edge it starts at to the nearest obstacle on the valley's side."""
    n = len(d)
    outside = (v.rising - 1) % n if v.rising == v.first else (v.rising + 1) % n
    ex, ey = _point(outside, d)
    inside = set(members(v, n))
    best = math.inf
    for k, r in enumerate(d):
        if r < math.inf and k in inside and r <= d[outside] + 2 * p.radius:
            x, y = _point(k, d)
            best = min(best, math.hypot(x - ex, y - ey))
    return best


def free_walking_area(d: list[float], goal: tuple[float, float], p: Params) -> Valley | None:
    """The navigable valley whose rising gap is closest to the goal's direction (None: no way out)."""
    n = p.sectors
    pnd = nearness(d, p)
    g = sector_of(math.atan2(goal[1], goal[0]), n)
    found = valleys(pnd, p)
    if not any(pnd):  # nothing in sight: the whole plane is one free region
        return Valley(0, n - 1, rising=g, other=g)
    if straight(d, goal, p):  # the goal is nearer than every obstacle on the way: its own region
        return goal_region(d, goal, n)
    ranked = sorted(found, key=lambda v: abs(_sector_gap(v.rising, g, n)))
    for v in ranked:
        if gap_width(v, d, p) > 2 * p.radius:
            return v
    return None


def straight(d: list[float], goal: tuple[float, float], p: Params) -> bool:
    """Can the robot drive straight to the goal: no obstacle within R + Ds/2 of the segment to it?"""
    gx, gy = goal
    length = math.hypot(gx, gy)
    if length < 1e-9:
        return True
    ux, uy = gx / length, gy / length
    for k, r in enumerate(d):
        if r < math.inf:
            x, y = _point(k, d)
            along = x * ux + y * uy
            margin = p.radius + p.security / 2
            if -margin < along < length + margin and abs(x * uy - y * ux) < margin:
                return False
    return True


def goal_region(d: list[float], goal: tuple[float, float], n: int) -> Valley:
    """The sectors around the goal's whose obstacles lie beyond the goal: the goal is in the free walking area."""
    g = sector_of(math.atan2(goal[1], goal[0]), n)
    reach = math.hypot(*goal)
    first = last = g
    while d[(first - 1) % n] > reach and (first - 1) % n != g:
        first = (first - 1) % n
    while d[(last + 1) % n] > reach and (last + 1) % n != first:
        last = (last + 1) % n
    return Valley(first, last, rising=g, other=g)


def _sector_gap(a: int, b: int, n: int) -> int:
    """Signed number of sectors from b to a, in (-n/2, n/2]."""
    return (a - b + n // 2) % n - n // 2


def _toward_valley(v: Valley) -> int:
    """+1 when the valley lies counter-clockwise from its rising gap, else -1."""
    return 1 if v.rising == v.first else -1


def speed_factor(d: list[float], direction: float, p: Params) -> float:
    """1 in high safety; in low safety, how deep the nearest obstacle ahead (within 45 degrees) is in the security zone.

    An obstacle to the side slows the robot to no less than a quarter: it moves
    away from it along the direction, which the low-safety actions turned
    away from the obstacle.
    """
    n = len(d)
    ahead = [r for k, r in enumerate(d) if abs(wrap(angle_of(k, n) - direction)) < math.pi / 4]
    side = [r for k, r in enumerate(d) if abs(wrap(angle_of(k, n) - direction)) < math.pi / 2]

    def depth(r: float) -> float:
        return max(0.0, min(1.0, (r - p.radius) / p.security))

    front = depth(min(ahead, default=math.inf))
    return min(front, max(0.25, depth(min(side, default=math.inf))))


def decide(points: list[tuple[float, float]], goal: tuple[float, float], p: Params) -> Decision | None:
    """The ND step: the situation, the motion direction and the speeds; None when no valley is navigable."""
    n = p.sectors
    d = distances(points, n, p.cell)
    v = free_walking_area(d, goal, p)
    if v is None:
        return None
    inside = members(v, n)
    g_angle = math.atan2(goal[1], goal[0])
    sector = TWO_PI / n
    smax = n // 4
    rd = angle_of(v.rising, n)
    side = _toward_valley(v)
    if v.rising == v.other:  # the goal's own region
        situation, direction = "HSGR", g_angle
    elif len(inside) >= smax:
        situation, direction = "HSWR", rd + side * (smax / 2) * sector
    else:
        situation, direction = "HSNR", wrap(rd + side * len(inside) / 2 * sector)
    near = [(k, r) for k, r in enumerate(d) if r - p.radius < p.security]
    if near:
        # The sides are those of the gap the robot heads for: the edge between its outer and valley sectors.
        ref = g_angle if v.rising == v.other else rd - side * sector / 2
        left = [(k, r) for k, r in near if wrap(angle_of(k, n) - ref) > 0]
        right = [(k, r) for k, r in near if wrap(angle_of(k, n) - ref) <= 0]
        if left and right:
            situation = "LS2"
            kl, dl = min(left, key=lambda kr: kr[1])
            kr_, dr = min(right, key=lambda kr: kr[1])
            middle = wrap(angle_of(kr_, n) + wrap(angle_of(kl, n) - angle_of(kr_, n)) / 2)
            direction = wrap(middle + (dl - dr) / (dl + dr) * math.pi / 2)  # away from the nearer side
        else:
            situation = "LS1"
            ko, do = min(near, key=lambda kr: kr[1])
            away = wrap(direction - angle_of(ko, n))  # > 0: the obstacle is on the right of the direction
            depth = min(1.0, max(0.0, 1 - (do - p.radius) / p.security))
            push = max(0.0, math.pi / 2 - abs(away)) * depth
            direction = wrap(direction + math.copysign(push, away))
    direction = wrap(direction)
    safety = speed_factor(d, direction, p)
    heading = max(0.0, 1 - abs(direction) / (math.pi / 2))
    # near the goal the robot slows down so that its turning radius v/w stays within half the distance left
    v_ = min(p.vmax, p.wmax * math.hypot(*goal) / 2) * safety * heading
    w_ = p.wmax * max(-1.0, min(1.0, direction / (math.pi / 2)))
    return Decision(situation, direction, v_, w_, v)
