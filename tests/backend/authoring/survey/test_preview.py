"""A fleet survey's preview (issue 23, item 6): the split covers the area, each block is its
vehicle's own lawnmower as the codec sends it and the planner flies it, quantisation moves
the footprint and the coverage follows it, and the time to finish is the one duration
estimate's."""

from __future__ import annotations

import math
from dataclasses import replace
from itertools import pairwise

import pytest

from backend.authoring.durations import flown
from backend.authoring.profile import twin_profile
from backend.authoring.survey import (
    SurveyArea,
    SurveyChecks,
    SurveyPreview,
    SurveyVehicle,
    preview_survey,
)
from backend.authoring.survey.area import frame_of
from backend.authoring.survey.coverage import coverage
from backend.chart.gps import Station
from codec import decode_frame
from planner import Limits, VehicleState, plan

TWIN = twin_profile(100.0)
#: The send checks as the training console has them: the transmitter at the NED origin.
CHECKS = SurveyChecks(
    Limits(max_depth_m=100.0, max_speed_mps=1.0),
    TWIN,
    Station(None, None, 0.0, 0.0, "datum"),
    730.0,
)
#: 200 m lanes over 120 m at 10 m: 12 lanes, 4 a vehicle; in the twin's speed range.
AREA = SurveyArea(
    origin_x_m=20.0,
    origin_y_m=-40.0,
    heading_deg=30.0,
    width_m=120.0,
    length_m=200.0,
    lane_spacing_m=10.0,
    depth_m=5.0,
    speed_mps=0.18,
)
FLEET = (
    SurveyVehicle("auv1", 0.0, 0.0, 0.0),
    SurveyVehicle("auv2", -30.0, 60.0, 90.0),
    SurveyVehicle("auv3", 250.0, 150.0, 200.0, z_m=2.0),
)


def survey(area: SurveyArea = AREA, vehicles: tuple[SurveyVehicle, ...] = FLEET) -> SurveyPreview:
    return preview_survey(area, vehicles, CHECKS)


def test_three_vehicles_cover_the_area_with_small_overlaps() -> None:
    p = survey()
    cov = p.coverage
    assert cov.area_m2 == pytest.approx(200.0 * 120.0)
    assert cov.covered_fraction >= 0.95
    assert cov.overlap_fraction <= 0.02
    assert cov.covered_m2 + cov.gap_m2 == pytest.approx(cov.area_m2)
    # an exact split: every block flown as asked, lanes touching edge to edge
    assert all(v.footprint.exact for v in p.vehicles)
    assert cov.gap_m2 == 0.0 and cov.overlap_m2 == 0.0
    # each vehicle surveys a third of it
    assert cov.vehicle_m2 == pytest.approx((8000.0, 8000.0, 8000.0))


def test_the_blocks_are_the_area_lanes_each_once() -> None:
    p = survey()
    assert len(p.lanes_across_m) == 12
    assert p.lanes_across_m[0] == pytest.approx(5.0) and p.lanes_across_m[-1] == pytest.approx(115)
    lanes = sorted(
        i
        for v in p.vehicles
        for i in range(v.assignment.block.first_lane, v.assignment.block.last_lane + 1)
    )
    assert lanes == list(range(12))
    assert sorted(v.assignment.block.index for v in p.vehicles) == [0, 1, 2]
    for v in p.vehicles:  # the lanes flown are the block's, in the area's frame
        assert sorted(v.footprint.lanes_across_m) == pytest.approx(
            [
                p.lanes_across_m[i]
                for i in range(v.assignment.block.first_lane, v.assignment.block.last_lane + 1)
            ]
        )


def test_each_command_decodes_to_its_params_and_flies_its_block() -> None:
    p = survey()
    frame = frame_of(AREA)
    for v in p.vehicles:
        decoded = decode_frame(v.encoded.frame.hex).command
        assert decoded.pattern.name == "lawnmower"
        assert decoded.params == v.command.params
        assert decoded.params["laps"] == v.assignment.block.laps == 2
        assert decoded.params["sweep_length"] == 200.0 and decoded.params["lane_spacing"] == 10.0
        # the path the coverage uses is the planner's, for the decoded command, from the entry
        e = v.assignment.entry
        z = v.transit.path.zs[-1] if v.transit is not None else v.vehicle.z_m
        again = plan(decoded, VehicleState(e.x_m, e.y_m, z, e.heading_deg, 0.18), None)
        assert again.path.xs == pytest.approx(v.survey.path.xs)
        assert again.path.ys == pytest.approx(v.survey.path.ys)
        # the entry is the block's corner, heading along (or back along) the lanes
        along, across = frame.to_local(e.x_m, e.y_m)
        assert along == pytest.approx(200.0 if e.from_end else 0.0, abs=1e-9)
        first = v.assignment.block.last_lane if e.from_end else v.assignment.block.first_lane
        assert across == pytest.approx(p.lanes_across_m[first])
        assert (e.heading_deg - AREA.heading_deg) % 360 == pytest.approx(180 if e.from_end else 0)
        # the transit starts where the vehicle is and ends at the entry
        assert v.transit is not None
        assert (v.transit.path.xs[0], v.transit.path.ys[0]) == (v.vehicle.x_m, v.vehicle.y_m)
        assert v.transit.path.xs[-1] == pytest.approx(e.x_m)
        assert v.transit.path.ys[-1] == pytest.approx(e.y_m)
        # checked as every send is: every check's line, none violated at in-profile speed
        assert [line.check for line in v.report.lines][:3] == [
            "depth_rating",
            "depth_limit",
            "speed_limit",
        ]
        assert v.report.violations == ()


def test_time_to_finish_is_the_slowest_of_the_one_duration_estimate() -> None:
    p = survey()
    totals = {}
    for v in p.vehicles:
        assert v.transit is not None
        transit = flown(v.transit, TWIN)[0].duration_s
        decoded = decode_frame(v.encoded.frame.bits).command
        e = v.assignment.entry
        lawnmower = plan(decoded, VehicleState(e.x_m, e.y_m, 5.0, e.heading_deg, 0.18), None)
        totals[v.vehicle.name] = transit + flown(lawnmower, TWIN)[0].duration_s
        assert v.duration_s == pytest.approx(totals[v.vehicle.name])
        # about the lanes' length at the survey speed (4 lanes of 200 m, 3 turns of 10 m)
        assert v.survey_estimate.duration_s == pytest.approx((800 + 30) / 0.18, rel=0.1)
    assert p.time_to_finish_s == pytest.approx(max(totals.values()))
    assert p.slowest == max(totals, key=lambda name: totals[name])
    # the far vehicle's transit makes it the slowest
    assert p.slowest == "auv3"


def test_blocks_go_to_the_nearest_vehicles() -> None:
    """Each vehicle waiting at a block's corner gets that block: no transit to speak of."""
    frame = frame_of(AREA)
    at = [frame.to_ned(0.0, across) for across in (5.0, 45.0, 85.0)]
    vehicles = tuple(
        SurveyVehicle(name, x, y, AREA.heading_deg)
        for name, (x, y) in zip(("c", "a", "b"), (at[2], at[0], at[1]), strict=True)
    )
    p = survey(vehicles=vehicles)
    assert [v.assignment.block.index for v in p.vehicles] == [2, 0, 1]
    for v in p.vehicles:
        assert v.transit is None and v.transit_duration_s == 0.0
        assert v.duration_s == v.survey_estimate.duration_s


def test_quantisation_moves_the_footprint_and_the_coverage_follows_it() -> None:
    """20.6 m lanes are sent as 21 m (the length scale's 1 m steps from 20 m), 123 m lanes
    as 125 m: each 8-lane block spreads 2.8 m wider than asked, centred, so neighbours
    overlap; the coverage counts the lanes flown."""
    area = SurveyArea(0.0, 0.0, 0.0, 24 * 20.6, 123.0, 20.6, 5.0, 0.18)
    p = survey(area=area)
    assert [v.assignment.block.lane_count for v in p.vehicles] == [8, 8, 8]
    overlap_m2 = 0.0
    blocks = sorted(p.vehicles, key=lambda v: v.assignment.block.index)
    for v in blocks:
        f = v.footprint
        assert not f.exact and not v.encoded.snaps[0].changed  # the speed is exact
        assert (f.lane_spacing_m, f.sweep_length_m) == (21.0, 125.0)
        flown_lanes = sorted(f.lanes_across_m)
        assert [b - a for a, b in pairwise(flown_lanes)] == (pytest.approx([21.0] * 7))
        assert f.max_lane_shift_m == pytest.approx(7 * 0.4 / 2)
        assert (f.along_start_m, f.along_end_m) == pytest.approx((-1.0, 124.0))
        assert any("lane_spacing: requested 20.6 m, sent 21 m" in n for n in v.notes)
        assert any("sweep_length: requested 123 m, sent 125 m" in n for n in v.notes)
    for low, high in pairwise(blocks):
        top = max(low.footprint.lanes_across_m) + 20.6 / 2
        bottom = min(high.footprint.lanes_across_m) - 20.6 / 2
        assert top - bottom == pytest.approx(2.8)
        overlap_m2 += (top - bottom) * 123.0
    cov = p.coverage
    # the overlap the moved lanes make, to a cell across per boundary
    assert cov.overlap_m2 == pytest.approx(overlap_m2, abs=2 * cov.cell_across_m * 123.0)
    assert cov.overlap_m2 > 0.0
    # the same lanes as asked (unmoved) would not overlap: the coverage is of the moved ones
    frame = frame_of(area)
    asked = [
        [frame.to_ned(a, p.lanes_across_m[i]) for i in range(8 * k, 8 * k + 8) for a in (0, 123)]
        for k in range(3)
    ]
    exact = coverage(area, frame, [([x for x, _ in t], [y for _, y in t]) for t in asked], 20.6)
    assert exact.overlap_m2 == 0.0


def test_an_odd_lane_is_flown_outside_the_area() -> None:
    """13 lanes for 3 vehicles: 4, 4 and 5; the 5-lane block flies 6 lanes (3 laps), its
    sixth beyond the area's edge, so nothing overlaps."""
    area = SurveyArea(0.0, 0.0, 90.0, 130.0, 100.0, 10.0, 3.0, 0.18)
    p = survey(area=area)
    counts = sorted(v.assignment.block.lane_count for v in p.vehicles)
    assert counts == [4, 4, 5]
    odd = next(v for v in p.vehicles if v.assignment.block.lane_count == 5)
    assert odd.command.params["laps"] == 3 and odd.footprint.extra_lanes == 1
    extra = odd.footprint.lanes_across_m[-1]
    assert extra < 0.0 or extra > 130.0
    assert any("flies 6" in n and "outside the area" in n for n in odd.notes)
    assert p.coverage.overlap_m2 == 0.0 and p.coverage.gap_m2 == 0.0


def test_a_rotated_area_is_covered_the_same() -> None:
    turned = survey(area=replace(AREA, heading_deg=137.0))
    assert turned.coverage.covered_fraction == pytest.approx(1.0)
    assert turned.coverage.overlap_m2 == 0.0


def test_a_speed_beyond_the_profile_is_the_send_checks_violation() -> None:
    p = survey(area=replace(AREA, speed_mps=0.5))
    for v in p.vehicles:
        assert [x.check for x in v.report.violations] == ["top_speed"]
        assert v.survey_estimate.duration_s > v.survey_estimate.planned_duration_s
    assert math.isfinite(p.time_to_finish_s)
