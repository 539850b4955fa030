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

This module holds the rule and :func:`plan`, and the patterns that start from the vehicle's
pose or where it is (lawnmower, straight, hover, surface). The orbit patterns are
:mod:`planner._orbits`; the :class:`Plan` record, the path builder and the planner's rates and
bounds are :mod:`planner._build`, which both import. All three are the vehicle's: its replan
loads them (``nemesys bench reconfig`` measures the footprint).
"""

from __future__ import annotations

import math

from planner._build import (
    DEPTH_RATE_MPS,
    HEAVE_CAPABILITY_MPS,
    HOVER_APPROACH_MPS,
    LEAD_TURN_RADII,
    MAX_WAYPOINTS,
    MIN_TURN_RADIUS_M,
    YAW_RATE_DPS,
    Build,
    Plan,
    param_number,
    param_positive,
    param_speed,
    plan_hold,
    turn_radius_m,
)
from planner._errors import PlanError
from planner._geometry import arc, heading_deg, wrap
from planner._orbits import plan_circle_like, plan_square
from planner._path import Path, VehicleState

TYPE_CHECKING = False
if TYPE_CHECKING:
    from codec import Command
    from planner._build import Params

__all__ = [
    "DEPTH_RATE_MPS",
    "HEAVE_CAPABILITY_MPS",
    "HOVER_APPROACH_MPS",
    "LEAD_TURN_RADII",
    "MAX_WAYPOINTS",
    "MIN_TURN_RADIUS_M",
    "REPEATING_PATTERNS",
    "YAW_RATE_DPS",
    "Plan",
    "anchor_for",
    "plan",
    "turn_radius_m",
]

#: Patterns that repeat until retasked.
REPEATING_PATTERNS = frozenset({"square", "circle"})


def _plan_lawnmower(command: Command, p: Params, state: VehicleState, current: Plan | None) -> Plan:
    speed = param_speed(command, p)
    depth = param_number(p, "depth")
    length = param_positive(command, p, "sweep_length", "a lawnmower needs lanes longer than 0 m")
    spacing = param_positive(command, p, "lane_spacing", "lanes must be more than 0 m apart")
    n_lanes = 2 * int(p["laps"])
    b = Build(state)
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
            return plan_hold(command, state, current.anchor)
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
    speed = param_speed(command, p)
    depth = param_number(p, "depth")
    duration = param_positive(command, p, "duration", "a straight needs a duration above 0 s")
    heading = math.radians(param_number(p, "heading"))
    elapsed = 0.0
    if current is not None and current.pattern == "straight":
        elapsed = max(0.0, current.progress(state))
    b = Build(state)
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
        return plan_hold(command, state, anchor)
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
    duration = param_positive(command, p, "duration", "a hover needs a duration above 0 s")
    depth = param_number(p, "depth")
    heading = param_number(p, "heading")
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


def _plan_surface(command: Command, state: VehicleState, anchor: tuple[float, float]) -> Plan:
    b = Build(state)
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
        size = param_positive(command, p, key, f"a {name.replace('_', ' ')} needs a size above 0 m")
        half = size / 2 if name == "square" else size
        if name == "square":
            return plan_square(command, p, state, anchor, half, 0, 0.0)
        laps = int(p["laps"])
        # a lap in progress is flown again in full from the new entry point
        done = math.floor(current.progress(state) + 1e-9) if same and current else 0
        if laps - done <= 0:
            return plan_hold(command, state, anchor)
        return plan_square(command, p, state, anchor, half, laps - done, float(done))
    if name in ("circle", "helix", "spiral"):
        return plan_circle_like(command, p, state, anchor, current, name)
    if name == "lawnmower":
        return _plan_lawnmower(command, p, state, current)
    if name == "straight":
        return _plan_straight(command, p, state, anchor, current)
    if name == "hover":
        return _plan_hover(command, p, state, anchor, current)
    if name == "surface":
        return _plan_surface(command, state, anchor)
    raise PlanError(f"the planner has no expansion for pattern {name!r} (ID {command.pattern.id})")
