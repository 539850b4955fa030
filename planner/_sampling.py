"""Sampling a path in time, and its length: the console's previews, estimates and benches.

:meth:`planner.Path.sample` and :meth:`planner.Path.length_m` call into this module, loaded on
first use: the vehicle's guidance follows the waypoints themselves and never samples.
"""

from __future__ import annotations

import math

from codec._record import Record, init

TYPE_CHECKING = False
if TYPE_CHECKING:
    from planner._path import Path


class Setpoint(Record):
    """Where the path wants the vehicle at one time: position (m), speed (m/s), course (deg)."""

    __slots__ = ("course_deg", "speed_mps", "t_s", "x_m", "y_m", "z_m")
    t_s: float
    x_m: float
    y_m: float
    z_m: float
    speed_mps: float
    course_deg: float

    def __init__(
        self, t_s: float, x_m: float, y_m: float, z_m: float, speed_mps: float, course_deg: float
    ) -> None:
        init(self, "t_s", t_s)
        init(self, "x_m", x_m)
        init(self, "y_m", y_m)
        init(self, "z_m", z_m)
        init(self, "speed_mps", speed_mps)
        init(self, "course_deg", course_deg)


def length_m(path: Path, start: int = 0, stop: int | None = None) -> float:
    """3D length from waypoint ``start`` to ``stop`` (default: the end)."""
    xs, ys, zs = path.xs, path.ys, path.zs
    end = len(xs) - 1 if stop is None else stop
    return sum(
        math.sqrt((xs[i + 1] - xs[i]) ** 2 + (ys[i + 1] - ys[i]) ** 2 + (zs[i + 1] - zs[i]) ** 2)
        for i in range(start, end)
    )


def sample(path: Path, t_s: float) -> Setpoint:
    """The setpoint at ``t_s`` after the plan starts, interpolated between waypoints.

    Before 0 gives the first waypoint; past the end, a repeating path wraps into its lap
    and a finite one holds its last waypoint at speed 0.
    """
    times = path.times
    t_end = times[-1]
    if t_s > t_end and path.loop_start is not None:
        t_loop = times[path.loop_start]
        lap = t_end - t_loop
        t_s = t_loop + math.fmod(t_s - t_loop, lap) if lap > 0 else t_loop
    if t_s <= times[0] or len(times) == 1:
        i, f = 0, 0.0
    elif t_s >= t_end:
        i, f = len(times) - 2, 1.0
    else:
        lo, hi = 0, len(times) - 1
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if times[mid] <= t_s:
                lo = mid
            else:
                hi = mid
        i = lo
        span = times[i + 1] - times[i]
        f = (t_s - times[i]) / span if span > 0 else 1.0
    if len(times) == 1:
        x, y, z = path.point(0)
        return Setpoint(t_s, x, y, z, 0.0, path.course_deg(0))
    x = path.xs[i] + f * (path.xs[i + 1] - path.xs[i])
    y = path.ys[i] + f * (path.ys[i + 1] - path.ys[i])
    z = path.zs[i] + f * (path.zs[i + 1] - path.zs[i])
    finished = t_s >= t_end and path.loop_start is None
    speed = 0.0 if finished else path.speeds[i]
    return Setpoint(t_s, x, y, z, speed, path.course_deg(i))
