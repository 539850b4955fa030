"""The kinematic twin: the real onboard guidance flying a plan on a vehicle reduced to the
figures of its profile. The preview's estimate is timed by it, so that the estimate, the
prediction (the full twin, :mod:`sim.simulation`) and the vehicle's own run tell one
duration story (issue 20).

What it keeps of the full twin, and why each matters to a duration:

* guidance itself (:class:`onboard.guidance.Guidance`): the line-of-sight lookahead cuts
  corners and flies inside tight circles (a 2 m square is flown ~25 % shorter than its path),
  a hover ends on its own clock, a path ends at its horizontal end, and either is done once
  the vehicle is at the held depth;
* the autopilot's laws (:class:`sim.control.AutopilotGains`): the heading turns at
  ``heading_k_per_s`` times its error, at most the yaw rate (the autopilot's limit, at most the
  vehicle's), and the surge slows to ``cos^2`` of the heading error while it turns;
* the vehicle's figures (:class:`Rates`): the top speed through the water caps every speed,
  and the depth moves towards guidance's reference at the descent or ascent rate: a depth the
  path leaves for the end (its ramp outlasting the horizontal path) is flown in place at the
  vehicle's rate, not at the planner's 0.05 m/s ramp;
* the completion rule (:class:`sim.completion.Completion`): a finite pattern is done at its
  end and depth, a repeating one after the join and one lap.

What it leaves out: accelerations (about a second of surge and yaw transients), the depth
loop's overshoot, the current, the battery. It steps at a quarter of guidance's lookahead (a
jump along a straight leg the vehicle already follows), so a pattern costs a few hundred
guidance ticks: milliseconds, for every preview.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import pairwise

from onboard.guidance import Guidance, GuidanceConfig, Reference
from planner import DEPTH_RATE_MPS, YAW_RATE_DPS, Path, Plan
from sim.completion import AT_DEPTH_M, Completion
from sim.control import AutopilotGains, wrap_rad
from vehicle_contract.codes import Mode

#: Horizontal distance per step, as a fraction of guidance's lookahead; for a long path, at
#: most about :data:`PATH_STEPS` steps (up to a whole lookahead each: the curvature of a path
#: that long is gentle).
STEP_LOOKAHEADS = 0.25
PATH_STEPS = 3000
#: Shortest and longest step (s) while moving (longer for a path whose plan takes more than
#: :data:`PATH_STEPS` of them); longest while holding still.
MIN_STEP_S = 0.1
MAX_STEP_S = 2.0
MAX_HOLD_STEP_S = 60.0
#: Most steps flown before giving up (a path the vehicle cannot follow, its turns too tight for
#: its speed): ~0.1 s of one core. A pattern takes a few hundred.
MAX_STEPS = 10_000
#: A flight longer than this many times the plan's own duration (and an hour) is given up.
MAX_STRETCH = 20.0
_EPS = 1e-9


@dataclass(frozen=True, slots=True)
class Rates:
    """What the kinematic vehicle can do; ``None``: unknown, flown as the plan asks (its speed;
    depth steps at the planner's own rate)."""

    #: Top speed through the water (m/s).
    top_speed_mps: float | None = None
    #: Fastest descent (m/s).
    descent_mps: float | None = None
    #: Fastest ascent (m/s); None: the descent rate.
    ascent_mps: float | None = None
    #: Fastest turn (deg/s): the autopilot's limit, at most the vehicle's own.
    yaw_rate_dps: float = YAW_RATE_DPS
    #: The autopilot's heading law: turn rate per radian of heading error (1/s).
    heading_gain_per_s: float = AutopilotGains().heading_k_per_s


@dataclass(frozen=True, slots=True)
class Flight:
    """How the kinematic twin flew a plan (s from the plan taking effect)."""

    #: When the vehicle passed each waypoint (guidance moved past it; the last: ``done_s``).
    #: Waypoints guidance never visits (a hover's) are timed in proportion to the path's own.
    times: tuple[float, ...]
    #: When the pattern was done (:mod:`sim.completion`); None: not within the bound.
    done_s: float | None
    #: Horizontal distance flown (m).
    length_m: float
    #: Time lost slowing down in turns (s): the surge at ``cos^2`` of the heading error.
    turning_s: float
    #: Time from guidance finishing the path (holding) to the vehicle at its depth (s).
    depth_wait_s: float


def _planner_step_rate(plan: Plan) -> float:
    """The rate the path itself gives its in-place depth steps (m/s): a vehicle of unknown
    heave is timed as planned."""
    path = plan.path
    xs, ys, zs, ts = path.xs, path.ys, path.zs, path.times
    rate = 0.0
    for i in range(len(xs) - 1):
        dt = ts[i + 1] - ts[i]
        if dt > _EPS and math.hypot(xs[i + 1] - xs[i], ys[i + 1] - ys[i]) < 1e-6:
            rate = max(rate, abs(zs[i + 1] - zs[i]) / dt)
    return rate if rate > 0.0 else DEPTH_RATE_MPS


def fly(
    plan: Plan,
    rates: Rates,
    heading_deg: float | None = None,
    guidance: GuidanceConfig | None = None,
) -> Flight:
    """Fly ``plan`` from its first waypoint (the vehicle's position) facing ``heading_deg``
    (None: along the path's first leg) until it is done (see the module doc)."""
    path = plan.path
    g = Guidance(guidance)
    g.set_plan(plan, 0.0)
    done = Completion()
    v = _Vehicle(plan, rates, g.config.lookahead_m, heading_deg)
    reached: list[float | None] = [None] * len(path)
    reached[0] = 0.0
    last = 0
    finished_s: float | None = None
    limit = max(3600.0, MAX_STRETCH * path.duration_s)
    for _ in range(MAX_STEPS):
        ref = g.update(v.x, v.y, v.z, v.t)
        if done.update(g, v.t) is not None or v.t > limit:
            break
        if g.segment > last:
            for i in range(last + 1, g.segment + 1):
                reached[i] = v.t
            last = g.segment
        if finished_s is None and (g.at_end or g.mode is not Mode.RUNNING):
            finished_s = v.t
        v.step(g, ref)
    done_s = done.done_s
    wait = 0.0 if done_s is None or finished_s is None else max(0.0, done_s - finished_s)
    return Flight(_times(plan, reached, done_s), done_s, v.length, v.turning, wait)


class _Vehicle:
    """The kinematic vehicle: where it is, where it faces, what it has flown."""

    def __init__(
        self, plan: Plan, rates: Rates, lookahead_m: float, heading_deg: float | None
    ) -> None:
        path = plan.path
        self.plan = plan
        self.hover = plan.pattern == "hover"
        self.top = rates.top_speed_mps
        self.down = rates.descent_mps or _planner_step_rate(plan)
        self.up = rates.ascent_mps or self.down
        self.r_max = math.radians(rates.yaw_rate_dps)
        self.k = rates.heading_gain_per_s
        self.look = lookahead_m
        horizontal = sum(_horizontal_m(path, i) for i in range(len(path) - 1))
        self.step_m = min(lookahead_m, max(STEP_LOOKAHEADS * lookahead_m, horizontal / PATH_STEPS))
        self.max_step_s = max(MAX_STEP_S, path.duration_s / PATH_STEPS)
        self.x, self.y, self.z = path.xs[0], path.ys[0], path.zs[0]
        heading = heading_deg if heading_deg is not None else path.course_deg(0)
        self.psi = math.radians(heading)
        self.t = self.length = self.turning = 0.0
        #: Where the horizontal path ends (a repeating one: its lap's end, the last waypoint;
        #: a finite one: before the depth change left for the end, if any).
        self.end = len(path) - 1
        while path.loop_start is None and self.end > 0 and _level(path, self.end - 1):
            self.end -= 1

    def _to_end_m(self, i: int) -> float:
        """Distance (m) from the vehicle, along segment ``i``, to the segment's end."""
        path = self.plan.path
        ax, ay, bx, by = path.xs[i], path.ys[i], path.xs[i + 1], path.ys[i + 1]
        h = math.hypot(bx - ax, by - ay)
        if h <= 1e-6:
            return 0.0
        along = ((self.x - ax) * (bx - ax) + (self.y - ay) * (by - ay)) / h
        return max(0.0, h - along)

    def step(self, g: Guidance, ref: Reference) -> None:
        """One step towards guidance's reference ``ref``: as long as a quarter lookahead
        takes (longer along a straight leg it follows, or holding still)."""
        speed = ref.speed_mps if self.top is None else min(ref.speed_mps, self.top)
        running = g.mode is Mode.RUNNING and not g.at_end  # following the path (or hovering)
        target = ref.depth_m
        if speed > _EPS:
            dt = min(self.max_step_s, max(MIN_STEP_S, self.step_m / speed))
            dt = max(dt, self._straight_run_s(g, ref.course_rad, speed))
            if running and not self.hover:
                if g.segment + 1 >= self.end:  # no further than the path's (or the lap's) end
                    dt = min(dt, max(MIN_STEP_S, self._to_end_m(g.segment) / speed + 1e-3))
                # the reference moves on along the leg's ramp
                target = self._ramped(g.segment, target, speed * dt)
        gap = target - self.z
        rate = self.down if gap > 0 else self.up
        if speed <= _EPS:  # holding still: until the hover's time is up or the depth is reached
            left = self.plan.path.duration_s - self.t if self.hover and running else 0.0
            left = max(left, (abs(gap) - AT_DEPTH_M) / rate)
            dt = min(MAX_HOLD_STEP_S, max(MIN_STEP_S, left))
        err = wrap_rad(ref.course_rad - self.psi)
        err2 = _heading_error_after(err, dt, self.k, self.r_max)
        u = speed * (max(0.0, math.cos(err)) ** 2 + max(0.0, math.cos(err2)) ** 2) / 2
        mid = self.psi + wrap_rad(err - err2) / 2
        self.x += u * dt * math.cos(mid)
        self.y += u * dt * math.sin(mid)
        self.length += u * dt
        if speed > _EPS:
            self.turning += dt * (1.0 - u / speed)
        self.psi = ref.course_rad - err2
        if ref.vertical:
            self.z += max(-rate * dt, min(rate * dt, gap))
        self.t += dt

    def _ramped(self, i: int, depth: float, ahead_m: float) -> float:
        """Guidance's depth ``ahead_m`` further along segment ``i`` (its ramp), at most its
        end's."""
        path = self.plan.path
        xs, ys, zs = path.xs, path.ys, path.zs
        h = math.hypot(xs[i + 1] - xs[i], ys[i + 1] - ys[i])
        if h <= 1e-6:
            return depth
        end = zs[i + 1]
        ahead = depth + (end - zs[i]) / h * ahead_m
        return min(ahead, end) if end >= depth else max(ahead, end)

    def _straight_run_s(self, g: Guidance, course: float, speed: float) -> float:
        """A longer step along a straight leg the vehicle already follows (on it, facing along
        it), stopping a lookahead and two steps short of its end: 0 when there is none."""
        if g.cross_track_m > 0.05 or abs(wrap_rad(course - self.psi)) > 0.01:
            return 0.0
        path = self.plan.path
        i = g.segment
        if i + 1 >= len(path):
            return 0.0
        end = math.hypot(path.xs[i + 1] - self.x, path.ys[i + 1] - self.y)
        ahead = end - self.look - 2 * self.step_m
        return ahead / speed if ahead > 2 * self.step_m else 0.0


def _horizontal_m(path: Path, i: int) -> float:
    """Horizontal length of segment ``i`` (m)."""
    return math.hypot(path.xs[i + 1] - path.xs[i], path.ys[i + 1] - path.ys[i])


def _level(path: Path, i: int) -> bool:
    """Segment ``i`` has no horizontal extent (a depth change in place)."""
    return _horizontal_m(path, i) < 1e-6


def _heading_error_after(err: float, dt: float, k: float, r_max: float) -> float:
    """The heading error after ``dt`` of the autopilot's law ``r = k err``, limited to
    ``r_max`` (exact: a linear turn while saturated, then an exponential decay)."""
    a = abs(err)
    saturated_s = max(0.0, (a - r_max / k) / r_max) if k > 0 else math.inf
    if dt <= saturated_s:
        left = a - r_max * dt
    else:
        left = min(a, r_max / k) * math.exp(-k * (dt - saturated_s))
    return math.copysign(left, err)


def _times(plan: Plan, reached: list[float | None], done_s: float | None) -> tuple[float, ...]:
    """Every waypoint's time: as reached, the last at ``done_s``, the rest in proportion to the
    path's own times between their timed neighbours (after the last one timed: the path's own
    spacing)."""
    own = plan.path.times
    n = len(own)
    if done_s is not None and n > 1:
        reached[-1] = max(done_s, max((r for r in reached[:-1] if r is not None), default=0.0))
    out = list(own)
    anchors = [i for i, r in enumerate(reached) if r is not None]
    for a, b in pairwise(anchors):
        ta, tb = reached[a], reached[b]
        assert ta is not None and tb is not None
        span = own[b] - own[a]
        for i in range(a, b + 1):
            f = (own[i] - own[a]) / span if span > 0 else 1.0
            out[i] = ta + f * (tb - ta)
    last = anchors[-1]
    shift = (reached[last] or 0.0) - own[last]
    for i in range(last + 1, n):
        out[i] = own[i] + shift
    return tuple(out)
