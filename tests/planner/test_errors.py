"""Commands with no flyable path, and vehicle states that are not numbers."""

from __future__ import annotations

import math

import pytest

from codec import ParamValue
from planner import MAX_WAYPOINTS, PlanError, VehicleState, plan
from tests.planner.helpers import command, vehicle

STATE = vehicle(0.0, 0.0, 2.0, 0.0, 0.5)

_SQUARE: dict[str, ParamValue] = {"speed": 0.5, "depth": 2, "side_span": 8, "direction": "cw"}
_CIRCLE: dict[str, ParamValue] = {"speed": 0.5, "depth": 2, "radius": 5, "direction": "cw"}
_HELIX: dict[str, ParamValue] = {
    "speed": 0.5,
    "start_depth": 2,
    "end_depth": 4,
    "radius": 3,
    "turns": 2,
    "direction": "cw",
}
_SPIRAL: dict[str, ParamValue] = {
    "speed": 0.5,
    "depth": 2,
    "initial_radius": 2,
    "final_radius": 8,
    "loops": 2,
    "direction": "cw",
}
_MOWER: dict[str, ParamValue] = {
    "speed": 0.5,
    "depth": 3,
    "sweep_length": 20,
    "lane_spacing": 5,
    "laps": 2,
}
_BOX: dict[str, ParamValue] = {"speed": 0.5, "depth": 2, "radius": 5, "direction": "cw", "laps": 2}
_STRAIGHT: dict[str, ParamValue] = {"speed": 0.5, "depth": 2, "duration": 60, "heading": 90}
_HOVER: dict[str, ParamValue] = {"duration": 60, "depth": 2, "heading": 0}

BAD: list[tuple[str, dict[str, ParamValue], tuple[str, ...]]] = [
    ("circle", {**_CIRCLE, "radius": 0}, ("radius",)),
    ("helix", {**_HELIX, "radius": 0}, ("radius",)),
    ("square", {**_SQUARE, "side_span": 0}, ("side_span",)),
    ("box_orbit", {**_BOX, "radius": 0}, ("radius",)),
    ("lawnmower", {**_MOWER, "sweep_length": 0}, ("sweep_length",)),
    ("lawnmower", {**_MOWER, "lane_spacing": 0}, ("lane_spacing",)),
    (
        "spiral",
        {**_SPIRAL, "initial_radius": 0, "final_radius": 0},
        ("initial_radius", "final_radius"),
    ),
    ("straight", {**_STRAIGHT, "duration": 0}, ("duration",)),
    ("hover", {**_HOVER, "duration": 0}, ("duration",)),
    ("square", {**_SQUARE, "speed": 0}, ("speed",)),
    ("circle", {**_CIRCLE, "speed": 0}, ("speed",)),
    ("helix", {**_HELIX, "speed": 0}, ("speed",)),
    ("spiral", {**_SPIRAL, "speed": 0}, ("speed",)),
    ("lawnmower", {**_MOWER, "speed": 0}, ("speed",)),
    ("box_orbit", {**_BOX, "speed": 0}, ("speed",)),
    ("straight", {**_STRAIGHT, "speed": 0}, ("speed",)),
]


@pytest.mark.parametrize(("name", "params", "fields"), BAD, ids=[f"{b[0]}-{b[2][0]}" for b in BAD])
def test_plan_error_names_the_field(
    name: str, params: dict[str, ParamValue], fields: tuple[str, ...]
) -> None:
    cmd = command(name, **params)
    with pytest.raises(PlanError) as info:
        plan(cmd, STATE)
    assert info.value.field in fields
    assert isinstance(info.value, ValueError)
    assert str(info.value)
    # the message names the parameter too
    assert any(f in str(info.value) for f in fields)


@pytest.mark.parametrize(("name", "params", "fields"), BAD, ids=[f"{b[0]}-{b[2][0]}" for b in BAD])
def test_plan_error_also_on_retask(
    name: str, params: dict[str, ParamValue], fields: tuple[str, ...]
) -> None:
    """The same commands are refused when they interrupt a plan of the same pattern."""
    good = {
        "circle": _CIRCLE,
        "helix": _HELIX,
        "square": _SQUARE,
        "box_orbit": _BOX,
        "lawnmower": _MOWER,
        "spiral": _SPIRAL,
        "straight": _STRAIGHT,
        "hover": _HOVER,
    }[name]
    current = plan(command(name, **good), STATE)
    with pytest.raises(PlanError) as info:
        plan(command(name, **params), vehicle(1.0, 1.0, 2.0, 30.0, 0.5, 5.0), current)
    assert info.value.field in fields


def test_one_zero_spiral_radius_is_fine() -> None:
    for r0, r1 in ((0, 5), (5, 0)):
        p = plan(command("spiral", **{**_SPIRAL, "initial_radius": r0, "final_radius": r1}), STATE)
        assert len(p.path) > 2


@pytest.mark.parametrize(
    ("name", "params"),
    [
        ("spiral", {**_SPIRAL, "initial_radius": 0, "final_radius": 700, "loops": 255}),
        ("spiral", {**_SPIRAL, "initial_radius": 700, "final_radius": 0.5, "loops": 255}),
        ("helix", {**_HELIX, "radius": 700, "turns": 255}),
    ],
    ids=["spiral-out", "spiral-in", "helix"],
)
def test_too_many_waypoints(name: str, params: dict[str, ParamValue]) -> None:
    with pytest.raises(PlanError) as info:
        plan(command(name, **params), STATE)
    assert str(MAX_WAYPOINTS) in str(info.value)


def test_largest_plans_that_fit_stay_within_the_budget() -> None:
    for name, params in (
        ("lawnmower", {**_MOWER, "sweep_length": 750, "laps": 255}),
        ("box_orbit", {**_BOX, "laps": 255}),
        ("helix", {**_HELIX, "radius": 2, "turns": 255}),
    ):
        p = plan(command(name, **params), STATE)
        assert len(p.path) <= MAX_WAYPOINTS


_FIELDS = ["x_m", "y_m", "z_m", "heading_deg", "speed_mps", "t_s"]


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
@pytest.mark.parametrize("field", _FIELDS)
def test_vehicle_state_rejects_non_finite(field: str, bad: float) -> None:
    values = [1.0] * len(_FIELDS)
    values[_FIELDS.index(field)] = bad
    with pytest.raises(ValueError, match=field):
        x, y, z, heading, speed, t = values
        VehicleState(x, y, z, heading, speed, t)


def test_vehicle_state_rejects_negative_segment() -> None:
    with pytest.raises(ValueError, match="segment"):
        VehicleState(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1)


def test_vehicle_state_normalises_heading() -> None:
    assert VehicleState(0.0, 0.0, 0.0, -90.0).heading_deg == 270.0
    assert VehicleState(0.0, 0.0, 0.0, 720.0).heading_deg == 0.0
