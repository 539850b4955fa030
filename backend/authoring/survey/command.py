"""One vehicle's share of a survey: its block as its own lawnmower command, the path it flies,
the time it takes, and the same checks every send runs.

A lawnmower starts where the vehicle is when it takes effect, along its heading, with no
join (``docs/patterns.md``): the block's command therefore only surveys the block if it
takes effect at the block's entry (:class:`backend.authoring.survey.assign.Entry`). The
vehicle gets there first; that transit is the planner's join (:meth:`planner._build.Build.
join`: turn, straight, turn at the survey speed's turn radius, the depth ramped on the way),
and it counts in the vehicle's time. Both legs are timed by the one duration estimate
(:func:`backend.authoring.durations.flown`: the kinematic twin on the vehicle's profile).

The command is the codec's: the area's values snapped to the lawnmower's 8-bit scales
(:func:`codec.encode_frame`), and the plan is of the command as the vehicle decodes it. Where
a snap moves the block's lanes (a lane spacing or sweep length off the scale's steps, or an
odd block flown as whole pairs), the footprint says how far; the coverage is of the path
flown, not of the block asked for.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from backend.authoring.durations import estimate_notes, flown
from backend.authoring.profile import VehicleProfile
from backend.authoring.survey.area import SurveyArea, SurveyError, SurveyVehicle
from backend.authoring.survey.assign import Assignment
from backend.chart.gps import Station
from backend.commands.checks import CheckReport, check_plan
from codec import Command, Encoded, EncodeError, decode_frame, encode_frame
from planner import Estimate, Limits, Plan, PlanError, VehicleState, plan
from planner._build import Build

#: Lanes closer than this to where the block wants them have not moved (m).
SAME_M = 1e-6


@dataclass(frozen=True, slots=True)
class SurveyChecks:
    """What the send checks take besides the plan (:func:`backend.commands.checks.
    check_plan`): the console's limits, the vehicle profile, the ME transmitter and its range.
    The battery is checked as full: a fleet vehicle's charge is not known here."""

    limits: Limits
    profile: VehicleProfile | None
    station: Station | None
    range_m: float | None


@dataclass(frozen=True, slots=True)
class Footprint:
    """The block as its lawnmower flies it, in the area's frame (m), lanes in flight order:
    where they are (``lanes_across_m``) and where the block wants them (``block_across_m``,
    one fewer for an odd block, whose extra lane lies outside the area)."""

    along_start_m: float
    along_end_m: float
    lanes_across_m: tuple[float, ...]
    block_across_m: tuple[float, ...]
    sweep_length_m: float
    lane_spacing_m: float
    #: The sweep length the area asks for (m).
    area_length_m: float

    @property
    def exact(self) -> bool:
        """The lawnmower flies exactly the block's lanes over the area's length."""
        return (
            self.max_lane_shift_m < SAME_M
            and self.extra_lanes == 0
            and abs(self.sweep_length_m - self.area_length_m) < SAME_M
        )

    @property
    def max_lane_shift_m(self) -> float:
        """The largest distance (m) of a flown lane from the block lane it stands for."""
        pairs = zip(self.lanes_across_m, self.block_across_m, strict=False)
        return max((abs(a - b) for a, b in pairs), default=0.0)

    @property
    def extra_lanes(self) -> int:
        return len(self.lanes_across_m) - len(self.block_across_m)


@dataclass(frozen=True, slots=True)
class VehicleSurvey:
    """A vehicle's block, its command (requested and as sent), the transit to its entry and
    the lawnmower from there (plans and estimates), its footprint, its checks and notes."""

    vehicle: SurveyVehicle
    assignment: Assignment
    encoded: Encoded
    command: Command
    transit: Plan | None
    survey: Plan
    transit_estimate: Estimate | None
    survey_estimate: Estimate
    duration_notes: tuple[str, ...]
    footprint: Footprint
    report: CheckReport
    notes: tuple[str, ...]

    @property
    def transit_duration_s(self) -> float:
        return 0.0 if self.transit_estimate is None else self.transit_estimate.duration_s

    @property
    def transit_length_m(self) -> float:
        return 0.0 if self.transit_estimate is None else self.transit_estimate.length_m

    @property
    def duration_s(self) -> float:
        """The transit and the lawnmower, each as the vehicle flies it (s)."""
        return self.transit_duration_s + self.survey_estimate.duration_s


def requested_params(area: SurveyArea, laps: int) -> dict[str, float | int]:
    """The block's lawnmower as asked for: the area's values, the block's laps."""
    return {
        "speed": area.speed_mps,
        "depth": area.depth_m,
        "sweep_length": area.length_m,
        "lane_spacing": area.lane_spacing_m,
        "laps": laps,
    }


def plan_vehicle(
    vehicle: SurveyVehicle,
    index: int,
    assignment: Assignment,
    area: SurveyArea,
    lanes: Sequence[float],
    checks: SurveyChecks,
) -> VehicleSurvey:
    """The vehicle's block as its lawnmower, flown from its entry after the transit there.

    Raises:
        SurveyError: the planner cannot fly it (named at the vehicle ``index``).
    """
    block, entry = assignment.block, assignment.entry
    try:
        enc = encode_frame("lawnmower", requested_params(area, block.laps))
    except EncodeError as err:  # the area's values and the laps were checked before
        raise SurveyError(f"vehicle {vehicle.name}: {err}", ("vehicles", index)) from None
    cmd = decode_frame(enc.frame.bits).command  # what the vehicle will decode
    params = cmd.params
    speed, depth = float(params["speed"]), float(params["depth"])
    start = VehicleState(vehicle.x_m, vehicle.y_m, vehicle.z_m, vehicle.heading_deg % 360.0)
    try:
        transit = _transit(cmd, start, (entry.x_m, entry.y_m, entry.heading_deg), depth, speed)
        z_entry = vehicle.z_m if transit is None else transit.path.zs[-1]
        at_entry = VehicleState(entry.x_m, entry.y_m, z_entry, entry.heading_deg, speed)
        survey = plan(cmd, at_entry, None)
    except PlanError as err:
        raise SurveyError(f"vehicle {vehicle.name}: {err}", ("vehicles", index)) from None
    profile = checks.profile
    transit_est, transit_flight = (None, None) if transit is None else flown(transit, profile)
    survey_est, survey_flight = flown(survey, profile)
    report = check_plan(
        survey,
        limits=checks.limits,
        profile=checks.profile,
        soc_pct=None,
        station=checks.station,
        range_m=checks.range_m,
        estimate=survey_est,
    )
    footprint = footprint_of(survey, assignment, lanes, area.length_m)
    notes = _notes(enc, footprint, assignment, area)
    said = [f"lawnmower: {n}" for n in estimate_notes(survey, survey_est, survey_flight, profile)]
    if transit is not None and transit_est is not None and transit_flight is not None:
        said[:0] = [
            f"transit: {n}" for n in estimate_notes(transit, transit_est, transit_flight, profile)
        ]
    return VehicleSurvey(
        vehicle,
        assignment,
        enc,
        cmd,
        transit,
        survey,
        transit_est,
        survey_est,
        tuple(said),
        footprint,
        report,
        notes,
    )


def _transit(
    cmd: Command, start: VehicleState, entry: tuple[float, float, float], depth: float, speed: float
) -> Plan | None:
    """The planner's join from ``start`` to the entry pose ``(x, y, heading_deg)`` at
    ``speed``, ramping to ``depth``; None when the vehicle is there already."""
    x, y, heading = entry
    b = Build(start)
    body = b.join(start, (x, y, math.radians(heading)), depth, 0.0, speed)
    if body == 0:
        return None
    return Plan(cmd, b.finish(start, speed, body), (x, y), (x, y), heading, t0_s=0.0)


def footprint_of(
    survey: Plan, assignment: Assignment, lanes: Sequence[float], area_length_m: float
) -> Footprint:
    """Where the lawnmower's lanes lie in the area's frame, against the block's."""
    block, entry = assignment.block, assignment.entry
    params = survey.command.params
    length, spacing = float(params["sweep_length"]), float(params["lane_spacing"])
    sign = -1.0 if entry.from_end else 1.0
    flown_across = tuple(entry.across_m + sign * offset for offset in survey.lanes)
    wanted = (
        range(block.last_lane, block.first_lane - 1, -1)
        if entry.from_end
        else range(block.first_lane, block.last_lane + 1)
    )
    along = (
        (entry.along_m - length, entry.along_m)
        if entry.from_end
        else (entry.along_m, entry.along_m + length)
    )
    return Footprint(
        along[0],
        along[1],
        flown_across,
        tuple(lanes[i] for i in wanted),
        length,
        spacing,
        area_length_m,
    )


def _notes(
    enc: Encoded, footprint: Footprint, assignment: Assignment, area: SurveyArea
) -> tuple[str, ...]:
    """What the codec's steps and the lawnmower's pairs change, in words."""
    out: list[str] = []
    for snap in enc.snaps:
        if not snap.changed:
            continue
        if snap.field == "lane_spacing":
            out.append(
                f"{snap}: its lanes move up to {footprint.max_lane_shift_m:.2f} m across from "
                "the block's (centred on them)"
            )
        elif snap.field == "sweep_length":
            moved = (footprint.sweep_length_m - area.length_m) / 2.0
            where = "beyond" if moved > 0 else "short of"
            gap = "" if moved > 0 else " (strips not surveyed)"
            out.append(
                f"{snap}: its lanes end {abs(moved):.2f} m {where} the area's edges at both "
                f"ends{gap}"
            )
        else:
            out.append(str(snap))
    if footprint.extra_lanes:
        block = assignment.block
        extra = footprint.lanes_across_m[-1]
        out.append(
            f"its block has {block.lane_count} lanes; a lawnmower flies out-and-back pairs, so it "
            f"flies {2 * block.laps}: the last, {extra:.2f} m across, lies outside the area "
            f"(0 to {area.width_m:g} m across)"
        )
    return tuple(out)
