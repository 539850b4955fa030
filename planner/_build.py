"""What every pattern's expansion is built from: the planner's rates and bounds, the
:class:`Plan` record, the polyline builder that times a path, the command's parameters, and the
plan that holds where the vehicle is.

The patterns (:mod:`planner._orbits`, :mod:`planner._plan`) build on this module; it imports
neither of them.
"""

from __future__ import annotations

import math

from codec._record import Record, init
from planner._errors import PlanError
from planner._geometry import dubins
from planner._path import Path, VehicleState, timed

TYPE_CHECKING = False
if TYPE_CHECKING:
    from codec import Command, ParamValue

    Params = dict[str, ParamValue]

#: Depth rate used for ramps (m/s), below the vehicle's 73.1 mm/s heave capability.
DEPTH_RATE_MPS = 0.05
#: Measured heave capability (m/s, the paper's Cfg #3); the surface command ascends at it.
HEAVE_CAPABILITY_MPS = 0.0731
#: Yaw rate the planner's turns assume (deg/s), below the 30.3 deg/s capability.
YAW_RATE_DPS = 20.0
#: Smallest turn radius used for joins (m).
MIN_TURN_RADIUS_M = 0.5
#: How far ahead of the vehicle (in turn radii) a continued pattern is rejoined.
LEAD_TURN_RADII = 3.0
#: Horizontal speed for hover station keeping when it has to move (m/s).
HOVER_APPROACH_MPS = 0.2
#: A plan may not exceed this many waypoints (about 2 MB on the vehicle).
MAX_WAYPOINTS = 10_000


def turn_radius_m(speed_mps: float) -> float:
    """Radius of the planner's turns at ``speed_mps`` (yaw rate :data:`YAW_RATE_DPS`)."""
    return max(MIN_TURN_RADIUS_M, speed_mps / math.radians(YAW_RATE_DPS))


class Plan(Record):
    """A command expanded for one vehicle state.

    Attributes:
        command: the decoded command.
        path: the waypoints (join, then the pattern).
        anchor: the mission anchor ``(x_m, y_m)`` in force: the centre of orbit patterns,
            the centre of a lawnmower's box.
        origin: the pattern's own reference point ``(x_m, y_m)``: orbit centre, lawnmower
            start corner, straight line start, hover hold point, surfacing point.
        angle_deg: the pattern's reference angle: lawnmower lane axis or straight heading
            (deg from north), or for orbits the bearing from the centre of progress mark 0.
        lanes: lawnmower lane offsets to starboard of the axis (m), one per lane.
        t0_s: mission time when the plan took effect (s).
    """

    __slots__ = ("anchor", "angle_deg", "command", "lanes", "origin", "path", "t0_s")
    command: Command
    path: Path
    anchor: tuple[float, float]
    origin: tuple[float, float]
    angle_deg: float
    lanes: tuple[float, ...]
    t0_s: float

    def __init__(
        self,
        command: Command,
        path: Path,
        anchor: tuple[float, float],
        origin: tuple[float, float],
        angle_deg: float = 0.0,
        lanes: tuple[float, ...] = (),
        t0_s: float = 0.0,
    ) -> None:
        init(self, "command", command)
        init(self, "path", path)
        init(self, "anchor", anchor)
        init(self, "origin", origin)
        init(self, "angle_deg", angle_deg)
        init(self, "lanes", lanes)
        init(self, "t0_s", t0_s)

    @property
    def pattern(self) -> str:
        return self.command.pattern.name

    def progress(self, state: VehicleState) -> float:
        """The pattern's progress mark where ``state`` is (see :attr:`Path.marks`)."""
        path = self.path
        if self.pattern == "hover":
            return path.mark_at_time(state.t_s - self.t0_s)
        index = path.locate(state.x_m, state.y_m, state.z_m, state.segment, state.t_s - self.t0_s)
        if index < path.body_start:
            return path.marks[path.body_start]
        return path.mark_at(index)


class Build:
    """Accumulates a horizontal polyline with body depths and marks."""

    __slots__ = ("loop", "marks", "xs", "ys", "zb")

    def __init__(self, state: VehicleState) -> None:
        self.xs = [state.x_m]
        self.ys = [state.y_m]
        self.zb = [state.z_m]
        self.marks = [0.0]
        self.loop = -1

    def add(self, x: float, y: float, z: float, mark: float) -> None:
        self.xs.append(x)
        self.ys.append(y)
        self.zb.append(z)
        self.marks.append(mark)

    def length_m(self) -> float:
        """Horizontal length of the polyline so far."""
        xs, ys = self.xs, self.ys
        return sum(math.hypot(xs[i + 1] - xs[i], ys[i + 1] - ys[i]) for i in range(len(xs) - 1))

    def join(
        self,
        state: VehicleState,
        entry: tuple[float, float, float],
        z: float,
        mark: float,
        speed_mps: float,
    ) -> int:
        """Dubins transit from the vehicle's pose to ``entry``; returns the body start index.

        The join is flown at the commanded ``speed_mps``, so its turns use that speed's radius.
        """
        pose = (state.x_m, state.y_m, state.heading_rad)
        jx, jy, _ = dubins(pose, entry, turn_radius_m(speed_mps))
        self.xs.extend(jx)
        self.ys.extend(jy)
        self.zb.extend([z] * len(jx))
        self.marks.extend([mark] * len(jx))
        self.zb[0] = z
        self.marks[0] = mark
        return len(self.xs) - 1

    def finish(
        self,
        state: VehicleState,
        speed_mps: float,
        body_start: int,
        rate_mps: float = DEPTH_RATE_MPS,
        hold_heading_deg: float | None = None,
    ) -> Path:
        if len(self.xs) > MAX_WAYPOINTS:
            raise PlanError(
                f"the path needs {len(self.xs)} waypoints, more than the vehicle's "
                f"{MAX_WAYPOINTS}: shorten the pattern (fewer laps, turns or loops), or bring "
                "the vehicle nearer the pattern's depth first (a long depth ramp adds laps)"
            )
        xs, ys, zs, sp, ts, ms, where = timed(
            self.xs, self.ys, self.zb, self.marks, state.z_m, speed_mps, rate_mps
        )
        start = where[body_start]
        loop: int | None = None
        if self.loop >= 0:
            loop = where[self.loop]
            sp[-1] = sp[loop]
        return Path(
            tuple(xs),
            tuple(ys),
            tuple(zs),
            tuple(sp),
            tuple(ts),
            tuple(ms),
            start,
            loop,
            hold_heading_deg,
        )


# --- parameters ---------------------------------------------------------------------------


def param_number(params: Params, name: str) -> float:
    value = params[name]
    assert not isinstance(value, str)
    return float(value)


def param_sense(params: Params) -> int:
    """+1 clockwise seen from above (N -> E -> S), -1 counter-clockwise."""
    return 1 if params["direction"] == "cw" else -1


def param_positive(command: Command, params: Params, name: str, what: str) -> float:
    value = param_number(params, name)
    if value <= 0.0:
        raise PlanError(f"{name} {value:g} {command.pattern.field(name).unit}: {what}", field=name)
    return value


def param_speed(command: Command, params: Params) -> float:
    return param_positive(
        command, params, "speed", f"{command.pattern.name} needs a speed above 0 m/s"
    )


def plan_hold(command: Command, state: VehicleState, anchor: tuple[float, float]) -> Plan:
    """The pattern is already complete: hold where the vehicle is."""
    path = Path((state.x_m,), (state.y_m,), (state.z_m,), (0.0,), (0.0,), (0.0,), 0, None, None)
    return Plan(command, path, anchor, (state.x_m, state.y_m), state.heading_deg, t0_s=state.t_s)
