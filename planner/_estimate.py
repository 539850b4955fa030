"""Estimates for the console's confirm step: what a plan costs and what a retask changes."""

from __future__ import annotations

import math

from codec._record import Record, init

TYPE_CHECKING = False
if TYPE_CHECKING:
    from codec import ParamValue
    from planner._plan import Plan


class Estimate(Record):
    """Size and cost of a plan, all from its waypoints.

    Attributes:
        waypoints: number of waypoints.
        length_m: 3D path length (for a repeating pattern: the join and one lap).
        duration_s: time to fly it (same convention).
        transit_length_m, transit_duration_s: the join, before the pattern starts.
        lap_length_m, lap_duration_s: the repeated lap, or ``None`` for a finite path.
        depth_min_m, depth_max_m: depth range (m, down).
        x_min_m, x_max_m, y_min_m, y_max_m: bounding box (m, north and east).
    """

    __slots__ = (
        "depth_max_m",
        "depth_min_m",
        "duration_s",
        "lap_duration_s",
        "lap_length_m",
        "length_m",
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

    def __init__(self, plan: Plan) -> None:
        path = plan.path
        init(self, "waypoints", len(path))
        init(self, "length_m", path.length_m())
        init(self, "duration_s", path.duration_s)
        init(self, "transit_length_m", path.length_m(0, path.body_start))
        init(self, "transit_duration_s", path.times[path.body_start])
        loop = path.loop_start
        init(self, "lap_length_m", None if loop is None else path.length_m(loop))
        init(self, "lap_duration_s", None if loop is None else path.duration_s - path.times[loop])
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


def estimate(plan: Plan) -> Estimate:
    """Length, duration, depth range and bounding box of ``plan``."""
    return Estimate(plan)


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
        changes: parameters that differ (all of them when the pattern changes).
        old, new: estimates of both plans (``old`` is ``None`` with no running plan).
        anchor_moved_m: how far the mission anchor moves (m).
    """

    __slots__ = ("anchor_moved_m", "changes", "new", "new_pattern", "old", "old_pattern")
    old_pattern: str | None
    new_pattern: str
    changes: tuple[ParamChange, ...]
    old: Estimate | None
    new: Estimate
    anchor_moved_m: float

    def __init__(self, current: Plan | None, new: Plan) -> None:
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
            if old_params.get(name) != new_params.get(name) or self.pattern_changed
        ]
        init(self, "changes", tuple(changes))
        init(self, "old", None if current is None else Estimate(current))
        init(self, "new", Estimate(new))
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


def compare(current: Plan | None, new: Plan) -> PlanDiff:
    """What replacing ``current`` by ``new`` changes (parameters, estimates, anchor)."""
    return PlanDiff(current, new)
