"""Geofences: a circle or a polygon fixed in the NED frame (the mission origin is ``(0, 0)``),
which every waypoint of a plan, join included, must stay inside.

Part of the limits (:mod:`planner._limits`), in a module of its own because the vehicle needs
it only when it is given a geofence: ``validate`` imports it then.
"""

from __future__ import annotations

import math

from codec._record import Record, init
from planner._errors import Violation, finite_positive

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Sequence

    from planner._plan import Plan

#: The parameters that set how far each pattern reaches (named in geofence violations).
EXTENT_PARAMS = {
    "straight": ("duration", "speed", "heading"),
    "square": ("side_span",),
    "lawnmower": ("sweep_length", "lane_spacing", "laps"),
    "circle": ("radius",),
    "spiral": ("initial_radius", "final_radius"),
    "helix": ("radius",),
    "hover": (),
    "box_orbit": ("radius",),
    "surface": (),
}


class CircleFence(Record):
    """Stay within ``radius_m`` of ``centre`` (NED metres, default the mission origin)."""

    __slots__ = ("centre", "radius_m")
    radius_m: float
    centre: tuple[float, float]

    def __init__(self, radius_m: float, centre: tuple[float, float] = (0.0, 0.0)) -> None:
        init(self, "radius_m", finite_positive("geofence radius_m", radius_m))
        init(self, "centre", (float(centre[0]), float(centre[1])))

    def contains(self, x_m: float, y_m: float) -> bool:
        return math.hypot(x_m - self.centre[0], y_m - self.centre[1]) <= self.radius_m + 1e-9

    def crosses(self, a: tuple[float, float], b: tuple[float, float]) -> bool:
        """A disc is convex: a segment between two inside points never leaves it."""
        return False

    def describe(self) -> str:
        c = self.centre
        return f"geofence circle of {self.radius_m:g} m around ({c[0]:g} N, {c[1]:g} E)"


class PolygonFence(Record):
    """Stay inside a simple polygon given by its vertices ``(x_m, y_m)`` in NED metres."""

    __slots__ = ("vertices",)
    vertices: tuple[tuple[float, float], ...]

    def __init__(self, vertices: Sequence[tuple[float, float]]) -> None:
        pts = tuple((float(x), float(y)) for x, y in vertices)
        if len(pts) < 3:
            raise ValueError(f"a geofence polygon needs at least 3 vertices, got {len(pts)}")
        if not all(math.isfinite(v) for p in pts for v in p):
            raise ValueError("geofence polygon vertices must be finite numbers")
        n = len(pts)
        for i in range(n):
            for j in range(i + 1, n):
                if j in (i + 1, (i - 1) % n) or (i == 0 and j == n - 1):
                    continue
                if _segments_cross(pts[i], pts[(i + 1) % n], pts[j], pts[(j + 1) % n]):
                    raise ValueError(f"the geofence polygon crosses itself (edges {i} and {j})")
        area2 = sum(
            pts[i][0] * pts[(i + 1) % len(pts)][1] - pts[(i + 1) % len(pts)][0] * pts[i][1]
            for i in range(len(pts))
        )
        if abs(area2) < 1e-9:
            raise ValueError("the geofence polygon has no area")
        init(self, "vertices", pts)

    def contains(self, x_m: float, y_m: float) -> bool:
        inside = False
        pts = self.vertices
        for i in range(len(pts)):
            (ax, ay), (bx, by) = pts[i - 1], pts[i]
            if (ay > y_m) != (by > y_m):
                xc = ax + (y_m - ay) * (bx - ax) / (by - ay)
                if x_m < xc:
                    inside = not inside
        return inside

    def crosses(self, a: tuple[float, float], b: tuple[float, float]) -> bool:
        """Does segment ``ab`` cross an edge (a concave fence can be left between points)?"""
        pts = self.vertices
        return any(_segments_cross(a, b, pts[i - 1], pts[i]) for i in range(len(pts)))

    def describe(self) -> str:
        return f"geofence polygon of {len(self.vertices)} vertices"


def _orient(p: tuple[float, float], q: tuple[float, float], r: tuple[float, float]) -> float:
    return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])


def _segments_cross(
    a: tuple[float, float], b: tuple[float, float], c: tuple[float, float], d: tuple[float, float]
) -> bool:
    """Proper crossing of segments ab and cd (touching does not count)."""
    d1, d2 = _orient(c, d, a), _orient(c, d, b)
    d3, d4 = _orient(a, b, c), _orient(a, b, d)
    return d1 * d2 < 0 and d3 * d4 < 0


def fence_violations(plan: Plan, fence: CircleFence | PolygonFence) -> list[Violation]:
    """The violation of ``plan`` leaving ``fence`` (a waypoint outside, or a segment crossing
    its edge), or none."""
    path = plan.path
    xs, ys = path.xs, path.ys
    outside = [i for i in range(len(xs)) if not fence.contains(xs[i], ys[i])]
    crossing = not outside and any(
        fence.crosses((xs[i], ys[i]), (xs[i + 1], ys[i + 1])) for i in range(len(xs) - 1)
    )
    if not outside and not crossing:
        return []
    params = plan.command.params
    names = EXTENT_PARAMS.get(plan.pattern, ())
    name = names[0] if names else "position"
    value = params.get(name)
    first = outside[0] if outside else 0
    part = "the join to the pattern" if outside and first < plan.path.body_start else "the path"
    where = f" at ({xs[first]:.1f} N, {ys[first]:.1f} E)" if outside else " between waypoints"
    advice = f": reduce {', '.join(names)}" if names else ": the vehicle is outside already"
    return [
        Violation(
            name,
            float(value) if isinstance(value, float | int) else math.hypot(xs[first], ys[first]),
            fence.radius_m if isinstance(fence, CircleFence) else None,
            plan.command.pattern.field(name).unit if name in params else "m",
            f"{part} leaves the {fence.describe()}{where} "
            f"({len(outside)} of {len(xs)} waypoints outside){advice}",
        )
    ]
