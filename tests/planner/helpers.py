"""Helpers of the planner tests: commands as the vehicle decodes them, and plain geometry.

Everything here is computed from first principles (positions, bearings, distances) and not
from the planner's own helpers, so the tests check the planner against an independent model.
"""

from __future__ import annotations

import math

import pytest

from codec import Command, ParamValue, decode_frame, encode_frame, make_command
from planner import (
    DEPTH_RATE_MPS,
    HEAVE_CAPABILITY_MPS,
    HOVER_APPROACH_MPS,
    Path,
    Plan,
    VehicleState,
)

#: Tolerance of floating-point comparisons of positions (m) and times (s).
TOL = 1e-6


def command(pattern: str, **params: ParamValue) -> Command:
    """The command the vehicle decodes for ``pattern`` with the requested values.

    The values are snapped by :func:`codec.make_command`, sent through a frame and decoded, so
    the planner always sees what the vehicle would receive.
    """
    snapped, _ = make_command(pattern, params)
    decoded = decode_frame(encode_frame(snapped).frame.bits).command
    assert decoded.pattern.name == snapped.pattern.name
    assert decoded.params == snapped.params
    return decoded


def num(cmd: Command, name: str) -> float:
    """A numeric parameter of ``cmd`` (the snapped value)."""
    value = cmd.params[name]
    assert not isinstance(value, str)
    return float(value)


def sense(cmd: Command) -> int:
    """+1 clockwise seen from above (bearing increasing), -1 counter-clockwise."""
    return 1 if cmd.params["direction"] == "cw" else -1


def vehicle(
    x: float = 0.0,
    y: float = 0.0,
    z: float = 2.0,
    heading: float = 0.0,
    speed: float = 0.5,
    t: float = 0.0,
) -> VehicleState:
    return VehicleState(x, y, z, heading, speed, t)


def on_path(p: Plan, t: float, tracked: bool = False) -> VehicleState:
    """The vehicle where ``p`` puts it ``t`` s after it took effect, flying its course.

    With ``tracked`` the state also says which segment guidance is on; otherwise
    ``segment`` is ``None`` and the planner has to find the vehicle on the path.
    """
    sp = p.path.sample(t)
    segment = None
    if tracked:
        times = p.path.times
        segment = max(i for i in range(len(times) - 1) if times[i] <= t)
    return VehicleState(
        sp.x_m, sp.y_m, sp.z_m, sp.course_deg, max(sp.speed_mps, 0.1), p.t0_s + t, segment
    )


def bearing(centre: tuple[float, float], x: float, y: float) -> float:
    """Bearing (rad, from north toward east) of ``(x, y)`` seen from ``centre``."""
    return math.atan2(y - centre[1], x - centre[0])


def wrap(a: float) -> float:
    """Angle in ``[-pi, pi)``."""
    return (a + math.pi) % (2 * math.pi) - math.pi


def angle_diff_deg(a: float, b: float) -> float:
    """Smallest absolute difference of two angles in degrees."""
    return abs((a - b + 180.0) % 360.0 - 180.0)


def dist(p: tuple[float, float], q: tuple[float, float]) -> float:
    return math.hypot(p[0] - q[0], p[1] - q[1])


def xy(path: Path, i: int) -> tuple[float, float]:
    return path.xs[i], path.ys[i]


def horizontal(path: Path, i: int) -> float:
    """Horizontal length of segment ``i -> i+1``."""
    return math.hypot(path.xs[i + 1] - path.xs[i], path.ys[i + 1] - path.ys[i])


def course(path: Path, i: int) -> float:
    """Course of segment ``i -> i+1`` (rad from north), computed here from the positions."""
    return math.atan2(path.ys[i + 1] - path.ys[i], path.xs[i + 1] - path.xs[i])


def straight_legs(path: Path, lo: int) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """Straight legs of the path from ``lo``: runs of horizontal segments on one course."""
    out: list[tuple[tuple[float, float], tuple[float, float]]] = []
    cur: float | None = None
    for i in range(lo, len(path) - 1):
        if horizontal(path, i) < TOL:
            continue
        c = math.atan2(path.ys[i + 1] - path.ys[i], path.xs[i + 1] - path.xs[i])
        if cur is not None and abs(math.remainder(c - cur, 2 * math.pi)) < 1e-9:
            out[-1] = (out[-1][0], xy(path, i + 1))
        else:
            out.append((xy(path, i), xy(path, i + 1)))
        cur = c
    return out


def turns_between(path: Path, lo: int, hi: int) -> list[tuple[int, float]]:
    """``(waypoint, |course change| rad)`` at every waypoint ``lo < k < hi`` joining two
    horizontal segments (vertical segments in between are skipped)."""
    out: list[tuple[int, float]] = []
    prev: float | None = None
    for i in range(lo, hi):
        if horizontal(path, i) < TOL:
            continue
        c = course(path, i)
        if prev is not None:
            out.append((i, abs(wrap(c - prev))))
        prev = c
    return out


def unwrapped_bearings(centre: tuple[float, float], path: Path, lo: int, hi: int) -> list[float]:
    """Bearings of waypoints ``lo..hi`` (inclusive) from ``centre``, unwrapped (rad)."""
    out: list[float] = []
    for i in range(lo, hi + 1):
        b = bearing(centre, path.xs[i], path.ys[i])
        out.append(b if not out else out[-1] + wrap(b - out[-1]))
    return out


def chord_error(
    curve: list[tuple[float, float]], a: tuple[float, float], b: tuple[float, float]
) -> float:
    """Largest distance from the points of ``curve`` to the segment ``ab``."""
    ax, ay = a
    dx, dy = b[0] - ax, b[1] - ay
    den = dx * dx + dy * dy
    worst = 0.0
    for px, py in curve:
        f = 0.0 if den == 0.0 else min(1.0, max(0.0, ((px - ax) * dx + (py - ay) * dy) / den))
        worst = max(worst, math.hypot(ax + f * dx - px, ay + f * dy - py))
    return worst


def depth_rate_violations(path: Path, rate: float, lo: int = 0) -> list[tuple[int, float]]:
    """Segments from ``lo`` whose depth rate exceeds ``rate``: ``(segment, |dz|/dt)``."""
    bad: list[tuple[int, float]] = []
    for i in range(lo, len(path) - 1):
        dz = abs(path.zs[i + 1] - path.zs[i])
        dt = path.times[i + 1] - path.times[i]
        if dz > TOL and (dt <= 0.0 or dz / dt > rate + 1e-9):
            bad.append((i, dz / dt if dt > 0 else math.inf))
    return bad


def swept_angles(
    centre: tuple[float, float], path: Path, lo: int, phi0: float, sense: int
) -> list[tuple[int, float]]:
    """``(waypoint, angle swept since bearing phi0 in the given sense)`` from ``lo`` on.

    The angle is followed from point to point (each step taken in ``(-pi, pi]``), so it
    counts whole turns; points at the centre (no bearing) are left out.
    """
    out: list[tuple[int, float]] = []
    theta = 0.0
    for i in range(lo, len(path)):
        if dist(xy(path, i), centre) < 1e-9:
            continue
        b = sense * (bearing(centre, path.xs[i], path.ys[i]) - phi0)
        theta += wrap(b - theta)
        out.append((i, theta))
    return out


#: One command of every pattern, both senses where there is one (name, requested values).
CASES: list[tuple[str, dict[str, ParamValue]]] = [
    ("square", {"speed": 0.5, "depth": 2, "side_span": 8, "direction": "cw"}),
    ("square", {"speed": 1.2, "depth": 6, "side_span": 3, "direction": "ccw"}),
    ("box_orbit", {"speed": 0.5, "depth": 3, "radius": 5, "direction": "cw", "laps": 2}),
    ("box_orbit", {"speed": 0.3, "depth": 1, "radius": 2.5, "direction": "ccw", "laps": 1}),
    ("circle", {"speed": 0.5, "depth": 3, "radius": 5, "direction": "cw"}),
    ("circle", {"speed": 1.0, "depth": 1, "radius": 20, "direction": "ccw"}),
    (
        "spiral",
        {
            "speed": 0.5,
            "depth": 2,
            "initial_radius": 2,
            "final_radius": 10,
            "loops": 3,
            "direction": "cw",
        },
    ),
    (
        "spiral",
        {
            "speed": 0.7,
            "depth": 4,
            "initial_radius": 12,
            "final_radius": 0,
            "loops": 2,
            "direction": "ccw",
        },
    ),
    (
        "spiral",
        {
            "speed": 0.4,
            "depth": 4,
            "initial_radius": 0,
            "final_radius": 8,
            "loops": 4,
            "direction": "cw",
        },
    ),
    (
        "helix",
        {
            "speed": 0.5,
            "start_depth": 2,
            "end_depth": 4,
            "radius": 2.5,
            "turns": 3,
            "direction": "cw",
        },
    ),
    (
        "helix",
        {
            "speed": 0.5,
            "start_depth": 9,
            "end_depth": 1,
            "radius": 1,
            "turns": 2,
            "direction": "ccw",
        },
    ),
    ("lawnmower", {"speed": 0.5, "depth": 3, "sweep_length": 20, "lane_spacing": 5, "laps": 2}),
    ("lawnmower", {"speed": 1.5, "depth": 0.5, "sweep_length": 7, "lane_spacing": 2, "laps": 1}),
    ("straight", {"speed": 0.5, "depth": 3, "duration": 60, "heading": 180}),
    ("straight", {"speed": 2.0, "depth": 0, "duration": 10, "heading": 22.5}),
    ("hover", {"duration": 60, "depth": 3, "heading": 45}),
    ("surface", {}),
]


def case_id(case: tuple[str, dict[str, ParamValue]]) -> str:
    name, params = case
    return name + "-" + "-".join(str(v) for v in params.values())


def check_timing(p: Plan, cmd: Command) -> None:
    """Times increase, the depth rate holds, speeds match lengths and times."""
    path = p.path
    name = cmd.pattern.name
    rate = HEAVE_CAPABILITY_MPS if name == "surface" else DEPTH_RATE_MPS
    cruise = HOVER_APPROACH_MPS if name in ("hover", "surface") else num(cmd, "speed")
    assert path.times[0] == 0.0
    for i in range(len(path) - 1):
        dt = path.times[i + 1] - path.times[i]
        same = path.point(i) == path.point(i + 1)
        assert dt > 0.0 or (dt == 0.0 and same), f"time does not advance at {i}"
    assert depth_rate_violations(path, rate) == []
    for i in range(len(path) - 1):
        h = horizontal(path, i)
        dt = path.times[i + 1] - path.times[i]
        v = path.speeds[i]
        assert v * dt == pytest.approx(h, rel=1e-9, abs=1e-6), f"speed column at {i}"
        assert v <= cruise + 1e-9, f"faster than commanded at {i}"
        if h > TOL and v < cruise * (1 - 1e-9):
            # slower than the cruise speed only where the depth rate needs the time
            dz = abs(path.zs[i + 1] - path.zs[i])
            assert dz / dt == pytest.approx(rate, rel=1e-6), f"slowed for nothing at {i}"
    if name not in ("hover", "surface"):
        # the depth ramp runs while the vehicle moves: it may finish in place only at the
        # end of a finite path, never by stopping in the middle of one (a segment shorter
        # than TOL flown at the cruise speed is a tiny step, not a stop: a vehicle 1e-6 m
        # off the commanded depth ramps it in a 1e-6 m chord)
        stops = [
            (i, round(path.times[i + 1] - path.times[i], 3))
            for i in range(len(path) - 1)
            if horizontal(path, i) < TOL
            and path.speeds[i] < cruise * (1 - 1e-9)
            and path.times[i + 1] > path.times[i]
            and (i < len(path) - 2 or path.loop_start is not None)
        ]
        assert stops == [], "the vehicle stops mid-path (segment, seconds) to change depth"
    if path.loop_start is None:
        assert path.speeds[-1] == 0.0
    else:
        assert path.speeds[-1] == path.speeds[path.loop_start]


def splits(p: Plan) -> set[int]:
    """Waypoints inserted on a chord (where a depth ramp meets the body depth): each lies
    strictly between its neighbours on the straight line through them."""
    path = p.path
    out: set[int] = set()
    for i in range(max(1, path.body_start), len(path) - 1):
        (ax, ay), (bx, by), (cx, cy) = xy(path, i - 1), xy(path, i), xy(path, i + 1)
        cross = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
        dot = (bx - ax) * (cx - bx) + (by - ay) * (cy - by)
        if abs(cross) < 1e-9 * max(1.0, dist((ax, ay), (cx, cy))) and dot > 0:
            out.add(i)
    return out


def body_points(p: Plan) -> list[int]:
    """Waypoints of the pattern itself: from ``body_start``, without ramp split points."""
    sp = splits(p)
    return [i for i in range(p.path.body_start, len(p.path)) if i not in sp]
