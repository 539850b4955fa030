"""Mission scripts, timed: each step's durations as the vehicle flies its plan, the one
duration story of issue 20.

A step's plan carries its own clock (``path.times``: the planner's, at the commanded speed,
depth ramped at 0.05 m/s), which the vehicle does not keep: a straight at 0.18 m/s from 12.34
to 12.5 m is 210 s by its plan and done at about 160 s. The script is timed as the preview's
estimate is (:func:`backend.authoring.durations.flown`: the onboard guidance flying the plan on
a vehicle reduced to its profile, done by the rule of :mod:`sim.completion`), so the
timeline, the onboard export and the run agree with the estimate, the prediction and the
vehicle's own report.

:class:`StepTiming` keeps when the vehicle is estimated to pass each waypoint, and maps times
between the two clocks: where the estimate has the vehicle at a time (the plan's path sampled
at the matching plan time), and when the estimate has it at a point of the plan. Those
durations are *estimated*; an ``at`` trigger's time is as set.

The caller passes a :data:`Timing` (a step's plan -> its timing): :func:`flown_timing` of the
console's vehicle profile, so this package needs no console.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Callable
from dataclasses import dataclass

from backend.authoring.durations import estimate_notes, flown
from backend.authoring.profile import VehicleProfile
from planner import Plan

#: How every estimated duration of a script is worked out, in words (the preview says it).
ESTIMATED_TEXT = (
    "durations, and the times that follow from them, are estimated: each step's plan flown "
    "by the onboard guidance on the vehicle's profile (top speed, heave and ascent rates, turn "
    "rate), done when it holds the end at its depth; 'at' times are as set"
)


@dataclass(frozen=True, slots=True)
class StepTiming:
    """When the vehicle is estimated to fly a step's plan (s after the step takes effect).

    Attributes:
        times: when it passes each waypoint of the plan (the last: when it is done; a
            repeating plan: the join and one lap).
        plan_times: the plan's own times of the same waypoints (its clock).
        loop_start: the plan's lap start (``None``: finite).
        notes: why the estimate differs from the plan's own clock, in words (empty when they
            agree within :data:`backend.authoring.durations.DIFFER`).
    """

    times: tuple[float, ...]
    plan_times: tuple[float, ...]
    loop_start: int | None
    notes: tuple[str, ...] = ()

    @property
    def duration_s(self) -> float:
        """The estimated duration: join and pattern (one lap for a repeating plan)."""
        return self.times[-1]

    @property
    def planned_duration_s(self) -> float:
        """The plan's own duration (its clock)."""
        return self.plan_times[-1]

    @property
    def completion_s(self) -> float | None:
        """When the step is estimated complete; ``None``: it repeats until retasked."""
        return None if self.loop_start is not None else self.times[-1]

    @property
    def planned_completion_s(self) -> float | None:
        """When the plan's clock has it complete; ``None``: it repeats."""
        return None if self.loop_start is not None else self.plan_times[-1]

    def to_plan_s(self, t_s: float) -> float:
        """The plan's time where the estimate has the vehicle ``t_s`` after the step took
        effect: past a finite plan's end, its end; past a repeating one's, laps on (the
        path's sampling wraps them)."""
        return _map(self.times, self.plan_times, self.loop_start, t_s)

    def from_plan_s(self, t_plan_s: float) -> float:
        """The inverse: when the estimate has the vehicle at the plan's time ``t_plan_s``."""
        return _map(self.plan_times, self.times, self.loop_start, t_plan_s)


#: A step's plan -> when the vehicle flies it.
Timing = Callable[[Plan], StepTiming]


def flown_timing(profile: VehicleProfile | None) -> Timing:
    """The timing of the vehicle of ``profile`` (None: unknown figures, flown at the plan's
    speeds and rates): :func:`backend.authoring.durations.flown`, once per plan."""
    known: dict[int, tuple[Plan, StepTiming]] = {}

    def timing(plan: Plan) -> StepTiming:
        hit = known.get(id(plan))
        if hit is not None and hit[0] is plan:
            return hit[1]
        est, flight = flown(plan, profile)
        own = plan.path.times
        if flight.done_s is not None:
            times = flight.times
        else:  # the model gave up: the planner's stretched duration, spread as the plan's
            scale = est.duration_s / own[-1] if own[-1] > 0 else 1.0
            times = tuple(t * scale for t in own)
        notes = tuple(estimate_notes(plan, est, flight, profile))
        out = StepTiming(_monotonic(times), tuple(own), plan.path.loop_start, notes)
        known[id(plan)] = (plan, out)
        return out

    return timing


def _monotonic(times: tuple[float, ...]) -> tuple[float, ...]:
    out: list[float] = []
    for t in times:
        out.append(max(t, out[-1]) if out else t)
    return tuple(out)


def _map(src: tuple[float, ...], dst: tuple[float, ...], loop: int | None, t: float) -> float:
    """``t`` on the ``src`` clock to the ``dst`` clock, linear between waypoints; a lap past
    the end of a repeating path (``loop``) maps lap for lap."""
    if t <= src[0]:
        return dst[0]
    if t >= src[-1]:
        if loop is None:
            return dst[-1]
        lap_src, lap_dst = src[-1] - src[loop], dst[-1] - dst[loop]
        if lap_src <= 0.0:
            return dst[-1]
        laps = math.floor((t - src[loop]) / lap_src)
        inside = t - laps * lap_src
        return _map(src, dst, None, inside) + laps * lap_dst
    k = min(bisect_right(src, t) - 1, len(src) - 2)
    span = src[k + 1] - src[k]
    f = (t - src[k]) / span if span > 0 else 1.0
    return dst[k] + f * (dst[k + 1] - dst[k])
