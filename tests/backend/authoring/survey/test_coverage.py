"""The coverage grid: a swath is a strip one lane spacing wide around the path, counted only
inside the area; overlaps are between vehicles, never a vehicle with itself."""

from __future__ import annotations

import pytest

from backend.authoring.survey.area import SurveyArea, area_lanes, frame_of, lane_count
from backend.authoring.survey.coverage import MAX_CELLS, cell_size_m, coverage

#: 100 m lanes over 40 m at 10 m (four lanes at 5, 15, 25, 35 m across), lanes north.
AREA = SurveyArea(0.0, 0.0, 0.0, 40.0, 100.0, 10.0, 2.0, 0.2)


def _lane(across_m: float) -> tuple[list[float], list[float]]:
    """A lane over the area's length (NED: along is north, across is east)."""
    return [0.0, 100.0], [across_m, across_m]


def test_one_lane_covers_its_strip() -> None:
    cov = coverage(AREA, frame_of(AREA), [_lane(5.0)], 10.0)
    assert cov.covered_m2 == pytest.approx(1000.0)
    assert cov.gap_m2 == pytest.approx(3000.0) and cov.gap_fraction == pytest.approx(0.75)
    assert cov.overlap_m2 == 0.0


def test_a_strip_beyond_the_edge_covers_nothing_outside() -> None:
    cov = coverage(AREA, frame_of(AREA), [_lane(0.0)], 10.0)  # half of it outside
    assert cov.covered_m2 == pytest.approx(500.0)


def test_two_vehicles_on_neighbouring_lanes_touch_without_overlap() -> None:
    cov = coverage(AREA, frame_of(AREA), [_lane(5.0), _lane(15.0)], 10.0)
    assert cov.covered_m2 == pytest.approx(2000.0) and cov.overlap_m2 == 0.0


def test_overlap_is_between_vehicles_not_within_one() -> None:
    both = ([0.0, 100.0, 100.0, 0.0], [5.0, 5.0, 9.0, 9.0])  # one vehicle, lanes 4 m apart
    cov = coverage(AREA, frame_of(AREA), [both], 10.0)
    assert cov.overlap_m2 == 0.0
    assert cov.covered_m2 == pytest.approx(1400.0)
    cov = coverage(AREA, frame_of(AREA), [_lane(5.0), _lane(9.0)], 10.0)  # two vehicles
    assert cov.overlap_m2 == pytest.approx(600.0)
    assert cov.overlap_fraction == pytest.approx(0.15)
    assert cov.vehicle_m2 == pytest.approx((1000.0, 1000.0))


def test_the_area_lanes_are_centred() -> None:
    assert area_lanes(AREA) == pytest.approx((5.0, 15.0, 25.0, 35.0))
    wider = SurveyArea(0.0, 0.0, 0.0, 45.0, 100.0, 10.0, 2.0, 0.2)
    assert lane_count(wider) == 5
    assert area_lanes(wider) == pytest.approx((2.5, 12.5, 22.5, 32.5, 42.5))


def test_a_large_area_gets_coarser_cells() -> None:
    big = SurveyArea(0.0, 0.0, 0.0, 20000.0, 750.0, 10.0, 2.0, 0.2)
    cell = cell_size_m(big)
    assert cell > 1.0
    assert (20000.0 / cell) * (750.0 / cell) == pytest.approx(MAX_CELLS)
    assert cell_size_m(AREA) == pytest.approx(0.5)  # a twentieth of the lane spacing
