"""Estimates for the console's confirm step: what a plan costs and what a retask changes.

Durations are as the vehicle flies the path. The console gives them: the arrival ``times``
of its motion model (``sim.kinematic``: the onboard guidance on a vehicle reduced to its
profile's top speed, heave and yaw rates, which cuts corners, flies depth steps at the
vehicle's heave rate and is done when the vehicle is at its end and depth), the model the
prediction's full twin shares. Without them (the planner alone), at the speed the vehicle can
fly: given its top speed through the water (and its heave rate), a segment the path asks to
fly faster takes as long as the vehicle needs (:func:`flyable_times`). The path's own times
stay in ``planned_duration_s``. The path itself (shared with the vehicle) is never changed:
guidance follows its geometry, not its clock.
"""

from __future__ import annotations

import math

from codec._record import Record, init

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Sequence

    from codec import ParamValue
    from planner._path import Path
    from planner._plan import Plan


#: The fastest vertical rate the planner ever asks for (m/s): the surface command's ascent
#: at the paper's measured heave (depth ramps are slower, 0.05 m/s). A vehicle at least this
#: fast, within the 1 % the figure is measured to, never needs a segment stretched vertically.
_PLANNER_HEAVE_MPS = 0.0731
_MEASURED_WITHIN = 0.99


def flyable_times(
    path: Path, top_speed_mps: float | None = None, heave_rate_mps: float | None = None
) -> tuple[float, ...]:
    """Arrival time at each waypoint (s) for a vehicle no faster than ``top_speed_mps``
    horizontally and ``heave_rate_mps`` vertically (``None``: unknown, not limited).

    Each segment takes ``max(planned, horizontal / top speed, |depth change| / heave rate)``.
    The path's own times when it never asks for more (the usual case: no loop at all).
    """
    times = path.times
    top = top_speed_mps if top_speed_mps is not None and top_speed_mps > 0 else None
    heave = heave_rate_mps if heave_rate_mps is not None and heave_rate_mps > 0 else None
    if heave is not None and heave >= _PLANNER_HEAVE_MPS * _MEASURED_WITHIN:
        heave = None
    if top is not None and max(path.speeds, default=0.0) <= top:
        top = None
    if top is None and heave is None:
        return times
    xs, ys, zs = path.xs, path.ys, path.zs
    inv_top = 0.0 if top is None else 1.0 / top
    inv_heave = 0.0 if heave is None else 1.0 / heave
    out = [times[0]]
    t = times[0]
    hypot = math.hypot
    for i in range(len(times) - 1):
        dt = times[i + 1] - times[i]
        need = max(
            hypot(xs[i + 1] - xs[i], ys[i + 1] - ys[i]) * inv_top,
            abs(zs[i + 1] - zs[i]) * inv_heave,
        )
        t += dt if dt >= need else need
        out.append(t)
    return tuple(out)


def planned_speed_mps(plan: Plan) -> float | None:
    """The cruise speed the plan asks for (m/s): the command's ``speed``, or for a pattern
    without one the fastest its path moves (hover's approach); ``None`` if it never moves."""
    speed = plan.command.params.get("speed")
    if isinstance(speed, int | float):
        return float(speed)
    fastest = max(plan.path.speeds, default=0.0)
    return fastest if fastest > 0.0 else None


class Estimate(Record):
    """Size and cost of a plan, all from its waypoints.

    Durations are as the vehicle flies the path: from the motion model's ``times`` when
    given, else at the speed the vehicle can fly (see the module doc); with neither a top
    speed nor a heave rate they are the path's own.

    Attributes:
        waypoints: number of waypoints.
        length_m: 3D path length (for a repeating pattern: the join and one lap).
        duration_s: time to fly it (same convention), as the vehicle flies it.
        planned_duration_s: the same at the planned (commanded) speed: the path's own times.
        planned_speed_mps: the cruise speed the plan asks for (``None``: it does not move).
        flyable_speed_mps: the speed the vehicle will fly it at, ``min(planned, top)``.
        transit_length_m, transit_duration_s: the join, before the pattern starts.
        lap_length_m, lap_duration_s: the repeated lap, or ``None`` for a finite path.
        depth_min_m, depth_max_m: depth range (m, down).
        x_min_m, x_max_m, y_min_m, y_max_m: bounding box (m, north and east).
    """

    __slots__ = (
        "depth_max_m",
        "depth_min_m",
        "duration_s",
        "flyable_speed_mps",
        "lap_duration_s",
        "lap_length_m",
        "length_m",
        "planned_duration_s",
        "planned_speed_mps",
        "transit_duration_s",
        "transit_length_m",
        "waypoints",
        "x_max_m",
        "x_min_m",
        "y_max_m",
        "y_min_m",
    )
    waypoints: int
    length_m: float
    duration_s: float
    planned_duration_s: float
    planned_speed_mps: float | None
    flyable_speed_mps: float | None
    transit_length_m: float
    transit_duration_s: float
    lap_length_m: float | None
    lap_duration_s: float | None
    depth_min_m: float
    depth_max_m: float
    x_min_m: float
    x_max_m: float
    y_min_m: float
    y_max_m: float

    def __init__(
        self,
        plan: Plan,
        top_speed_mps: float | None = None,
        heave_rate_mps: float | None = None,
        times: Sequence[float] | None = None,
    ) -> None:
        path = plan.path
        if times is None:
            times = flyable_times(path, top_speed_mps, heave_rate_mps)
        elif len(times) != len(path):
            raise ValueError(f"times has {len(times)} values for a path of {len(path)} waypoints")
        speed = planned_speed_mps(plan)
        flyable = speed
        if speed is not None and top_speed_mps is not None:
            flyable = min(speed, top_speed_mps)
        init(self, "waypoints", len(path))
        init(self, "length_m", path.length_m())
        init(self, "duration_s", times[-1])
        init(self, "planned_duration_s", path.duration_s)
        init(self, "planned_speed_mps", speed)
        init(self, "flyable_speed_mps", flyable)
        init(self, "transit_length_m", path.length_m(0, path.body_start))
        init(self, "transit_duration_s", times[path.body_start])
        loop = path.loop_start
        init(self, "lap_length_m", None if loop is None else path.length_m(loop))
        init(self, "lap_duration_s", None if loop is None else times[-1] - times[loop])
        init(self, "depth_min_m", min(path.zs))
        init(self, "depth_max_m", max(path.zs))
        init(self, "x_min_m", min(path.xs))
        init(self, "x_max_m", max(path.xs))
        init(self, "y_min_m", min(path.ys))
        init(self, "y_max_m", max(path.ys))

    @property
    def repeats(self) -> bool:
        """The pattern repeats its lap until retasked (square, circle)."""
        return self.lap_length_m is not None


def estimate(
    plan: Plan,
    top_speed_mps: float | None = None,
    heave_rate_mps: float | None = None,
    times: Sequence[float] | None = None,
) -> Estimate:
    """Length, duration (the motion model's ``times`` when given, else at the speed a vehicle
    of ``top_speed_mps`` and ``heave_rate_mps`` can fly; unknown: as planned), depth range and
    bounding box of ``plan``."""
    return Estimate(plan, top_speed_mps, heave_rate_mps, times)


class ParamChange(Record):
    """One parameter whose value differs between the current and the new command."""

    __slots__ = ("new", "old", "param", "unit")
    param: str
    unit: str
    old: ParamValue | None
    new: ParamValue | None

    def __init__(
        self, param: str, unit: str, old: ParamValue | None, new: ParamValue | None
    ) -> None:
        init(self, "param", param)
        init(self, "unit", unit)
        init(self, "old", old)
        init(self, "new", new)


class PlanDiff(Record):
    """What a retask changes, for the confirm step.

    Attributes:
        old_pattern: the running pattern (``None`` if none).
        new_pattern: the commanded one.
        changes: parameters whose value differs (snapped, as decoded), across patterns
            too: a parameter equal in both is not a change; one only one side has is.
        old, new: estimates of both plans (``old`` is ``None`` with no running plan): the
            given ``estimates``, else at the flyable speed when a top speed is given.
        anchor_moved_m: how far the mission anchor moves (m).
    """

    __slots__ = ("anchor_moved_m", "changes", "new", "new_pattern", "old", "old_pattern")
    old_pattern: str | None
    new_pattern: str
    changes: tuple[ParamChange, ...]
    old: Estimate | None
    new: Estimate
    anchor_moved_m: float

    def __init__(
        self,
        current: Plan | None,
        new: Plan,
        top_speed_mps: float | None = None,
        heave_rate_mps: float | None = None,
        estimates: tuple[Estimate | None, Estimate] | None = None,
    ) -> None:
        init(self, "old_pattern", None if current is None else current.pattern)
        init(self, "new_pattern", new.pattern)
        old_params = {} if current is None else current.command.params
        new_params = new.command.params
        units = {f.name: f.unit for f in new.command.pattern.fields}
        if current is not None:
            for f in current.command.pattern.fields:
                units.setdefault(f.name, f.unit)
        changes = [
            ParamChange(name, units[name], old_params.get(name), new_params.get(name))
            for name in dict.fromkeys([*old_params, *new_params])
            if old_params.get(name) != new_params.get(name)
        ]
        init(self, "changes", tuple(changes))
        if estimates is not None:
            init(self, "old", None if current is None else estimates[0])
            init(self, "new", estimates[1])
        else:
            rates = (top_speed_mps, heave_rate_mps)
            init(self, "old", None if current is None else Estimate(current, *rates))
            init(self, "new", Estimate(new, *rates))
        moved = 0.0 if current is None else math.dist(current.anchor, new.anchor)
        init(self, "anchor_moved_m", moved)

    @property
    def pattern_changed(self) -> bool:
        return self.old_pattern != self.new_pattern

    def delta(self, attribute: str) -> float | None:
        """New minus old value of an :class:`Estimate` attribute (``None`` if either lacks it)."""
        if self.old is None:
            return None
        a, b = getattr(self.old, attribute), getattr(self.new, attribute)
        if a is None or b is None:
            return None
        return float(b) - float(a)


def compare(
    current: Plan | None,
    new: Plan,
    top_speed_mps: float | None = None,
    heave_rate_mps: float | None = None,
    estimates: tuple[Estimate | None, Estimate] | None = None,
) -> PlanDiff:
    """What replacing ``current`` by ``new`` changes (parameters, estimates: the given
    ``(old, new)`` ones, else at the flyable speed; anchor)."""
    return PlanDiff(current, new, top_speed_mps, heave_rate_mps, estimates)
