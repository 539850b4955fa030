"""Bad survey input: a :class:`SurveyError` naming the field at fault (``loc``) and, in words,
what is wrong and what is allowed; never a clamp."""

from __future__ import annotations

from dataclasses import replace

import pytest

from backend.authoring.survey import SurveyArea, SurveyError, SurveyVehicle, preview_survey
from tests.backend.authoring.survey.test_preview import AREA, CHECKS, FLEET


def refused(area: SurveyArea = AREA, vehicles: tuple[SurveyVehicle, ...] = FLEET) -> SurveyError:
    with pytest.raises(SurveyError) as caught:
        preview_survey(area, vehicles, CHECKS)
    assert len(str(caught.value)) <= 300  # the API's 422 keeps every message whole
    return caught.value


def test_no_vehicles() -> None:
    err = refused(vehicles=())
    assert err.loc == ("vehicles",)
    assert str(err) == "no vehicles: a survey is split among 1 to 15 vehicles"


def test_more_vehicles_than_addresses() -> None:
    many = tuple(SurveyVehicle(f"auv{i}", 0.0, 0.0, 0.0) for i in range(1, 17))
    err = refused(area=replace(AREA, width_m=400.0), vehicles=many)
    assert err.loc == ("vehicles",)
    assert str(err).startswith("16 vehicles: a survey is split among 1 to 15 vehicles")


def test_fewer_lanes_than_two_a_vehicle() -> None:
    err = refused(area=replace(AREA, width_m=50.0))  # 5 lanes for 3 vehicles
    assert err.loc == ("vehicles",)
    text = str(err)
    assert "the area has 5 lanes (width_m 50 at lane_spacing_m 10)" in text
    assert "3 vehicles need at least 6" in text
    assert "out-and-back pairs" in text and "use at most 2 vehicles" in text


def test_fewer_lanes_than_vehicles() -> None:
    err = refused(area=replace(AREA, width_m=8.0))  # 1 lane
    assert err.loc == ("area", "width_m")
    assert "the area has 1 lane " in str(err) and "need at least 6" in str(err)


def test_too_many_lanes_for_the_laps_scale() -> None:
    err = refused(area=replace(AREA, width_m=20000.0, lane_spacing_m=10.0))  # 2000 lanes
    assert err.loc == ("area", "width_m")
    assert "the area has 2000 lanes" in str(err)
    assert "3 vehicles fly at most 1530 (255 laps of 2 lanes each" in str(err)


@pytest.mark.parametrize(
    ("field", "value", "words"),
    [
        (
            "length_m",
            900.0,
            "length_m 900 m: it is sent as the lawnmower's sweep_length, whose "
            "8-bit scale allows 0 to 750 m",
        ),
        (
            "lane_spacing_m",
            800.0,
            "lane_spacing_m 800 m: it is sent as the lawnmower's "
            "lane_spacing, whose 8-bit scale allows 0 to 750 m",
        ),
        (
            "speed_mps",
            3.0,
            "speed_mps 3 m/s: it is sent as the lawnmower's speed, whose 8-bit "
            "scale allows 0 to 2.55 m/s",
        ),
        (
            "depth_m",
            200.0,
            "depth_m 200 m: it is sent as the lawnmower's depth, whose 8-bit "
            "scale allows 0 to 107.5 m",
        ),
        (
            "length_m",
            0.01,
            "length_m 0.01 is sent as 0 m (the lawnmower's sweep_length); the "
            "smallest it sends above 0 is 0.025 m",
        ),
        (
            "speed_mps",
            0.004,
            "speed_mps 0.004 is sent as 0 m/s (the lawnmower's speed); the "
            "smallest it sends above 0 is 0.01 m/s",
        ),
    ],
)
def test_an_area_beyond_the_scales(field: str, value: float, words: str) -> None:
    err = refused(area=replace(AREA, **{field: value}))
    assert err.loc == ("area", field)
    assert str(err) == words


def test_a_width_of_nothing() -> None:
    err = refused(area=replace(AREA, width_m=0.0))
    assert err.loc == ("area", "width_m")
    assert str(err) == "width_m 0.0: allowed a finite number above 0 m"


def test_a_vehicle_out_of_the_link_range() -> None:
    far = (*FLEET[:2], SurveyVehicle("auv3", 2000.0, 0.0, 0.0))
    err = refused(vehicles=far)
    assert err.loc == ("vehicles", 2, "x_m")
    assert str(err) == (
        "vehicle auv3 is 2,000 m from the ME transmitter, beyond the link's 730 m range: it "
        "would not hear its command. Allowed: within 730 m of the transmitter (x_m 0, y_m 0)"
    )


def test_a_vehicle_twice() -> None:
    err = refused(vehicles=(*FLEET, FLEET[0]))
    assert err.loc == ("vehicles", 3, "vehicle")
    assert str(err) == "vehicle auv1 is given twice: each vehicle gets one block"


def test_a_vehicle_name_that_is_no_name() -> None:
    err = refused(vehicles=(SurveyVehicle("AUV 1", 0.0, 0.0, 0.0),))
    assert err.loc == ("vehicles", 0, "vehicle")
    assert str(err).startswith("vehicle 'AUV 1': a name is a lower-case letter")


def test_a_position_that_is_not_a_number() -> None:
    err = refused(vehicles=(SurveyVehicle("auv1", float("nan"), 0.0, 0.0),))
    assert err.loc == ("vehicles", 0, "x_m")
    assert str(err) == "vehicle auv1: x_m must be a finite number"
