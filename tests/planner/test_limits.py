"""Validation against operational limits: every violation names the parameter, its value
and the limit; the 100 m rating cannot be overridden; geofences are fixed in NED."""

from __future__ import annotations

import math

import pytest

from codec import ParamValue, make_command
from planner import (
    RATED_DEPTH_M,
    CircleFence,
    LimitError,
    Limits,
    Plan,
    PolygonFence,
    VehicleState,
    check,
    plan,
    turn_radius_m,
    validate,
)

START = VehicleState(0.0, 0.0, 2.0, 0.0, 0.5)


def planned(pattern: str, **params: ParamValue) -> Plan:
    command, _ = make_command(pattern, params)
    return plan(command, START)


def circle(**over: ParamValue) -> Plan:
    params: dict[str, ParamValue] = {"speed": 0.5, "depth": 5, "radius": 5, "direction": "cw"}
    params.update(over)
    return planned("circle", **params)


def test_a_plan_within_limits_has_no_violations() -> None:
    assert validate(circle(), Limits()) == ()
    assert check(circle(), Limits()) == ()


def test_depth_beyond_the_rating_is_not_overridable() -> None:
    (v,) = validate(circle(depth=105), Limits())
    assert (v.param, v.value, v.limit, v.unit, v.overridable) == ("depth", 105.0, 100.0, "m", False)
    assert "100 m rating" in v.message and "105" in v.message
    with pytest.raises(LimitError) as err:
        check(circle(depth=105), Limits(), override=True)
    assert err.value.violations == (v,)


def test_configured_max_depth_is_overridable() -> None:
    limits = Limits(max_depth_m=30)
    (v,) = validate(circle(depth=40), limits)
    assert (v.param, v.value, v.limit, v.overridable) == ("depth", 40.0, 30.0, True)
    with pytest.raises(LimitError, match="deeper than the maximum depth 30 m"):
        check(circle(depth=40), limits)
    assert check(circle(depth=40), limits, override=True) == (v,)


@pytest.mark.parametrize(("name", "value"), [("start_depth", 35.0), ("end_depth", 45.0)])
def test_helix_depths_are_each_checked(name: str, value: float) -> None:
    params: dict[str, ParamValue] = {
        "speed": 0.5,
        "start_depth": 2,
        "end_depth": 8,
        "radius": 5,
        "turns": 1,
        "direction": "ccw",
    }
    params[name] = value
    (v,) = validate(planned("helix", **params), Limits(max_depth_m=30))
    assert (v.param, v.value, v.limit) == (name, value, 30.0)


def test_speed_above_the_maximum() -> None:
    (v,) = validate(circle(speed=1.5, radius=20), Limits(max_speed_mps=1.2))
    assert (v.param, v.value, v.limit, v.unit) == ("speed", 1.5, 1.2, "m/s")
    assert "1.5 m/s" in v.message and "1.2 m/s" in v.message


def test_circle_tighter_than_the_turn_radius() -> None:
    (v,) = validate(circle(radius=1), Limits())
    assert v.param == "radius" and v.value == 1.0
    assert v.limit == pytest.approx(turn_radius_m(0.5))
    assert "slow down or widen it" in v.message
    assert validate(circle(radius=1, speed=0.3), Limits()) == ()


def test_circle_geofence_names_the_extent_parameter() -> None:
    limits = Limits(geofence=CircleFence(8.0))
    assert validate(circle(radius=5), limits) == ()
    (v,) = validate(circle(radius=10), limits)
    assert (v.param, v.value, v.limit, v.unit) == ("radius", 10.0, 8.0, "m")
    assert "geofence circle of 8 m" in v.message and "reduce radius" in v.message


def test_geofence_is_fixed_in_ned_not_moved_with_the_vehicle() -> None:
    far = VehicleState(40.0, 0.0, 2.0, 0.0, 0.5)
    command, _ = make_command("circle", {"speed": 0.5, "depth": 5, "radius": 2, "direction": "cw"})
    (v,) = validate(plan(command, far), Limits(geofence=CircleFence(20.0)))
    assert v.param == "radius"
    moved = Limits(geofence=CircleFence(20.0, centre=(40.0, 0.0)))
    assert validate(plan(command, far), moved) == ()


def test_straight_leaving_the_fence_names_duration() -> None:
    p = planned("straight", speed=0.5, depth=3, duration=120, heading=90)
    (v,) = validate(p, Limits(geofence=CircleFence(30.0)))
    assert (v.param, v.value, v.unit) == ("duration", 120.0, "s")
    assert "reduce duration, speed, heading" in v.message


def test_polygon_fence_catches_a_path_cutting_a_concave_corner() -> None:
    # a fence with a notch cut into it: every waypoint is inside, the first lane crosses it
    fence = PolygonFence(
        [(-5, -5), (14, -5), (14, 3), (18, 3), (18, -5), (30, -5), (30, 10), (-5, 10)]
    )
    lane = planned("lawnmower", speed=0.5, depth=3, sweep_length=25, lane_spacing=1, laps=1)
    assert all(fence.contains(x, y) for x, y in zip(lane.path.xs, lane.path.ys, strict=True))
    (v,) = validate(lane, Limits(geofence=fence))
    assert v.param == "sweep_length" and v.limit is None
    assert "between waypoints" in v.message


def test_polygon_fence_contains_points() -> None:
    square = PolygonFence([(-1, -1), (1, -1), (1, 1), (-1, 1)])
    assert square.contains(0, 0) and not square.contains(2, 0) and not square.contains(0, -1.5)


@pytest.mark.parametrize(
    ("vertices", "message"),
    [
        ([(0, 0), (1, 0)], "at least 3 vertices"),
        ([(0, 0), (1, 0), (2, 0)], "no area"),
        ([(0, 0), (2, 2), (2, 0), (0, 2)], "crosses itself"),
        ([(0, 0), (1, math.nan), (2, 0)], "finite"),
    ],
)
def test_bad_polygons_are_refused(vertices: list[tuple[float, float]], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        PolygonFence(vertices)


@pytest.mark.parametrize(
    ("max_depth_m", "max_speed_mps", "message"),
    [
        (RATED_DEPTH_M + 1, 1.0, "exceeds the vehicle's 100 m rating"),
        (0.0, 1.0, "max_depth_m must be a finite number above 0"),
        (50.0, -1.0, "max_speed_mps must be a finite number above 0"),
        (50.0, math.inf, "max_speed_mps must be a finite number above 0"),
    ],
)
def test_bad_limits_are_refused(max_depth_m: float, max_speed_mps: float, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Limits(max_depth_m, max_speed_mps)


def test_circle_fence_needs_a_positive_radius() -> None:
    with pytest.raises(ValueError, match="geofence radius_m"):
        CircleFence(0.0)


def test_several_violations_are_all_listed() -> None:
    found = validate(circle(depth=40, speed=1.5, radius=30), Limits(30, 1.0, CircleFence(10)))
    assert [v.param for v in found] == ["depth", "speed", "radius"]
    with pytest.raises(LimitError) as err:
        check(circle(depth=40, speed=1.5, radius=30), Limits(30, 1.0, CircleFence(10)))
    assert str(err.value).count(";") == 2
