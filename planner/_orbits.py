"""The orbit patterns, centred on the mission anchor: square and box orbit, circle, helix and
spiral (the anchoring rule and the retask join are :mod:`planner._plan`'s).

Each is entered tangentially from the vehicle's pose and keeps the anchor across a retask; a
change of parameters only continues from the vehicle's progress (finite orbits keep the turns
already flown), and a repeating one flies extra laps until its depth ramp ends so that the
repeated loop is level.
"""

from __future__ import annotations

import math

from planner._build import (
    DEPTH_RATE_MPS,
    LEAD_TURN_RADII,
    MAX_WAYPOINTS,
    Build,
    Plan,
    param_number,
    param_positive,
    param_sense,
    param_speed,
    plan_hold,
    turn_radius_m,
)
from planner._errors import PlanError
from planner._geometry import (
    CHORD_TOL_M,
    MAX_STEP_RAD,
    TAU,
    arc,
    dubins,
    heading_deg,
    step_angle,
)
from planner._path import EPS_M, VehicleState

TYPE_CHECKING = False
if TYPE_CHECKING:
    from codec import Command
    from planner._build import Params


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


def plan_square(
    command: Command,
    p: Params,
    state: VehicleState,
    anchor: tuple[float, float],
    half_m: float,
    laps: int,
    mark0: float,
) -> Plan:
    """square (``laps == 0``: repeats) and box orbit (``laps`` orbits, marks from ``mark0``)."""
    speed = param_speed(command, p)
    sense = param_sense(p)
    depth = param_number(p, "depth")
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
    b = Build(state)
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
        r0, r1 = param_number(p, "initial_radius"), param_number(p, "final_radius")
        if r0 <= 0.0 and r1 <= 0.0:
            raise PlanError(
                "initial_radius and final_radius are both 0 m: a spiral needs one above 0 m",
                field="final_radius",
            )
        depth = param_number(p, "depth")
        return r0, r1, depth, depth, float(p["loops"])
    r = param_positive(command, p, "radius", f"a {shape} needs a radius above 0 m")
    if shape == "helix":
        return r, r, param_number(p, "start_depth"), param_number(p, "end_depth"), float(p["turns"])
    return r, r, param_number(p, "depth"), param_number(p, "depth"), 1.0


def plan_circle_like(
    command: Command,
    p: Params,
    state: VehicleState,
    anchor: tuple[float, float],
    current: Plan | None,
    shape: str,
) -> Plan:
    """circle (repeats), helix (turns between two depths) and spiral (two radii)."""
    speed = param_speed(command, p)
    sense = param_sense(p)
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
            return plan_hold(command, state, anchor)
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
    b = Build(state)
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
    b: Build,
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
