"""Operational limits: what a plan may not do, and the violations that stop a send.

Checks, each reported as a :class:`Violation` naming the parameter, its value and the limit:

* the vehicle's depth rating (:data:`RATED_DEPTH_M`, 100 m): never overridable;
* a configurable maximum depth (at most the rating) and maximum speed;
* the tightest circle the vehicle can hold at the commanded speed (radius >= the turn
  radius :func:`planner.turn_radius_m` gives at that speed);
* an optional geofence, a circle or a polygon fixed in the NED frame (the mission origin is
  ``(0, 0)``), which every waypoint of the plan, join included, must stay inside;
* the vehicle's top speed through the water (:func:`top_speed`, overridable): a command
  faster than the vehicle can fly is flown at top speed, slower than planned. The console
  checks it from its vehicle profile; it is not one of the onboard :class:`Limits`, so an
  operator's override reaches the vehicle.

:func:`check` raises :class:`LimitError` unless every violation is overridable and the
operator overrides explicitly.
"""

from __future__ import annotations

import math

from codec._record import Record, init
from planner._plan import turn_radius_m

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Sequence

    from planner._estimate import Estimate
    from planner._plan import Plan

#: Depth rating of the NemeSys hull (m); no override can exceed it.
RATED_DEPTH_M = 100.0
#: Default maximum speed (m/s); an assumption, the paper gives no cruise speed.
DEFAULT_MAX_SPEED_MPS = 1.0

_DEPTH_PARAMS = ("depth", "start_depth", "end_depth")
_ROUND_PARAMS = {"circle": "radius", "helix": "radius"}
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


def _finite_positive(name: str, value: float) -> float:
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a finite number above 0, got {value!r}")
    return float(value)


class CircleFence(Record):
    """Stay within ``radius_m`` of ``centre`` (NED metres, default the mission origin)."""

    __slots__ = ("centre", "radius_m")
    radius_m: float
    centre: tuple[float, float]

    def __init__(self, radius_m: float, centre: tuple[float, float] = (0.0, 0.0)) -> None:
        init(self, "radius_m", _finite_positive("geofence radius_m", radius_m))
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


class Limits(Record):
    """Operational limits a plan is checked against.

    Attributes:
        max_depth_m: deepest allowed depth (m), at most :data:`RATED_DEPTH_M`.
        max_speed_mps: fastest allowed cruise speed (m/s).
        geofence: optional :class:`CircleFence` or :class:`PolygonFence`.
    """

    __slots__ = ("geofence", "max_depth_m", "max_speed_mps")
    max_depth_m: float
    max_speed_mps: float
    geofence: CircleFence | PolygonFence | None

    def __init__(
        self,
        max_depth_m: float = RATED_DEPTH_M,
        max_speed_mps: float = DEFAULT_MAX_SPEED_MPS,
        geofence: CircleFence | PolygonFence | None = None,
    ) -> None:
        _finite_positive("max_depth_m", max_depth_m)
        if max_depth_m > RATED_DEPTH_M:
            raise ValueError(
                f"max_depth_m {max_depth_m:g} m exceeds the vehicle's {RATED_DEPTH_M:g} m rating"
            )
        init(self, "max_depth_m", float(max_depth_m))
        init(self, "max_speed_mps", _finite_positive("max_speed_mps", max_speed_mps))
        init(self, "geofence", geofence)


class Violation(Record):
    """One broken limit.

    Attributes:
        param: the command parameter at fault (``depth``, ``radius``...).
        value: its value in the command.
        limit: the limit it breaks, in the same unit (``None`` for a polygon geofence, which
            the message describes).
        unit: the unit of ``value`` and ``limit``.
        message: a sentence for the operator.
        overridable: ``False`` for the depth rating, which no operator can override.
    """

    __slots__ = ("limit", "message", "overridable", "param", "unit", "value")
    param: str
    value: float
    limit: float | None
    unit: str
    message: str
    overridable: bool

    def __init__(
        self,
        param: str,
        value: float,
        limit: float | None,
        unit: str,
        message: str,
        overridable: bool = True,
    ) -> None:
        init(self, "param", param)
        init(self, "value", value)
        init(self, "limit", limit)
        init(self, "unit", unit)
        init(self, "message", message)
        init(self, "overridable", overridable)


class LimitError(ValueError):
    """A plan breaks limits and was not (or cannot be) overridden."""

    def __init__(self, violations: Sequence[Violation]) -> None:
        self.violations = tuple(violations)
        super().__init__("; ".join(v.message for v in self.violations))


def validate(plan: Plan, limits: Limits) -> tuple[Violation, ...]:
    """Every limit ``plan`` breaks (empty if none)."""
    out: list[Violation] = []
    params = plan.command.params
    for name in _DEPTH_PARAMS:
        value = params.get(name)
        if not isinstance(value, float | int):
            continue
        if value > RATED_DEPTH_M:
            out.append(
                Violation(
                    name,
                    value,
                    RATED_DEPTH_M,
                    "m",
                    f"{name} {value:g} m is deeper than the vehicle's {RATED_DEPTH_M:g} m "
                    "rating (cannot be overridden)",
                    overridable=False,
                )
            )
        elif value > limits.max_depth_m:
            out.append(
                Violation(
                    name,
                    value,
                    limits.max_depth_m,
                    "m",
                    f"{name} {value:g} m is deeper than the maximum depth {limits.max_depth_m:g} m",
                )
            )
    speed = params.get("speed")
    if isinstance(speed, float | int):
        if speed > limits.max_speed_mps:
            out.append(
                Violation(
                    "speed",
                    speed,
                    limits.max_speed_mps,
                    "m/s",
                    f"speed {speed:g} m/s is faster than the maximum speed "
                    f"{limits.max_speed_mps:g} m/s",
                )
            )
        key = _ROUND_PARAMS.get(plan.pattern)
        radius = params.get(key) if key else None
        if key and isinstance(radius, float | int) and 0 < radius < turn_radius_m(speed):
            tight = turn_radius_m(speed)
            out.append(
                Violation(
                    key,
                    radius,
                    tight,
                    "m",
                    f"{key} {radius:g} m is tighter than the {tight:.2f} m the vehicle can turn "
                    f"at {speed:g} m/s: slow down or widen it",
                )
            )
    if limits.geofence is not None:
        out.extend(_fence(plan, limits.geofence))
    return tuple(out)


def top_speed(
    plan: Plan, top_speed_mps: float | None, est: Estimate | None = None
) -> Violation | None:
    """The violation of a plan asking for more than the vehicle's top speed (m/s), or
    ``None`` (also when the top speed is unknown, or the plan never moves horizontally).

    The speed is the command's ``speed``; a pattern without one (hover) is checked at the
    fastest its path moves. Overridable: the vehicle flies it at top speed, only slower.
    """
    from planner._estimate import estimate, planned_speed_mps

    speed = planned_speed_mps(plan)
    if top_speed_mps is None or speed is None or speed <= top_speed_mps:
        return None
    if est is None:  # the plan's estimate at the flyable speed, when not given
        est = estimate(plan, top_speed_mps)
    planned = est.planned_duration_s
    ratio = est.duration_s / planned if planned > 0 else speed / top_speed_mps
    top = f"{round(top_speed_mps, 2):g}"
    return Violation(
        "speed",
        speed,
        top_speed_mps,
        "m/s",
        f"speed {round(speed, 3):g} m/s exceeds the vehicle's {top} m/s top speed: it will "
        f"fly at {top} m/s, {ratio:.1f}x the planned duration",
    )


def _fence(plan: Plan, fence: CircleFence | PolygonFence) -> list[Violation]:
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


def check(plan: Plan, limits: Limits, override: bool = False) -> tuple[Violation, ...]:
    """Violations of ``plan``; raises unless there are none or the operator overrides.

    Returns:
        The violations that were overridden (empty if there were none).

    Raises:
        LimitError: there are violations and ``override`` is false, or one of them (the depth
            rating) cannot be overridden.
    """
    found = validate(plan, limits)
    if found and (not override or any(not v.overridable for v in found)):
        raise LimitError(found)
    return found
