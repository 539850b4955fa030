"""Plane geometry for the planner: curve sampling with a chord bound, and Dubins joins.

Coordinates are NED metres (x north, y east). Angles here are radians measured from north
toward east, so an angle that increases turns clockwise seen from above, like a compass
bearing. A point at angle ``a`` and distance ``r`` from ``(cx, cy)`` is
``(cx + r cos a, cy + r sin a)``; a heading ``h`` points along ``(cos h, sin h)``.

Sampling bound: every curve (circle, arc, spiral, helix, join) is replaced by chords that
deviate from the true curve by at most :data:`CHORD_TOL_M` horizontally, and no chord turns
through more than :data:`MAX_STEP_RAD`.
"""

from __future__ import annotations

import math

#: Largest horizontal distance between a sampled chord and the true curve (m).
CHORD_TOL_M = 0.05
#: Largest angle a single chord may subtend at the centre of curvature (rad): 8 per turn.
MAX_STEP_RAD = math.pi / 4

TAU = 2.0 * math.pi
_ANGLE_EPS = 1e-9


def step_angle(radius_m: float) -> float:
    """Largest angle step (rad) on a circle of ``radius_m`` that keeps the chord error bound."""
    if radius_m <= CHORD_TOL_M:
        return MAX_STEP_RAD
    return min(MAX_STEP_RAD, 2.0 * math.acos(1.0 - CHORD_TOL_M / radius_m))


def wrap(angle_rad: float) -> float:
    """Angle in ``(-pi, pi]``."""
    a = math.fmod(angle_rad, TAU)
    if a <= -math.pi:
        a += TAU
    elif a > math.pi:
        a -= TAU
    return a


def heading_deg(angle_rad: float) -> float:
    """Radians from north -> compass degrees in ``[0, 360)``."""
    d = math.degrees(angle_rad) % 360.0
    return 0.0 if d >= 360.0 else d


def arc(
    xs: list[float],
    ys: list[float],
    centre: tuple[float, float],
    radius_m: float,
    start_rad: float,
    sweep_rad: float,
    marks: tuple[list[float], float, float] | None = None,
) -> None:
    """Append the sampled arc (end point included, start point not) to ``xs``, ``ys``.

    ``start_rad`` is the angle of the start point around ``centre``; ``sweep_rad`` is signed
    (positive: clockwise seen from above). ``marks = (ms, m0, m1)`` also appends to ``ms`` a
    progress mark running linearly from ``m0`` (start) to ``m1`` (end).
    """
    if abs(sweep_rad) < _ANGLE_EPS:
        return
    n = max(1, math.ceil(abs(sweep_rad) / step_angle(radius_m) - 1e-9))
    d = sweep_rad / n
    cx, cy = centre
    cos, sin = math.cos, math.sin
    for k in range(1, n + 1):
        a = start_rad + d * k
        xs.append(cx + radius_m * cos(a))
        ys.append(cy + radius_m * sin(a))
    if marks is not None:
        ms, m0, m1 = marks
        dm = (m1 - m0) / n
        ms.extend([m0 + dm * k for k in range(1, n + 1)])


def _sweep(turn: int, from_rad: float, to_rad: float) -> float:
    """Unsigned angle (rad, in ``[0, 2 pi)``) turned from one heading to another in ``turn``."""
    s = (turn * (to_rad - from_rad)) % TAU
    return 0.0 if s > TAU - _ANGLE_EPS or s < _ANGLE_EPS else s


def dubins(
    start: tuple[float, float, float],
    goal: tuple[float, float, float],
    radius_m: float,
) -> tuple[list[float], list[float], float]:
    """Shortest turn-straight-turn path between two poses ``(x, y, heading_rad)``.

    The path leaves ``start`` along its heading and arrives at ``goal`` along the goal's
    heading, turning on circles of ``radius_m``: the join has no heading step at either end.
    Of the four CSC words the shortest feasible one is taken (the two same-sense words always
    exist, so there is always an answer).

    Returns:
        ``(xs, ys, length_m)``: the sampled points after ``start`` up to and including
        ``goal``, and the path length.
    """
    x0, y0, h0 = start
    x1, y1, h1 = goal
    r = radius_m
    best: tuple[float, int, int, float, float] | None = None
    for s1 in (1, -1):
        c1x, c1y = x0 - s1 * r * math.sin(h0), y0 + s1 * r * math.cos(h0)
        for s2 in (1, -1):
            c2x, c2y = x1 - s2 * r * math.sin(h1), y1 + s2 * r * math.cos(h1)
            dx, dy = c2x - c1x, c2y - c1y
            dist = math.hypot(dx, dy)
            if s1 == s2:
                hs = math.atan2(dy, dx) if dist > _ANGLE_EPS else h0
                straight = dist
            else:
                if dist < 2.0 * r:
                    continue
                hs = math.atan2(dy, dx) + math.asin(2.0 * s1 * r / dist)
                straight = math.sqrt(max(0.0, dist * dist - 4.0 * r * r))
            length = r * (_sweep(s1, h0, hs) + _sweep(s2, hs, h1)) + straight
            if best is None or length < best[0]:
                best = (length, s1, s2, hs, straight)
    assert best is not None  # the same-sense words always exist
    length, s1, s2, hs, straight = best
    xs: list[float] = []
    ys: list[float] = []
    c1 = (x0 - s1 * r * math.sin(h0), y0 + s1 * r * math.cos(h0))
    arc(xs, ys, c1, r, h0 - s1 * math.pi / 2, s1 * _sweep(s1, h0, hs))
    c2 = (x1 - s2 * r * math.sin(h1), y1 + s2 * r * math.cos(h1))
    a2 = hs - s2 * math.pi / 2
    if straight > _ANGLE_EPS:
        xs.append(c2[0] + r * math.cos(a2))
        ys.append(c2[1] + r * math.sin(a2))
    arc(xs, ys, c2, r, a2, s2 * _sweep(s2, hs, h1))
    if xs:
        xs[-1], ys[-1] = x1, y1
    elif math.hypot(x1 - x0, y1 - y0) > _ANGLE_EPS:
        xs.append(x1)
        ys.append(y1)
    return xs, ys, length
