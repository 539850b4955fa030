"""Expansion of a decoded command into the path the vehicle flies, and the retask join.

One function, :func:`plan`, serves the console's preview and the vehicle's execution. It takes
the decoded :class:`codec.Command` (so the path is built from the values the vehicle will
actually receive), the vehicle's state when the command takes effect and the plan it was
running, and returns the new :class:`Plan`.

Anchoring rule (``docs/patterns.md`` has the pictures):

* **Orbit patterns** (square, circle, spiral, helix, box orbit) are centred on the *mission
  anchor*. Switching between them, or changing their parameters, keeps the anchor, so the
  vehicle keeps circling the same pod or panel.
* **straight** and **lawnmower** start from the vehicle's pose (position and heading) when
  they take effect. A lawnmower's anchor is the centre of the box it surveys; after a
  straight the anchor is wherever the vehicle is when the next command takes effect.
* **hover** holds the position where it takes effect; **surface** rises in place. Neither
  moves the anchor, so a hover or a surfacing in the middle of a patrol can be followed by
  the same orbit around the same point.
* With no previous command the anchor is the vehicle's position.

Retask join: the new path begins at the vehicle's position with its heading (Dubins turn-
straight-turn transit at the turn radius the speed allows), reaches the pattern tangentially
at the entry point, and ramps the depth at :data:`DEPTH_RATE_MPS` while it moves. A change of
parameters only (same pattern) continues from the vehicle's progress: the lawnmower keeps its
lanes and lane number, finite orbits keep the turns already flown, straight and hover keep the
elapsed time.
"""

from __future__ import annotations

import math

from codec._record import Record, init
from planner._errors import PlanError
from planner._geometry import (
    CHORD_TOL_M,
    MAX_STEP_RAD,
    TAU,
    arc,
    dubins,
    heading_deg,
    step_angle,
    wrap,
)
from planner._path import EPS_M, Path, VehicleState, timed

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

#: Patterns that repeat until retasked.
REPEATING_PATTERNS = frozenset({"square", "circle"})


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


class _Build:
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


def _num(params: Params, name: str) -> float:
    value = params[name]
    assert not isinstance(value, str)
    return float(value)


def _sense(params: Params) -> int:
    """+1 clockwise seen from above (N -> E -> S), -1 counter-clockwise."""
    return 1 if params["direction"] == "cw" else -1


def _positive(command: Command, params: Params, name: str, what: str) -> float:
    value = _num(params, name)
    if value <= 0.0:
        raise PlanError(f"{name} {value:g} {command.pattern.field(name).unit}: {what}", field=name)
    return value


def _speed(command: Command, params: Params) -> float:
    return _positive(command, params, "speed", f"{command.pattern.name} needs a speed above 0 m/s")


def _turns_budget(turns: float, radius_m: float) -> None:
    step = step_angle(radius_m) if radius_m > 0 else MAX_STEP_RAD
    if turns * TAU / step > MAX_WAYPOINTS:
        raise PlanError(
            f"{turns:g} turns at {radius_m:g} m need more than the vehicle's {MAX_WAYPOINTS} "
            "waypoints: choose fewer turns or a smaller radius"
        )


# --- entry geometry ------------------------------------------------------------------------


def _entry_angle(
    anchor: tuple[float, float], radius_m: float, sense: int, state: VehicleState, lead_m: float
) -> float:
    """Bearing from the anchor of the point where the vehicle joins a circle of ``radius_m``.

    From outside: the tangent point reached in the commanded sense, at least ``lead_m`` of arc
    ahead of the vehicle's own bearing. From well inside: abeam on the side the pattern turns
    to, which a half-turn towards that side reaches tangentially (no loop when the radius
    allows it).
    """
    dx, dy = state.x_m - anchor[0], state.y_m - anchor[1]
    d = math.hypot(dx, dy)
    if d < 0.5 * radius_m or d < EPS_M:
        return state.heading_rad + sense * math.pi / 2
    lead = min(math.pi / 2, lead_m / radius_m) if radius_m > 0 else 0.0
    return math.atan2(dy, dx) + sense * max(math.acos(min(1.0, radius_m / d)), lead)


def _square_corners(
    anchor: tuple[float, float], half_m: float, sense: int
) -> list[tuple[float, float]]:
    """Corners in travel order starting at the north-east one."""
    ax, ay = anchor
    ne, se = (ax + half_m, ay + half_m), (ax - half_m, ay + half_m)
    sw, nw = (ax - half_m, ay - half_m), (ax + half_m, ay - half_m)
    return [ne, se, sw, nw] if sense > 0 else [ne, nw, sw, se]


def _square_entry(
    anchor: tuple[float, float], half_m: float, sense: int, bearing_rad: float
) -> tuple[float, float, int]:
    """Point of the square on the ray at ``bearing_rad`` and the side it lies on.

    Sides are numbered in travel order from the north-east corner (:func:`_square_corners`).
    """
    c, s = math.cos(bearing_rad), math.sin(bearing_rad)
    if abs(c) >= abs(s):
        k = half_m / abs(c)
        name = "north" if c > 0 else "south"
    else:
        k = half_m / abs(s)
        name = "east" if s > 0 else "west"
    order = _CW_SIDES if sense > 0 else _CCW_SIDES
    return anchor[0] + k * c, anchor[1] + k * s, order[name]


_CW_SIDES = {"east": 0, "south": 1, "west": 2, "north": 3}
_CCW_SIDES = {"north": 0, "west": 1, "south": 2, "east": 3}


# --- patterns ------------------------------------------------------------------------------


def _plan_square(
    command: Command,
    p: Params,
    state: VehicleState,
    anchor: tuple[float, float],
    half_m: float,
    laps: int,
    mark0: float,
) -> Plan:
    """square (``laps == 0``: repeats) and box orbit (``laps`` orbits, marks from ``mark0``)."""
    speed = _speed(command, p)
    sense = _sense(p)
    depth = _num(p, "depth")
    lead = LEAD_TURN_RADII * turn_radius_m(speed)
    bearing = _entry_angle(anchor, half_m, sense, state, lead)
    ex, ey, side = _square_entry(anchor, half_m, sense, bearing)
    corners = _square_corners(anchor, half_m, sense)
    nx, ny = corners[(side + 1) % 4]
    entry_heading = (
        math.atan2(ny - ey, nx - ex)
        if math.hypot(nx - ex, ny - ey) > EPS_M
        else (math.atan2(ny - corners[side][1], nx - corners[side][0]))
    )
    b = _Build(state)
    start = b.join(state, (ex, ey, entry_heading), depth, mark0, speed)
    perimeter = 8.0 * half_m
    repeat = laps == 0
    laps_out = 1 if repeat else laps
    if repeat:
        laps_out += _extra_laps(state.z_m, depth, b.length_m(), perimeter, speed)
    mark = mark0
    for lap in range(laps_out):
        if repeat and lap == laps_out - 1:
            b.loop = len(b.xs) - 1
        px, py = ex, ey
        for j in range(1, 5):
            cx, cy = corners[(side + j) % 4]
            mark += math.hypot(cx - px, cy - py) / perimeter
            b.add(cx, cy, depth, mark)
            px, py = cx, cy
        mark += math.hypot(ex - px, ey - py) / perimeter
        b.add(ex, ey, depth, mark)
    path = b.finish(state, speed, start)
    return Plan(command, path, anchor, anchor, heading_deg(bearing), t0_s=state.t_s)


def _polygon_circumference(radius_m: float) -> float:
    """Length of a full circle of ``radius_m`` as :func:`arc` samples it (m)."""
    n = max(1, math.ceil(TAU / step_angle(radius_m) - 1e-9))
    return 2.0 * radius_m * n * math.sin(math.pi / n)


def _extra_laps(z0: float, depth: float, transit_m: float, lap_m: float, speed: float) -> int:
    """Laps to fly before the repeated one so the depth ramp ends before the loop starts."""
    ramp_s = abs(depth - z0) / DEPTH_RATE_MPS
    spare = ramp_s - transit_m / speed
    return max(0, math.ceil(spare / (lap_m / speed) - 1e-9)) if spare > 0 else 0


def _round_pose(
    anchor: tuple[float, float], r: float, dr: float, sense: int, bearing: float
) -> tuple[float, float, float]:
    """Pose ``(x, y, heading)`` on a circle or spiral of radius ``r`` (``dr`` = dr/dtheta) at
    ``bearing`` from the anchor, moving in ``sense``."""
    ca, sa = math.cos(bearing), math.sin(bearing)
    heading = math.atan2(dr * sa + sense * r * ca, dr * ca - sense * r * sa)
    return anchor[0] + r * ca, anchor[1] + r * sa, heading


def _circle_shape(
    command: Command, p: Params, shape: str
) -> tuple[float, float, float, float, float]:
    """``(initial radius, final radius, start depth, end depth, turns)`` of a round pattern."""
    if shape == "spiral":
        r0, r1 = _num(p, "initial_radius"), _num(p, "final_radius")
        if r0 <= 0.0 and r1 <= 0.0:
            raise PlanError(
                "initial_radius and final_radius are both 0 m: a spiral needs one above 0 m",
                field="final_radius",
            )
        depth = _num(p, "depth")
        return r0, r1, depth, depth, float(p["loops"])
    r = _positive(command, p, "radius", f"a {shape} needs a radius above 0 m")
    if shape == "helix":
        return r, r, _num(p, "start_depth"), _num(p, "end_depth"), float(p["turns"])
    return r, r, _num(p, "depth"), _num(p, "depth"), 1.0


def _plan_circle_like(
    command: Command,
    p: Params,
    state: VehicleState,
    anchor: tuple[float, float],
    current: Plan | None,
    shape: str,
) -> Plan:
    """circle (repeats), helix (turns between two depths) and spiral (two radii)."""
    speed = _speed(command, p)
    sense = _sense(p)
    r0, r1, z0, z1, turns = _circle_shape(command, p, shape)
    _turns_budget(turns, min(r for r in (r0, r1) if r > 0))
    lead = LEAD_TURN_RADII * turn_radius_m(speed)
    total = turns * TAU
    ax, ay = anchor
    # theta: where on the pattern to start (rad from its start); phi0: bearing of theta = 0
    if current is not None and current.pattern == shape and shape != "circle":
        theta_v = current.progress(state) * TAU
        phi0 = math.radians(current.angle_deg)
        r_v = r0 + (r1 - r0) * min(theta_v, total) / total
        theta = theta_v + (min(math.pi / 2, lead / r_v) if r_v > 0 else math.pi / 2)
        if theta >= total - 1e-9:
            return _plan_hold(command, state, anchor)
    else:
        theta = 0.0
        if r0 > 0.0:
            phi0 = _entry_angle(anchor, r0, sense, state, lead)
            if math.hypot(state.x_m - ax, state.y_m - ay) < 0.5 * r0:
                # from well inside, take the shorter of the abeam and the straight-ahead entry
                pose = (state.x_m, state.y_m, state.heading_rad)
                dr0 = (r1 - r0) / total
                ahead = math.atan2(
                    state.y_m - ay + r0 * math.sin(pose[2]), state.x_m - ax + r0 * math.cos(pose[2])
                )
                turn = turn_radius_m(speed)
                phi0 = min(
                    (phi0, ahead),
                    key=lambda f: dubins(pose, _round_pose(anchor, r0, dr0, sense, f), turn)[2],
                )
        elif math.hypot(ax - state.x_m, ay - state.y_m) > EPS_M:
            phi0 = math.atan2(ay - state.y_m, ax - state.x_m)
        else:
            phi0 = state.heading_rad
    dr = (r1 - r0) / total
    entry = _round_pose(anchor, r0 + dr * theta, dr, sense, phi0 + sense * theta)
    b = _Build(state)
    entry_z = z0 + (z1 - z0) * theta / total
    start = b.join(state, entry, entry_z, theta / TAU, speed)
    if shape == "circle":
        laps = 1 + _extra_laps(state.z_m, z0, b.length_m(), _polygon_circumference(r0), speed)
        for lap in range(laps):
            if lap == laps - 1:
                b.loop = len(b.xs) - 1
            n0 = len(b.xs)
            arc(b.xs, b.ys, anchor, r0, phi0, sense * TAU, (b.marks, float(lap), lap + 1.0))
            b.zb.extend([z0] * (len(b.xs) - n0))
    else:
        if shape == "helix" and theta == 0.0:
            # a helix is entered at its start depth: circle there until the ramp gets there
            for _ in range(
                _extra_laps(state.z_m, z0, b.length_m(), _polygon_circumference(r0), speed)
            ):
                n0 = len(b.xs)
                arc(b.xs, b.ys, anchor, r0, phi0, sense * TAU, (b.marks, 0.0, 0.0))
                b.zb.extend([z0] * (len(b.xs) - n0))
            start = len(b.xs) - 1
        _sample_spiral(b, (ax, ay, phi0, sense), theta, total, (r0, r1), (z0, z1))
    path = b.finish(state, speed, start)
    return Plan(command, path, anchor, anchor, heading_deg(phi0), t0_s=state.t_s)


def _sample_spiral(
    b: _Build,
    frame: tuple[float, float, float, int],
    theta: float,
    total: float,
    radii: tuple[float, float],
    depths: tuple[float, float],
) -> None:
    """Sample the spiral or helix from ``theta`` to ``total`` (rad) within the chord bound.

    ``frame = (centre x, centre y, bearing of theta 0, sense)``; the radius runs linearly over
    ``radii`` and the depth over ``depths`` as theta goes from 0 to ``total``. A helix (constant
    radius) is sampled uniformly; a spiral's step uses the local radius of curvature of the
    Archimedean spiral, ``(r^2 + b^2)^1.5 / (r^2 + 2 b^2)`` with ``b = dr/dtheta``, taken at the
    smaller radius of the step, and no chord lets the tangent turn more than MAX_STEP_RAD.
    """
    ax, ay, phi0, sense = frame
    r0, r1 = radii
    z0, z1 = depths
    dr = (r1 - r0) / total
    dz = (z1 - z0) / total
    cos, sin = math.cos, math.sin
    xs, ys, zb, ms = b.xs, b.ys, b.zb, b.marks
    tol8 = 8.0 * CHORD_TOL_M * 0.8  # the sagitta formula is a first-order estimate
    b2 = dr * dr
    start, k = theta, 0
    # a helix (constant radius) takes n equal steps; a spiral sizes each step where it is
    n = max(1, math.ceil((total - theta) / step_angle(r0) - 1e-9)) if dr == 0.0 else 0
    while theta < total - 1e-12:
        if n:
            k += 1
            theta = start + (total - start) * k / n
        else:
            r = r0 + dr * theta
            rr = max(0.0, r + dr * MAX_STEP_RAD) if dr < 0.0 else r
            k2 = rr * rr + b2
            # the tangent turns (1 + b^2 / (r^2 + b^2)) times as fast as theta: cap its turn too
            step = min(
                0.999 * MAX_STEP_RAD / (1.0 + b2 / k2),
                math.sqrt(tol8 * k2**0.5 / (rr * rr + 2.0 * b2)),
            )
            theta = min(total, theta + step)
        r = r0 + dr * theta
        a = phi0 + sense * theta
        xs.append(ax + r * cos(a))
        ys.append(ay + r * sin(a))
        zb.append(z0 + dz * theta)
        ms.append(theta / TAU)


def _plan_lawnmower(command: Command, p: Params, state: VehicleState, current: Plan | None) -> Plan:
    speed = _speed(command, p)
    depth = _num(p, "depth")
    length = _positive(command, p, "sweep_length", "a lawnmower needs lanes longer than 0 m")
    spacing = _positive(command, p, "lane_spacing", "lanes must be more than 0 m apart")
    n_lanes = 2 * int(p["laps"])
    b = _Build(state)
    if current is not None and current.pattern == "lawnmower":
        ox, oy = current.origin
        axis = math.radians(current.angle_deg)
        k = int(current.progress(state))
        cur = k // 2  # the lane most recently started
        ux, uy = math.cos(axis), math.sin(axis)
        along = (state.x_m - ox) * ux + (state.y_m - oy) * uy
        on_lane = k % 2 == 0 and (along < length if cur % 2 == 0 else along > 0.0)
        # lanes already started keep their offsets; later ones use the new spacing
        lanes = list(current.lanes[: cur + 1])
        while len(lanes) < n_lanes:
            lanes.append(lanes[-1] + spacing)
        lane = cur if on_lane else cur + 1
        if lane >= len(lanes):
            return _plan_hold(command, state, current.anchor)
        lead = LEAD_TURN_RADII * turn_radius_m(speed)
        end = length if lane % 2 == 0 else 0.0
        step = lead if lane % 2 == 0 else -lead
        a_entry = along + step if on_lane else (0.0 if lane % 2 == 0 else length)
        if on_lane and (a_entry - end) * (1 if lane % 2 == 0 else -1) >= 0:
            a_entry = end
        entry_mark = 2 * lane + (
            abs(a_entry - (0.0 if lane % 2 == 0 else length)) / length if on_lane else 0.0
        )
        vx, vy = -uy, ux
        c = lanes[lane]
        ex, ey = ox + a_entry * ux + c * vx, oy + a_entry * uy + c * vy
        h = axis if lane % 2 == 0 else axis + math.pi
        start = b.join(state, (ex, ey, h), depth, entry_mark, speed)
        first = lane
    else:
        ox, oy, axis = state.x_m, state.y_m, state.heading_rad
        ux, uy = math.cos(axis), math.sin(axis)
        vx, vy = -uy, ux
        lanes = [i * spacing for i in range(n_lanes)]
        b.zb[0] = depth
        start, first = 0, 0
    for i in range(first, len(lanes)):
        a0, a1 = (0.0, length) if i % 2 == 0 else (length, 0.0)
        c = lanes[i]
        if i > first:
            b.add(ox + a0 * ux + c * vx, oy + a0 * uy + c * vy, depth, 2.0 * i)
        b.add(ox + a1 * ux + c * vx, oy + a1 * uy + c * vy, depth, 2.0 * i + 1)
    path = b.finish(state, speed, start)
    mid = (lanes[0] + lanes[-1]) / 2
    anchor = (ox + length / 2 * ux + mid * vx, oy + length / 2 * uy + mid * vy)
    return Plan(command, path, anchor, (ox, oy), heading_deg(axis), tuple(lanes), t0_s=state.t_s)


def _plan_straight(
    command: Command,
    p: Params,
    state: VehicleState,
    anchor: tuple[float, float],
    current: Plan | None,
) -> Plan:
    speed = _speed(command, p)
    depth = _num(p, "depth")
    duration = _positive(command, p, "duration", "a straight needs a duration above 0 s")
    heading = math.radians(_num(p, "heading"))
    elapsed = 0.0
    if current is not None and current.pattern == "straight":
        elapsed = max(0.0, current.progress(state))
    b = _Build(state)
    b.zb[0] = depth
    b.marks[0] = elapsed
    sweep = wrap(heading - state.heading_rad)
    r = turn_radius_m(speed)
    if abs(sweep) > 1e-9:
        turn = 1 if sweep > 0 else -1
        h0 = state.heading_rad
        centre = (state.x_m - turn * r * math.sin(h0), state.y_m + turn * r * math.cos(h0))
        n0 = len(b.xs)
        arc(b.xs, b.ys, centre, r, h0 - turn * math.pi / 2, sweep)
        b.zb.extend([depth] * (len(b.xs) - n0))
        b.marks.extend([elapsed] * (len(b.xs) - n0))
    start = len(b.xs) - 1
    sx, sy = b.xs[-1], b.ys[-1]
    remaining = duration - elapsed
    if remaining <= 0.0:
        return _plan_hold(command, state, anchor)
    dist = remaining * speed
    b.add(sx + dist * math.cos(heading), sy + dist * math.sin(heading), depth, duration)
    path = b.finish(state, speed, start)
    return Plan(command, path, anchor, (sx, sy), heading_deg(heading), t0_s=state.t_s)


def _plan_hover(
    command: Command,
    p: Params,
    state: VehicleState,
    anchor: tuple[float, float],
    current: Plan | None,
) -> Plan:
    duration = _positive(command, p, "duration", "a hover needs a duration above 0 s")
    depth = _num(p, "depth")
    heading = _num(p, "heading")
    elapsed = 0.0
    hx, hy = state.x_m, state.y_m
    if current is not None and current.pattern == "hover":
        elapsed = max(0.0, current.progress(state))
        hx, hy = current.origin
    # move to the hold point (station keeping) and to the depth, then hold for the rest
    x0, y0, z0 = state.x_m, state.y_m, state.z_m
    dt = max(math.hypot(hx - x0, hy - y0) / HOVER_APPROACH_MPS, abs(depth - z0) / DEPTH_RATE_MPS)
    xs, ys, zs, ts, ms = [x0], [y0], [z0], [0.0], [elapsed]
    if dt > 0.0:
        xs.append(hx)
        ys.append(hy)
        zs.append(depth)
        ts.append(dt)
        ms.append(min(duration, elapsed + dt))
    if elapsed + dt < duration:
        xs.append(hx)
        ys.append(hy)
        zs.append(depth)
        ts.append(duration - elapsed)
        ms.append(duration)
    sp = [
        math.hypot(xs[i + 1] - xs[i], ys[i + 1] - ys[i]) / (ts[i + 1] - ts[i])
        for i in range(len(xs) - 1)
    ]
    sp.append(0.0)
    path = Path(tuple(xs), tuple(ys), tuple(zs), tuple(sp), tuple(ts), tuple(ms), 0, None, heading)
    return Plan(command, path, anchor, (hx, hy), heading, t0_s=state.t_s)


def _plan_hold(command: Command, state: VehicleState, anchor: tuple[float, float]) -> Plan:
    """The pattern is already complete: hold where the vehicle is."""
    path = Path((state.x_m,), (state.y_m,), (state.z_m,), (0.0,), (0.0,), (0.0,), 0, None, None)
    return Plan(command, path, anchor, (state.x_m, state.y_m), state.heading_deg, t0_s=state.t_s)


def _plan_surface(command: Command, state: VehicleState, anchor: tuple[float, float]) -> Plan:
    b = _Build(state)
    b.add(state.x_m, state.y_m, 0.0, 0.0)
    b.zb[0] = 0.0
    path = b.finish(state, HOVER_APPROACH_MPS, 0, HEAVE_CAPABILITY_MPS, state.heading_deg)
    return Plan(command, path, anchor, (state.x_m, state.y_m), state.heading_deg, t0_s=state.t_s)


def anchor_for(current: Plan | None, state: VehicleState) -> tuple[float, float]:
    """The mission anchor a new command uses (see the module's anchoring rule)."""
    if current is None or current.pattern == "straight":
        return state.x_m, state.y_m
    return current.anchor


def plan(command: Command, state: VehicleState, current: Plan | None = None) -> Plan:
    """Expand ``command`` for a vehicle in ``state`` that is running ``current``.

    Raises:
        PlanError: the command has no flyable path (a zero radius, speed or duration, or more
            waypoints than :data:`MAX_WAYPOINTS`); the message names the parameter.
    """
    name = command.pattern.name
    p = command.params
    anchor = anchor_for(current, state)
    same = current is not None and current.pattern == name
    if name in ("square", "box_orbit"):
        key = "side_span" if name == "square" else "radius"
        size = _positive(command, p, key, f"a {name.replace('_', ' ')} needs a size above 0 m")
        half = size / 2 if name == "square" else size
        if name == "square":
            return _plan_square(command, p, state, anchor, half, 0, 0.0)
        laps = int(p["laps"])
        # a lap in progress is flown again in full from the new entry point
        done = math.floor(current.progress(state) + 1e-9) if same and current else 0
        if laps - done <= 0:
            return _plan_hold(command, state, anchor)
        return _plan_square(command, p, state, anchor, half, laps - done, float(done))
    if name in ("circle", "helix", "spiral"):
        return _plan_circle_like(command, p, state, anchor, current, name)
    if name == "lawnmower":
        return _plan_lawnmower(command, p, state, current)
    if name == "straight":
        return _plan_straight(command, p, state, anchor, current)
    if name == "hover":
        return _plan_hover(command, p, state, anchor, current)
    if name == "surface":
        return _plan_surface(command, state, anchor)
    raise PlanError(f"the planner has no expansion for pattern {name!r} (ID {command.pattern.id})")
