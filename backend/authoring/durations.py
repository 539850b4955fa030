"""One duration story (issue 20): the estimate as the vehicle flies the plan, and in words why
the plan's own clock, the estimate and the prediction differ where they do.

The estimate's durations come from the kinematic twin (:func:`sim.kinematic.fly`): the
onboard guidance flying the plan on a vehicle reduced to its profile (top speed, heave and
ascent rates, the autopilot's yaw-rate limit), done by the same rule as the prediction's full
twin (:mod:`sim.completion`). So for every pattern at in-profile speeds the estimate and the
prediction agree to a few per cent (``bench/durations.py``); the plan's clock (the planner's,
shared with the vehicle) does not change, and where it is more than :data:`DIFFER` away from
the estimate, or the prediction from the estimate, the notes say why, in the operator's words.
"""

from __future__ import annotations

import math
from typing import Final

from backend.authoring.profile import VehicleProfile
from onboard.guidance import GuidanceConfig
from planner import DEPTH_RATE_MPS, YAW_RATE_DPS, Estimate, Plan
from planner import estimate as plan_estimate
from sim.kinematic import Flight, Rates, fly

#: Durations further apart than this (a fraction) get a reason in words.
DIFFER: Final = 0.20
#: A cause is named when it accounts for at least this share of the planned duration.
_CAUSE: Final = 0.05
#: Water slower than this (m/s) is still water.
_STILL_MPS: Final = 0.005


def rates_of(profile: VehicleProfile | None) -> Rates:
    """The kinematic vehicle of ``profile`` (None: unknown, flown as planned)."""
    if profile is None:
        return Rates()
    yaw = YAW_RATE_DPS if profile.yaw_rate_dps is None else min(YAW_RATE_DPS, profile.yaw_rate_dps)
    return Rates(
        top_speed_mps=profile.top_speed_mps,
        descent_mps=profile.heave_rate_mps,
        ascent_mps=profile.ascent_rate_mps,
        yaw_rate_dps=yaw,
    )


def flown(plan: Plan, profile: VehicleProfile | None) -> tuple[Estimate, Flight]:
    """The estimate of ``plan`` as the vehicle of ``profile`` flies it, and the flight.

    A flight the model cannot finish (beyond its bound) falls back to the planner's own
    stretched times (:func:`planner.estimate` at the top speed and heave rate)."""
    flight = fly(plan, rates_of(profile))
    top = profile.top_speed_mps if profile is not None else None
    heave = profile.heave_rate_mps if profile is not None else None
    times = flight.times if flight.done_s is not None else None
    return plan_estimate(plan, top, heave, times), flight


def _apart(a: float, b: float) -> bool:
    """``a`` and ``b`` (s) differ by more than :data:`DIFFER` of the smaller."""
    return abs(a - b) > DIFFER * max(min(a, b), 1e-9)


def estimate_notes(
    plan: Plan, est: Estimate, flight: Flight, profile: VehicleProfile | None
) -> list[str]:
    """Why the estimate is more than :data:`DIFFER` away from the plan's own duration (its
    ``planned_duration_s``): the causes that account for a visible share, largest first;
    empty when they agree. A flight the model could not finish says so instead."""
    planned, estimated = est.planned_duration_s, est.duration_s
    if flight.done_s is None:  # the estimate fell back to the plan's clock (see flown)
        return [
            "guidance on the vehicle's profile does not finish this path (its turns may be too "
            "tight for the speed): the estimate is the plan's clock at the vehicle's top speed"
        ]
    if not _apart(planned, estimated):
        return []
    path = plan.path
    causes: list[tuple[float, str]] = []
    speed, top = est.planned_speed_mps, profile.top_speed_mps if profile is not None else None
    horizontal = _horizontal_m(plan)
    if speed is not None and top is not None and speed > top:
        share = horizontal / top - horizontal / speed
        causes.append(
            (share, f"the vehicle cannot hold {speed:g} m/s: its top speed is {top:.2f} m/s")
        )
    end = _end_of_horizontal(plan)
    dz = path.zs[-1] - path.zs[end]
    planned_wait = path.times[-1] - path.times[end]
    if abs(dz) > 1e-3 and plan.pattern != "hover":
        rate = _rate(profile, dz)
        way = "down" if dz > 0 else "up"
        pace = f"at {rate:.3f} m/s" if rate is not None else "at the planner's rate"
        causes.append(
            (
                abs(flight.depth_wait_s - planned_wait),
                f"the last {abs(dz):.1f} m {way} are flown in place at the end, {pace} "
                f"({flight.depth_wait_s:.0f} s; the plan's {DEPTH_RATE_MPS:g} m/s ramp: "
                f"{planned_wait:.0f} s)",
            )
        )
    if horizontal > 0 and flight.length_m < horizontal:
        look = GuidanceConfig().lookahead_m
        cruise = est.flyable_speed_mps or speed or 1.0
        causes.append(
            (
                (horizontal - flight.length_m) / cruise,
                f"guidance cuts corners and tight turns (it steers {look:g} m ahead): "
                f"{flight.length_m:.0f} m flown of the path's {horizontal:.0f} m",
            )
        )
    if flight.turning_s > 0:
        yaw = rates_of(profile).yaw_rate_dps
        causes.append(
            (
                flight.turning_s,
                f"it slows down in its turns (at most {yaw:g} deg/s): {flight.turning_s:.0f} s",
            )
        )
    named = [text for share, text in sorted(causes, reverse=True) if share >= _CAUSE * planned]
    if named:
        return named
    return [
        f"the vehicle's motion (guidance on its profile) takes {estimated:.0f} s where the "
        f"plan's clock says {planned:.0f} s"
    ]


def prediction_notes(
    predicted_s: float | None, estimate_s: float, current_mps: tuple[float, float]
) -> list[str]:
    """Why the prediction (the full twin's run) is more than :data:`DIFFER` away from the
    estimate; empty when they agree or there is no predicted duration."""
    if predicted_s is None or not _apart(predicted_s, estimate_s):
        return []
    north, east = current_mps
    speed = math.hypot(north, east)
    if speed >= _STILL_MPS:
        towards = math.degrees(math.atan2(east, north)) % 360.0
        return [
            f"the water current ({speed:.2f} m/s towards {towards:03.0f} deg) carries the "
            "vehicle: the estimate is for still water"
        ]
    return [
        f"the twin's run ({predicted_s:.0f} s: its accelerations, depth transients and start) "
        f"differs from the estimate's motion model ({estimate_s:.0f} s)"
    ]


def _rate(profile: VehicleProfile | None, dz: float) -> float | None:
    if profile is None or profile.heave_rate_mps is None:
        return None
    if dz < 0 and profile.ascent_rate_mps is not None:
        return profile.ascent_rate_mps
    return profile.heave_rate_mps


def _end_of_horizontal(plan: Plan) -> int:
    """Index of the waypoint where the path's horizontal travel ends (its in-place depth
    change, if any, follows)."""
    path = plan.path
    i = len(path) - 1
    while i > 0 and math.hypot(path.xs[i] - path.xs[i - 1], path.ys[i] - path.ys[i - 1]) < 1e-6:
        i -= 1
    return i


def _horizontal_m(plan: Plan) -> float:
    xs, ys = plan.path.xs, plan.path.ys
    return sum(math.hypot(xs[i + 1] - xs[i], ys[i + 1] - ys[i]) for i in range(len(xs) - 1))
