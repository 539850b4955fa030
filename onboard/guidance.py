"""Guidance: the planner's path -> (course, speed, depth) references for the autopilot.

Path following is line-of-sight with a lookahead on the path itself (the "enclosure" form of
Fossen's LOS): the vehicle steers at the point ``lookahead_m`` further along the path from
its projection. On a circle that is exact (the chord to the lookahead point asks for the
circle's curvature), and a repeating path wraps into its lap. The projection searches a
window of segments ahead of the active one (like MSS ``projectToPath``), so cutting a corner
never leaves the vehicle tied to a segment it has passed, and it never jumps back to an
earlier pass of a self-crossing path. Depth follows the path's own depth at the projection
(the planner already ramps it at 0.05 m/s).

Station keeping (hover, the end of a finite path, idle): NemeSys has no sway thruster, so it
turns to face the hold point and approaches when more than ``capture_m`` away, and holds the
heading inside ``settle_m`` (hysteresis). Hover and surfacing give the depth controller the
target depth as a step, as in the paper's tank test; the controller's thrust limit shapes the
transient.

The mode is the vehicle's word on its command (the status's ``mode``), so ``holding`` means
the command is done: guidance finishes a path at its horizontal end (a hover: when its time is
up), but a depth change the path leaves for the end (its ramp outlasting the horizontal path)
is still being flown there, in place; the mode stays ``running`` until the vehicle is at the
held depth, within :data:`AT_DEPTH_M` (issue 20: ``holding`` was reported with the vehicle
still 7 m above its depth). :attr:`Guidance.at_end` says guidance keeps station meanwhile.
"""

from __future__ import annotations

import math

from codec._record import Record, init
from planner import Plan
from vehicle_contract.codes import Mode


class GuidanceConfig(Record):
    """Guidance settings. A :class:`codec._record.Record`, not a dataclass: this module is on
    the onboard path, which keeps :mod:`dataclasses` (about 1.2 MB resident) out."""

    __slots__ = (
        "approach_gain_per_s",
        "approach_mps",
        "capture_m",
        "lookahead_m",
        "settle_m",
        "surfaced_depth_m",
    )
    lookahead_m: float
    capture_m: float  # start approaching the hold point beyond this
    settle_m: float  # stop approaching inside this
    approach_mps: float
    approach_gain_per_s: float
    surfaced_depth_m: float

    def __init__(
        self,
        lookahead_m: float = 1.5,
        capture_m: float = 1.0,
        settle_m: float = 0.3,
        approach_mps: float = 0.2,
        approach_gain_per_s: float = 0.3,
        surfaced_depth_m: float = 0.05,
    ) -> None:
        init(self, "lookahead_m", lookahead_m)
        init(self, "capture_m", capture_m)
        init(self, "settle_m", settle_m)
        init(self, "approach_mps", approach_mps)
        init(self, "approach_gain_per_s", approach_gain_per_s)
        init(self, "surfaced_depth_m", surfaced_depth_m)


class Reference:
    """What guidance asks of the autopilot for one tick."""

    __slots__ = ("course_rad", "depth_m", "speed_mps", "vertical")

    def __init__(
        self, course_rad: float, speed_mps: float, depth_m: float, vertical: bool = True
    ) -> None:
        self.course_rad = course_rad
        self.speed_mps = speed_mps
        self.depth_m = depth_m
        self.vertical = vertical  # False: vertical thrusters off (afloat at the surface)


#: The vehicle is at the held depth within this (m): the depth loop holds +-3 cm (the paper's
#: tank test), the depth sensor adds its noise. A finite pattern is ``holding`` (done) only then.
AT_DEPTH_M = 0.1


class Guidance:
    """Tracks one plan at a time; :meth:`set_plan` switches (the retask)."""

    def __init__(self, config: GuidanceConfig | None = None) -> None:
        self.config = config or GuidanceConfig()
        self.plan: Plan | None = None
        self.mode = Mode.IDLE
        self.segment = 0
        self.cross_track_m = 0.0
        self.hold: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)  # x, y, z, hdg rad
        self._approaching = False
        self._started_s = 0.0
        #: The plan's path is flown to its end (a hover: its time is up) and guidance keeps
        #: station there; the mode is ``running`` until the vehicle is at the held depth.
        self.at_end = False

    def hold_here(self, x_m: float, y_m: float, z_m: float, heading_deg: float) -> None:
        """Station keeping at a pose (idle, and after a finite pattern)."""
        self.hold = (x_m, y_m, z_m, math.radians(heading_deg))
        self._approaching = False

    def set_plan(self, plan: Plan, t_s: float) -> None:
        """Switch to ``plan`` (already joined from the current pose by the planner)."""
        self.plan = plan
        self.segment = 0
        self._started_s = t_s
        self._approaching = False
        self.at_end = False
        self.cross_track_m = 0.0
        path = plan.path
        name = plan.pattern
        if name == "surface":
            self.mode = Mode.SURFACING
            self.hold = (path.xs[0], path.ys[0], 0.0, math.radians(path.course_deg(0)))
        elif name == "hover":
            self.mode = Mode.RUNNING
            heading = path.hold_heading_deg or 0.0
            self.hold = (plan.origin[0], plan.origin[1], path.zs[-1], math.radians(heading))
        else:
            self.mode = Mode.RUNNING

    def update(self, x_m: float, y_m: float, z_m: float, t_s: float) -> Reference:
        """References for the vehicle at ``(x, y, z)`` (NED m) and ``t_s`` (s)."""
        plan = self.plan
        if self.mode is Mode.SURFACING or self.mode is Mode.SURFACED:
            hdg = self.hold[3]
            if z_m <= self.config.surfaced_depth_m:
                self.mode = Mode.SURFACED
            return Reference(hdg, 0.0, 0.0, self.mode is Mode.SURFACING)
        if plan is None or self.mode is Mode.HOLDING or self.mode is Mode.IDLE:
            return self._station(x_m, y_m)
        if plan.pattern == "hover" and t_s - self._started_s >= plan.path.duration_s:
            self.at_end = True
        if self.at_end:
            self._arrive(z_m)
            return self._station(x_m, y_m)
        if plan.pattern == "hover":
            return self._station(x_m, y_m)
        return self._follow(plan, x_m, y_m, z_m)

    def _arrive(self, z_m: float) -> None:
        """At the path's end: the command is done (``holding``) once the vehicle is at the
        held depth."""
        if abs(z_m - self.hold[2]) <= AT_DEPTH_M:
            self.mode = Mode.HOLDING

    # --- path following ------------------------------------------------------------------

    def _follow(self, plan: Plan, x: float, y: float, z: float) -> Reference:
        path = plan.path
        xs, ys, zs = path.xs, path.ys, path.zs
        n = len(xs)
        if n == 1:
            self._finish(plan, z)
            return self._station(x, y)
        look = self.config.lookahead_m
        loop = path.loop_start
        # window search: segments from the active one up to `look` metres of path beyond it
        best_i, best_f, best_d = self.segment, 0.0, math.inf
        i = self.segment
        ahead = 0.0
        for _ in range(n):
            f, d = _project(xs[i], ys[i], xs[i + 1], ys[i + 1], x, y)
            # on a tie (the end of one segment is the start of the next) the later one wins
            if d < best_d - 1e-9 or (d <= best_d + 1e-9 and best_f >= 1.0):
                best_i, best_f, best_d = i, f, d
            ahead += math.hypot(xs[i + 1] - xs[i], ys[i + 1] - ys[i])
            if ahead > look and i != self.segment:
                break
            i += 1
            if i >= n - 1:
                if loop is None:
                    break
                i = loop
        i, f = best_i, best_f
        self.segment = i
        self.cross_track_m = best_d
        if loop is None and i == n - 2 and f >= 1.0:
            self._finish(plan, z)
            return self._station(x, y)
        # the lookahead point
        px = xs[i] + f * (xs[i + 1] - xs[i])
        py = ys[i] + f * (ys[i + 1] - ys[i])
        depth = zs[i] + f * (zs[i + 1] - zs[i])
        left = look
        j, cx, cy = i, px, py
        while True:
            sx, sy = xs[j + 1] - cx, ys[j + 1] - cy
            seg = math.hypot(sx, sy)
            if seg >= left:
                cx, cy = cx + sx * left / seg, cy + sy * left / seg
                break
            left -= seg
            cx, cy = xs[j + 1], ys[j + 1]
            j += 1
            if j >= n - 1:
                if loop is None:
                    break
                j = loop
        if math.hypot(cx - x, cy - y) < 1e-6:
            course = math.radians(path.course_deg(i))
        else:
            course = math.atan2(cy - y, cx - x)
        return Reference(course, path.speeds[i], depth)

    def _finish(self, plan: Plan, z: float) -> None:
        """The path's horizontal end: hold its last waypoint (done at its depth)."""
        path = plan.path
        if path.hold_heading_deg is not None:
            heading = path.hold_heading_deg
        elif len(path) > 1:
            heading = path.course_deg(len(path) - 2)
        else:
            heading = plan.angle_deg
        self.hold_here(path.xs[-1], path.ys[-1], path.zs[-1], heading)
        self.at_end = True
        self._arrive(z)

    # --- station keeping -----------------------------------------------------------------

    def _station(self, x: float, y: float) -> Reference:
        cfg = self.config
        hx, hy, hz, hdg = self.hold
        dist = math.hypot(hx - x, hy - y)
        if dist > cfg.capture_m:
            self._approaching = True
        elif dist < cfg.settle_m:
            self._approaching = False
        if self._approaching:
            speed = min(cfg.approach_mps, cfg.approach_gain_per_s * dist)
            return Reference(math.atan2(hy - y, hx - x), speed, hz)
        return Reference(hdg, 0.0, hz)


def _project(ax: float, ay: float, bx: float, by: float, x: float, y: float) -> tuple[float, float]:
    """Fraction along segment a->b (clamped to [0, 1]) of the point nearest (x, y); distance.

    A segment with no horizontal extent (a depth change in place) counts as passed (1.0) as
    soon as it is the nearest: its depth becomes the reference as a step.
    """
    dx, dy = bx - ax, by - ay
    den = dx * dx + dy * dy
    f = 1.0 if den < 1e-12 else min(1.0, max(0.0, ((x - ax) * dx + (y - ay) * dy) / den))
    ex, ey = ax + f * dx - x, ay + f * dy - y
    return f, math.hypot(ex, ey)
