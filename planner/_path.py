"""Paths: 3D waypoints in NED with per-point speed, arrival time and progress mark.

A :class:`Path` is stored as parallel tuples (one float per waypoint per quantity), which is
both the fastest layout to build in pure Python and the smallest to keep on the vehicle.
"""

from __future__ import annotations

import math

from codec._record import Record, init
from planner._geometry import heading_deg

TYPE_CHECKING = False
if TYPE_CHECKING:
    from planner._sampling import Setpoint

#: Distances and depth differences below this are treated as zero (m).
EPS_M = 1e-6
#: Passes of a path closer than this to the nearest are told apart by time (m).
SAME_PLACE_M = 0.5


class VehicleState(Record):
    """The vehicle as the planner sees it when a command takes effect.

    Attributes:
        x_m, y_m, z_m: position in NED metres (north, east, depth; depth >= 0 is below the
            surface).
        heading_deg: heading, degrees clockwise from north.
        speed_mps: speed through the water (m/s).
        t_s: mission clock (s); a plan's times are relative to its own start, ``Plan.t0_s``.
        segment: index ``i`` of the active path's segment ``i -> i+1`` that guidance is
            tracking, when known; otherwise the planner projects the position on the path.
    """

    __slots__ = ("heading_deg", "segment", "speed_mps", "t_s", "x_m", "y_m", "z_m")
    x_m: float
    y_m: float
    z_m: float
    heading_deg: float
    speed_mps: float
    t_s: float
    segment: int | None

    def __init__(
        self,
        x_m: float,
        y_m: float,
        z_m: float,
        heading_deg: float = 0.0,
        speed_mps: float = 0.0,
        t_s: float = 0.0,
        segment: int | None = None,
    ) -> None:
        for name, value in (
            ("x_m", x_m),
            ("y_m", y_m),
            ("z_m", z_m),
            ("heading_deg", heading_deg),
            ("speed_mps", speed_mps),
            ("t_s", t_s),
        ):
            if not math.isfinite(value):
                raise ValueError(f"vehicle state {name} must be a finite number, got {value!r}")
        if segment is not None and segment < 0:
            raise ValueError(f"vehicle state segment must be >= 0 or None, got {segment}")
        init(self, "x_m", float(x_m))
        init(self, "y_m", float(y_m))
        init(self, "z_m", float(z_m))
        init(self, "heading_deg", float(heading_deg) % 360.0)
        init(self, "speed_mps", float(speed_mps))
        init(self, "t_s", float(t_s))
        init(self, "segment", segment)

    @property
    def heading_rad(self) -> float:
        return math.radians(self.heading_deg)


class Path(Record):
    """Waypoints the vehicle flies, in order, straight between consecutive points.

    Attributes:
        xs, ys, zs: waypoint positions, NED metres.
        speeds: horizontal speed (m/s) commanded from waypoint ``i`` to ``i + 1`` (lower than
            the cruise speed where the depth rate limit needs more time); the last is 0
            (hold) or, for a repeating path, the speed into the repeated lap.
        times: arrival time at each waypoint (s after the plan takes effect).
        marks: the pattern's progress coordinate at each waypoint (laps or turns for orbit
            patterns, waypoint number for the lawnmower, seconds for straight and hover);
            it is what a parameter-only retask continues from.
        body_start: index of the first waypoint of the pattern itself (before it: the join).
        loop_start: for patterns that repeat until retasked (circle, square), the index
            where the repeated lap starts; the lap runs to the last waypoint, which equals
            the ``loop_start`` waypoint. ``None`` for finite paths, which end in a hold.
        hold_heading_deg: heading to hold at the end (hover), or ``None`` to keep the last.
    """

    __slots__ = (
        "body_start",
        "hold_heading_deg",
        "loop_start",
        "marks",
        "speeds",
        "times",
        "xs",
        "ys",
        "zs",
    )
    xs: tuple[float, ...]
    ys: tuple[float, ...]
    zs: tuple[float, ...]
    speeds: tuple[float, ...]
    times: tuple[float, ...]
    marks: tuple[float, ...]
    body_start: int
    loop_start: int | None
    hold_heading_deg: float | None

    def __init__(
        self,
        xs: tuple[float, ...],
        ys: tuple[float, ...],
        zs: tuple[float, ...],
        speeds: tuple[float, ...],
        times: tuple[float, ...],
        marks: tuple[float, ...],
        body_start: int = 0,
        loop_start: int | None = None,
        hold_heading_deg: float | None = None,
    ) -> None:
        n = len(xs)
        if n == 0 or any(len(c) != n for c in (ys, zs, speeds, times, marks)):
            raise ValueError("a path needs at least one waypoint and columns of equal length")
        if not 0 <= body_start < n or (loop_start is not None and not 0 <= loop_start < n):
            raise ValueError("body_start and loop_start must index waypoints")
        init(self, "xs", xs)
        init(self, "ys", ys)
        init(self, "zs", zs)
        init(self, "speeds", speeds)
        init(self, "times", times)
        init(self, "marks", marks)
        init(self, "body_start", body_start)
        init(self, "loop_start", loop_start)
        init(self, "hold_heading_deg", hold_heading_deg)

    def __len__(self) -> int:
        return len(self.xs)

    @property
    def duration_s(self) -> float:
        """Time to the last waypoint (one lap for a repeating path)."""
        return self.times[-1]

    def point(self, i: int) -> tuple[float, float, float]:
        return self.xs[i], self.ys[i], self.zs[i]

    def course_deg(self, i: int) -> float:
        """Course of segment ``i -> i+1`` (deg from north); the previous one if it is vertical."""
        n = len(self.xs)
        j = min(i, n - 2)
        while j >= 0:
            dx, dy = self.xs[j + 1] - self.xs[j], self.ys[j + 1] - self.ys[j]
            if dx * dx + dy * dy > EPS_M * EPS_M:
                return heading_deg(math.atan2(dy, dx))
            j -= 1
        return self.hold_heading_deg if self.hold_heading_deg is not None else 0.0

    def length_m(self, start: int = 0, stop: int | None = None) -> float:
        """3D length from waypoint ``start`` to ``stop`` (default: the end) (m)."""
        from planner._sampling import length_m  # the console's: not loaded onboard

        return length_m(self, start, stop)

    def sample(self, t_s: float) -> Setpoint:
        """The setpoint at ``t_s`` after the plan starts, interpolated between waypoints.

        Before 0 gives the first waypoint; past the end, a repeating path wraps into its lap
        and a finite one holds its last waypoint at speed 0.
        """
        from planner._sampling import sample  # the console's: not loaded onboard

        return sample(self, t_s)

    def locate(
        self,
        x_m: float,
        y_m: float,
        z_m: float,
        hint: int | None = None,
        t_s: float | None = None,
    ) -> float:
        """Fractional waypoint index of the path point nearest to ``(x, y, z)``.

        With ``hint`` (the segment guidance is tracking) only that segment is used. Otherwise
        every segment is searched; where the path passes the same place more than once (laps
        of a box orbit, a flat helix), the pass whose times are nearest ``t_s`` (seconds into
        the plan) wins among those within :data:`SAME_PLACE_M` of the nearest.
        """
        xs, ys, zs = self.xs, self.ys, self.zs
        n = len(xs)
        if n == 1:
            return 0.0
        if hint is not None and hint < n - 1:
            candidates: range = range(hint, hint + 1)
        else:
            candidates = range(n - 1)
        found: list[tuple[float, int, float]] = []
        for i in candidates:
            ax, ay, az = xs[i], ys[i], zs[i]
            dx, dy, dz = xs[i + 1] - ax, ys[i + 1] - ay, zs[i + 1] - az
            den = dx * dx + dy * dy + dz * dz
            f = (
                0.0
                if den == 0.0
                else min(1.0, max(0.0, ((x_m - ax) * dx + (y_m - ay) * dy + (z_m - az) * dz) / den))
            )
            ex, ey, ez = ax + f * dx - x_m, ay + f * dy - y_m, az + f * dz - z_m
            found.append((math.sqrt(ex * ex + ey * ey + ez * ez), i, f))
        nearest = min(found)
        if t_s is None:
            return nearest[1] + nearest[2]
        times = self.times
        close = [c for c in found if c[0] <= nearest[0] + SAME_PLACE_M]
        _, i, f = min(
            close, key=lambda c: abs(times[c[1]] + c[2] * (times[c[1] + 1] - times[c[1]]) - t_s)
        )
        return i + f

    def mark_at(self, index: float) -> float:
        """Progress mark at a fractional waypoint index."""
        i = min(int(index), len(self.marks) - 1)
        if i >= len(self.marks) - 1:
            return self.marks[-1]
        f = index - i
        return self.marks[i] + f * (self.marks[i + 1] - self.marks[i])

    def mark_at_time(self, t_s: float) -> float:
        """Progress mark at ``t_s`` after the plan starts (clamped to the path's span)."""
        times = self.times
        if t_s <= times[0]:
            return self.marks[0]
        for i in range(1, len(times)):
            if times[i] >= t_s:
                span = times[i] - times[i - 1]
                f = (t_s - times[i - 1]) / span if span > 0 else 1.0
                return self.marks[i - 1] + f * (self.marks[i] - self.marks[i - 1])
        return self.marks[-1]


def timed(  # noqa: PLR0915 (one flat loop: the planner's hot path)
    xs: list[float],
    ys: list[float],
    zb: list[float],
    marks: list[float],
    z0: float,
    speed_mps: float,
    rate_mps: float,
) -> tuple[list[float], list[float], list[float], list[float], list[float], list[float], list[int]]:
    """Give a horizontal polyline its depths, speeds and times.

    ``zb`` is the depth the pattern asks for at each point; the vehicle starts at ``z0``. Each
    segment takes ``max(horizontal / speed, |body depth change| / rate)``: a pattern steeper
    than the depth rate is flown slower. The vehicle's own depth follows the body depth with
    a ramp limited to ``rate_mps`` that runs while it keeps moving (a waypoint is inserted
    where the ramp meets the body depth); if the horizontal path ends first, the ramp
    finishes in place. Zero-length segments are dropped.

    Returns:
        ``(xs, ys, zs, speeds, times, marks, where)``; ``where[i]`` is the output index of
        input waypoint ``i`` (of the last point kept before it, if it was dropped).
    """
    px, py, z, t = xs[0], ys[0], z0, 0.0
    ox, oy, oz, ot, om = [px], [py], [z0], [0.0], [marks[0]]
    sp: list[float] = []
    where = [0]
    ax, ay, az, at, am, asp, aw = (
        ox.append,
        oy.append,
        oz.append,
        ot.append,
        om.append,
        sp.append,
        where.append,
    )
    hypot = math.hypot
    zp = zb[0]
    for i in range(1, len(xs)):
        x1, y1, zt = xs[i], ys[i], zb[i]
        h = hypot(x1 - px, y1 - py)
        if h < EPS_M:
            # a vertical step of the pattern itself; a repeated point is dropped (a ramp in
            # progress carries on along the next segment rather than stopping here)
            dz = zt - z
            if (zt - zp >= EPS_M or zt - zp <= -EPS_M) and (dz >= EPS_M or dz <= -EPS_M):
                t += abs(dz) / rate_mps
                ax(x1)
                ay(y1)
                az(zt)
                at(t)
                am(marks[i])
                asp(0.0)
                z = zt
            aw(len(ox) - 1)
            px, py, zp = x1, y1, zt
            continue
        dzb = zt - zp
        dt = h / speed_mps
        if dzb * dzb > (rate_mps * dt) ** 2:
            dt = abs(dzb) / rate_mps
        v = h / dt
        gap = zp - z
        if -EPS_M < gap < EPS_M:
            z = zt
        else:
            sgn = 1.0 if gap > 0.0 else -1.0
            slope = dzb / dt
            closing = rate_mps - sgn * slope
            tau = abs(gap) / closing if closing > 1e-12 else math.inf
            if tau < dt - 1e-9:
                f = tau / dt
                ax(px + f * (x1 - px))
                ay(py + f * (y1 - py))
                az(zp + slope * tau)
                at(t + tau)
                am(om[-1] + f * (marks[i] - om[-1]))
                asp(v)
                z = zt
            else:
                z += sgn * rate_mps * dt
        t += dt
        ax(x1)
        ay(y1)
        az(z)
        at(t)
        am(marks[i])
        asp(v)
        aw(len(ox) - 1)
        px, py, zp = x1, y1, zt
    gap = zb[-1] - z
    if abs(gap) >= EPS_M:
        t += abs(gap) / rate_mps
        ax(px)
        ay(py)
        az(zb[-1])
        at(t)
        am(om[-1])
        asp(0.0)
    asp(0.0)
    return ox, oy, oz, sp, ot, om, where
