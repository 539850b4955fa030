"""The checks of a plan before it is sent: one report for every path that shows or sends it.

:func:`check_plan` runs every check the console knows on a plan (the command as the vehicle
will decode it, planned from where the vehicle is now) and returns a :class:`CheckReport`:
one :class:`CheckLine` per check (ran and passed, violated, or skipped with the reason) and
one :class:`SendViolation` per broken rule. The preview shows it, the confirm dialog lists it,
and the command service refuses or asks for an override from it: one source.

The checks, in the report's order:

* ``depth_rating``: a depth beyond the hull's 100 m rating. **Hard**: refused on every path,
  no override;
* ``depth_limit``, ``speed_limit``: the console's configured maxima (soft);
* ``turn_radius``: a circle or helix tighter than the vehicle turns at its speed (soft; only
  for those patterns);
* ``top_speed``: faster than the vehicle profile's top speed (soft: it flies at top speed);
* ``endurance``: the path's duration at the flyable speed beyond the time the battery has
  left at its state of charge now, by the profile's battery fit (soft). For a repeating
  pattern the duration is the join and one lap: the first lap is never finished otherwise;
* ``geofence``: the path leaving the geofence (soft);
* ``reach``: the path going farther from the ME transmitter than the link's range (soft:
  the next retask could not reach the vehicle there);
* ``onboard_limit``: only when :func:`planner.validate` reports a violation none of the
  checks above names (a limit added to the planner later): never dropped unnamed.

Surface is never held back for the battery or the link's reach: it is what an empty battery
or a vehicle out of range calls for, and its path only rises from where the vehicle is.

Soft means the operator may send it with an explicit override; hard, never. Pure: no I/O, no
clock; the caller gives the vehicle's profile, its state of charge and the transmitter. The
report's types are :mod:`backend.commands.report` (importable from here too).
"""

from __future__ import annotations

from typing import Final

from backend.authoring.durations import flown
from backend.authoring.profile import UNKNOWN, VehicleProfile, endurance_left_s
from backend.chart.gps import Station
from backend.chart.reach import distances_m, out_of_range_message
from backend.commands.report import (
    CheckLine,
    CheckName,
    CheckReport,
    CheckStatus,
    SendViolation,
    ViolationKind,
)
from planner import RATED_DEPTH_M, Estimate, Limits, Plan, Violation, turn_radius_m, validate
from planner._checks import top_speed
from planner._fence import EXTENT_PARAMS, fence_violations

__all__ = [
    "CheckLine",
    "CheckName",
    "CheckReport",
    "CheckStatus",
    "SendViolation",
    "ViolationKind",
    "check_plan",
    "plan_limits",
]

_DEPTH_PARAMS: Final = ("depth", "start_depth", "end_depth")
#: Patterns whose radius the vehicle must be able to turn (the planner's ``_ROUND_PARAMS``).
_ROUND_PATTERNS: Final = frozenset({"circle", "helix"})
#: Never held back for the battery or the reach (see the module doc).
_EXEMPT_PATTERN: Final = "surface"

_Result = tuple[CheckLine, tuple[SendViolation, ...]]


def check_plan(
    plan: Plan,
    *,
    limits: Limits,
    profile: VehicleProfile | None,
    soc_pct: float | None,
    station: Station | None,
    range_m: float | None,
    estimate: Estimate | None = None,
) -> CheckReport:
    """Every check of ``plan`` (see the module doc).

    Args:
        plan: the command as the vehicle decodes it, planned from the vehicle's state now.
        limits: the console's maxima and geofence.
        profile: what the vehicle can do; None: unknown (top speed and endurance skipped).
        soc_pct: the battery's state of charge now (%); None: unknown (checked against a
            full battery, saying so).
        station: the ME transmitter; None or not placed in NED: the reach is skipped.
        range_m: the ME link's range (m); None: the reach is skipped.
        estimate: the plan's estimate as the vehicle of ``profile`` flies it
            (:func:`backend.authoring.durations.flown`), when the caller has it.
    """
    est = estimate if estimate is not None else flown(plan, profile)[0]
    # the geofence apart (its own check, named), the rest of the onboard limits at once
    found = plan_limits(plan, limits)
    results: list[_Result] = [
        _depth_rating(plan, found),
        _depth_limit(plan, limits, found),
        _speed_limit(plan, limits, found),
    ]
    if plan.pattern in _ROUND_PATTERNS:
        results.append(_turn_radius(plan, found))
    speed_refused = any(v.param == "speed" for v in found)
    results += [
        _top_speed(plan, profile, est, speed_refused),
        _endurance(plan, profile, soc_pct, est),
        _geofence(plan, limits),
        _reach(plan, station, range_m),
    ]
    claimed = {*_DEPTH_PARAMS, "speed"} | ({"radius"} if plan.pattern in _ROUND_PATTERNS else set())
    other = tuple(
        _violation(v, "onboard_limit", "within the vehicle's limits")
        for v in found
        if v.param not in claimed
    )
    if other:
        detail = "; ".join(v.message for v in other)
        results.append((CheckLine("onboard_limit", "violated", detail), other))
    return CheckReport(
        tuple(line for line, _ in results), tuple(v for _, vs in results for v in vs)
    )


def plan_limits(plan: Plan, limits: Limits) -> tuple[Violation, ...]:
    """The onboard limits' violations (:func:`planner.validate`) but the geofence's."""
    return validate(plan, Limits(limits.max_depth_m, limits.max_speed_mps))


def _violation(v: Violation, check: CheckName, allowed: str) -> SendViolation:
    kind: ViolationKind = "soft" if v.overridable else "hard"
    return SendViolation(check, v.param, kind, v.message, v.value, v.limit, v.unit, allowed)


def _depths(plan: Plan) -> dict[str, float]:
    params = plan.command.params
    return {
        name: float(value)
        for name in _DEPTH_PARAMS
        if isinstance(value := params.get(name), int | float)
    }


def _speed(plan: Plan) -> float | None:
    speed = plan.command.params.get("speed")
    return float(speed) if isinstance(speed, int | float) else None


def _depth_rating(plan: Plan, found: tuple[Violation, ...]) -> _Result:
    bad = tuple(
        _violation(v, "depth_rating", f"0 to {RATED_DEPTH_M:g} m")
        for v in found
        if v.param in _DEPTH_PARAMS and not v.overridable
    )
    if bad:
        return CheckLine("depth_rating", "violated", "; ".join(v.message for v in bad)), bad
    depths = _depths(plan)
    if not depths:
        return CheckLine("depth_rating", "ok", "the command sets no depth"), ()
    deepest = max(depths.values())
    detail = f"deepest {deepest:g} m, within the vehicle's {RATED_DEPTH_M:g} m rating"
    return CheckLine("depth_rating", "ok", detail), ()


def _depth_limit(plan: Plan, limits: Limits, found: tuple[Violation, ...]) -> _Result:
    limit = limits.max_depth_m
    bad = tuple(
        _violation(v, "depth_limit", f"0 to {limit:g} m")
        for v in found
        if v.param in _DEPTH_PARAMS and v.overridable
    )
    depths = _depths(plan)
    over = {name: d for name, d in depths.items() if d > limit}
    if over:  # beyond the rating too: that check's hard violation stands for it
        detail = "; ".join(
            f"{name} {d:g} m is deeper than the maximum depth {limit:g} m"
            + (" (and the rating)" if d > RATED_DEPTH_M else "")
            for name, d in over.items()
        )
        return CheckLine("depth_limit", "violated", detail), bad
    if not depths:
        return CheckLine("depth_limit", "ok", "the command sets no depth"), ()
    detail = f"deepest {max(depths.values()):g} m, within the maximum depth {limit:g} m"
    return CheckLine("depth_limit", "ok", detail), ()


def _speed_limit(plan: Plan, limits: Limits, found: tuple[Violation, ...]) -> _Result:
    limit = limits.max_speed_mps
    allowed = f"0 to {limit:g} m/s"
    bad = tuple(_violation(v, "speed_limit", allowed) for v in found if v.param == "speed")
    if bad:
        return CheckLine("speed_limit", "violated", bad[0].message), bad
    speed = _speed(plan)
    if speed is None:
        return CheckLine("speed_limit", "ok", "the command sets no speed"), ()
    detail = f"speed {speed:g} m/s, within the maximum speed {limit:g} m/s"
    return CheckLine("speed_limit", "ok", detail), ()


def _turn_radius(plan: Plan, found: tuple[Violation, ...]) -> _Result:
    speed = _speed(plan)
    radius = plan.command.params.get("radius")
    if speed is None or not isinstance(radius, int | float):
        return CheckLine("turn_radius", "skipped", "the command sets no speed or radius"), ()
    tight = turn_radius_m(speed)
    allowed = f"at least {tight:.2f} m at {speed:g} m/s"
    bad = tuple(_violation(v, "turn_radius", allowed) for v in found if v.param == "radius")
    if bad:
        return CheckLine("turn_radius", "violated", bad[0].message), bad
    detail = f"radius {radius:g} m, wider than the {tight:.2f} m the vehicle turns at {speed:g} m/s"
    return CheckLine("turn_radius", "ok", detail), ()


def _top_speed(
    plan: Plan, profile: VehicleProfile | None, est: Estimate, speed_refused: bool
) -> _Result:
    if profile is None:
        return CheckLine("top_speed", "skipped", "no vehicle profile"), ()
    top = profile.top_speed_mps
    if top is None:
        return CheckLine("top_speed", "skipped", UNKNOWN["top_speed_mps"]), ()
    if speed_refused:
        # above the maximum speed the vehicle refuses the command onboard, so it would not
        # fly it at top speed either: the maximum's violation says enough
        detail = "the speed is beyond the maximum speed, which the vehicle refuses onboard"
        return CheckLine("top_speed", "skipped", detail), ()
    v = top_speed(plan, top, est)
    if v is not None:
        bad = (_violation(v, "top_speed", f"0 to {round(top, 2):g} m/s"),)
        return CheckLine("top_speed", "violated", v.message), bad
    speed = est.planned_speed_mps
    if speed is None:
        return CheckLine("top_speed", "ok", "the plan does not move horizontally"), ()
    detail = f"speed {round(speed, 3):g} m/s, within the vehicle's {round(top, 2):g} m/s top speed"
    return CheckLine("top_speed", "ok", detail), ()


def _endurance(
    plan: Plan, profile: VehicleProfile | None, soc_pct: float | None, est: Estimate
) -> _Result:
    if plan.pattern == _EXEMPT_PATTERN:
        detail = "surfacing is never held back for the battery"
        return CheckLine("endurance", "skipped", detail), ()
    if profile is None:
        return CheckLine("endurance", "skipped", "no vehicle profile"), ()
    if profile.endurance_s is None:
        return CheckLine("endurance", "skipped", UNKNOWN["endurance_s"]), ()
    left = endurance_left_s(profile.endurance_s, soc_pct)
    takes = (
        f"the join and one lap take {est.duration_s:,.0f} s"
        if est.repeats
        else f"the path takes {est.duration_s:,.0f} s"
    )
    battery = (
        f"the {left:,.0f} s a full battery lasts (the charge now is unknown)"
        if soc_pct is None
        else f"the {left:,.0f} s the battery has left at {round(soc_pct, 1):g} %"
    )
    if est.duration_s <= left:
        return CheckLine("endurance", "ok", f"{takes}, within {battery}"), ()
    message = f"{takes}, beyond {battery}"
    violation = SendViolation(
        "endurance",
        _extent_param(plan, "duration"),
        "soft",
        message,
        est.duration_s,
        left,
        "s",
        f"up to {left:,.0f} s",
    )
    return CheckLine("endurance", "violated", message), (violation,)


def _geofence(plan: Plan, limits: Limits) -> _Result:
    fence = limits.geofence
    if fence is None:
        return CheckLine("geofence", "skipped", "no geofence set"), ()
    allowed = f"inside the {fence.describe()}"
    bad = tuple(_violation(v, "geofence", allowed) for v in fence_violations(plan, fence))
    if bad:
        return CheckLine("geofence", "violated", bad[0].message), bad
    return CheckLine("geofence", "ok", f"the path stays {allowed}"), ()


def _reach(plan: Plan, station: Station | None, range_m: float | None) -> _Result:
    if plan.pattern == _EXEMPT_PATTERN:
        detail = "surfacing is never held back for the link's reach"
        return CheckLine("reach", "skipped", detail), ()
    if station is None or range_m is None:
        return CheckLine("reach", "skipped", "the transmitter or its range is unknown"), ()
    path = plan.path
    distance = distances_m(path.xs, path.ys, path.zs, station)
    if distance is None:
        detail = (
            "the transmitter is not placed: its lat/lon is known but there is no datum"
            if station.x_m is None or station.y_m is None
            else "a waypoint is too far from the transmitter to measure"
        )
        return CheckLine("reach", "skipped", detail), ()
    farthest = float(distance.max()) if distance.size else 0.0
    if farthest <= range_m:  # exactly at the range is in range, as the channel has it
        detail = (
            f"the path stays within {farthest:,.0f} m of the transmitter (range {range_m:,.0f} m)"
        )
        return CheckLine("reach", "ok", detail), ()
    message = out_of_range_message(farthest, range_m)
    violation = SendViolation(
        "reach",
        _extent_param(plan, "position"),
        "soft",
        message,
        farthest,
        range_m,
        "m",
        f"within {range_m:,.0f} m of the transmitter",
    )
    return CheckLine("reach", "violated", message), (violation,)


def _extent_param(plan: Plan, first: str) -> str:
    """The parameter to change for a path too long or too far: ``first`` when the command
    has it (a straight's duration), else the first that sets the pattern's extent (a
    circle's radius), else ``first``."""
    params = plan.command.params
    if first in params:
        return first
    names = EXTENT_PARAMS.get(plan.pattern, ())
    return names[0] if names else first
