"""A fleet survey's preview: one lawnmower area split into lane blocks, one per vehicle, each
block that vehicle's own lawnmower command from its entry, with the coverage, overlaps, gaps
and the time to finish (issue 23, item 6).

The steps: the area's values are checked against the lawnmower's scales, the vehicles against
the fleet's rules and the ME link's range; the lanes are split into blocks and assigned
(:mod:`backend.authoring.survey.assign`); each block becomes its vehicle's command, transit and
plans, timed and checked (:mod:`backend.authoring.survey.command`); the paths flown give the
coverage (:mod:`backend.authoring.survey.coverage`). Nothing is sent: each command goes later
through the normal send (``POST /api/commands``), one vehicle at a time.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from backend.authoring.survey.area import (
    SurveyArea,
    SurveyError,
    SurveyVehicle,
    area_lanes,
    check_area,
    check_vehicles,
    frame_of,
    lane_count,
)
from backend.authoring.survey.assign import assign
from backend.authoring.survey.command import SurveyChecks, VehicleSurvey, plan_vehicle
from backend.authoring.survey.coverage import Coverage, coverage
from backend.chart.reach import distances_m


@dataclass(frozen=True, slots=True)
class SurveyPreview:
    """The survey as it would be flown: the area's lanes (across offsets, m), each vehicle's
    share (in the request's order) and the coverage of their paths."""

    area: SurveyArea
    lanes_across_m: tuple[float, ...]
    vehicles: tuple[VehicleSurvey, ...]
    coverage: Coverage

    @property
    def time_to_finish_s(self) -> float:
        """The slowest vehicle's transit and lawnmower, as flown (s)."""
        return max(v.duration_s for v in self.vehicles)

    @property
    def slowest(self) -> str:
        return max(self.vehicles, key=lambda v: v.duration_s).vehicle.name


def preview_survey(
    area: SurveyArea, vehicles: Sequence[SurveyVehicle], checks: SurveyChecks
) -> SurveyPreview:
    """The survey of ``area`` by ``vehicles``, checked as every send is (``checks``).

    Raises:
        SurveyError: the area or a vehicle cannot be surveyed as given (naming the field and
            what is allowed).
    """
    sent = check_area(area)
    check_vehicles(vehicles, lane_count(area), area)
    check_reach(vehicles, checks)
    lanes = area_lanes(area)
    frame = frame_of(area)
    assignments = assign(vehicles, lanes, area, sent, frame)
    shares = tuple(
        plan_vehicle(v, i, a, area, lanes, checks)
        for i, (v, a) in enumerate(zip(vehicles, assignments, strict=True))
    )
    tracks = [(share.survey.path.xs, share.survey.path.ys) for share in shares]
    return SurveyPreview(area, lanes, shares, coverage(area, frame, tracks, area.lane_spacing_m))


def check_reach(vehicles: Sequence[SurveyVehicle], checks: SurveyChecks) -> None:
    """Every vehicle within the ME link's range of the transmitter (when both are known): a
    vehicle beyond it would not hear its command.

    Raises:
        SurveyError: naming the vehicle, its distance and the range.
    """
    station, range_m = checks.station, checks.range_m
    if station is None or range_m is None:
        return
    for i, v in enumerate(vehicles):
        distance = distances_m([v.x_m], [v.y_m], [v.z_m], station)
        if distance is None or float(distance[0]) <= range_m:
            continue
        raise SurveyError(
            f"vehicle {v.name} is {float(distance[0]):,.0f} m from the ME transmitter, beyond "
            f"the link's {range_m:,.0f} m range: it would not hear its command. Allowed: "
            f"within {range_m:,.0f} m of the transmitter (x_m {station.x_m:g}, "
            f"y_m {station.y_m:g})",
            ("vehicles", i, "x_m"),
        )
