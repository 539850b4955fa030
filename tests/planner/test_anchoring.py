"""The anchoring rule, in the paper's three retask scenarios and rule by rule."""

from __future__ import annotations

import math

import pytest

from codec import ParamValue
from planner import DEPTH_RATE_MPS, Plan, anchor_for, plan
from tests.planner.helpers import (
    TOL,
    angle_diff_deg,
    body_points,
    check_timing,
    command,
    depth_rate_violations,
    dist,
    num,
    on_path,
    straight_legs,
    vehicle,
    xy,
)

# --- (a) lawnmower: a longer sweep in the middle of the survey ----------------------------


def _frame(p: Plan) -> tuple[float, float, float, float, float, float]:
    """``(origin x, origin y, ux, uy, vx, vy)``: the lane axis and starboard unit vectors."""
    h = math.radians(p.angle_deg)
    return (*p.origin, math.cos(h), math.sin(h), -math.sin(h), math.cos(h))


def _along_cross(p: Plan, pt: tuple[float, float]) -> tuple[float, float]:
    ox, oy, ux, uy, vx, vy = _frame(p)
    return (pt[0] - ox) * ux + (pt[1] - oy) * uy, (pt[0] - ox) * vx + (pt[1] - oy) * vy


@pytest.mark.parametrize("heading", [0.0, 90.0, 217.5])
def test_scenario_a_lawnmower_longer_sweep_mid_survey(heading: float) -> None:
    old_cmd = command("lawnmower", speed=0.5, depth=3, sweep_length=20, lane_spacing=5, laps=2)
    old = plan(old_cmd, vehicle(12.0, -4.0, 3.0, heading, 0.5))
    # mid-survey on lane 1 (the first lane back): 40 s of lane 0, 10 s step, 20 s of lane 1
    state = on_path(old, 70.0)
    along, cross = _along_cross(old, (state.x_m, state.y_m))
    assert (along, cross) == pytest.approx((10.0, 5.0), abs=TOL)
    new_cmd = command("lawnmower", speed=0.5, depth=3, sweep_length=30, lane_spacing=5, laps=2)
    new = plan(new_cmd, state, old)
    path = new.path
    check_timing(new, new_cmd)
    # same origin and axis
    assert new.origin == pytest.approx(old.origin, abs=1e-12)
    assert angle_diff_deg(new.angle_deg, old.angle_deg) < 1e-9
    # lanes already started keep their offsets; the count is the commanded 2 * laps
    assert new.lanes[:2] == pytest.approx(old.lanes[:2], abs=1e-12)
    assert len(new.lanes) == 4
    # the lane number continues: the body starts on lane 1, not back on lane 0
    assert path.marks[path.body_start] >= 2.0
    assert min(path.marks[path.body_start :]) >= 2.0
    a0, c0 = _along_cross(new, xy(path, path.body_start))
    assert c0 == pytest.approx(old.lanes[1], abs=TOL)
    assert a0 < along  # ahead of the vehicle on lane 1, which runs toward along = 0
    legs = straight_legs(path, path.body_start)
    # rest of lane 1, step, lane 2, step, lane 3
    assert len(legs) == 5
    rest, _, lane2, _, lane3 = legs
    assert _along_cross(new, rest[1]) == pytest.approx((0.0, 5.0), abs=TOL)
    for leg, offset, (a_from, a_to) in ((lane2, 10.0, (0.0, 30.0)), (lane3, 15.0, (30.0, 0.0))):
        (fa, fc), (ta, tc) = _along_cross(new, leg[0]), _along_cross(new, leg[1])
        assert (fa, ta) == pytest.approx((a_from, a_to), abs=TOL)
        assert fc == pytest.approx(offset, abs=TOL)
        assert tc == pytest.approx(offset, abs=TOL)
    # the mission anchor is the centre of the new box
    assert dist(new.anchor, xy_of(new, 15.0, 7.5)) < TOL
    assert path.marks[-1] == pytest.approx(7.0)


def xy_of(p: Plan, along: float, cross: float) -> tuple[float, float]:
    ox, oy, ux, uy, vx, vy = _frame(p)
    return ox + along * ux + cross * vx, oy + along * uy + cross * vy


def test_lawnmower_new_spacing_applies_to_later_lanes_only() -> None:
    old = plan(
        command("lawnmower", speed=0.5, depth=3, sweep_length=20, lane_spacing=5, laps=2),
        vehicle(0.0, 0.0, 3.0, 0.0, 0.5),
    )
    state = on_path(old, 70.0)  # on lane 1
    new = plan(
        command("lawnmower", speed=0.5, depth=3, sweep_length=20, lane_spacing=2, laps=2),
        state,
        old,
    )
    assert new.lanes == pytest.approx((0.0, 5.0, 7.0, 9.0), abs=1e-12)


# --- (b) helix -> square around the same anchor -------------------------------------------


def test_scenario_b_helix_then_square_on_the_same_anchor() -> None:
    helix = command(
        "helix", speed=0.5, start_depth=2, end_depth=4, radius=2.5, turns=3, direction="cw"
    )
    first = plan(helix, vehicle(10.0, -5.0, 2.0, 30.0, 0.5))
    anchor = first.anchor
    assert anchor == (10.0, -5.0)
    bs = first.path.body_start
    t_mid = (first.path.times[bs] + first.path.times[-1]) / 2
    state = on_path(first, t_mid)
    assert 2.0 < state.z_m < 4.0  # mid-helix, between its depths
    square = command("square", speed=0.5, depth=3, side_span=5, direction="cw")
    p = plan(square, state, first)
    assert p.anchor == anchor
    assert p.origin == anchor
    path = p.path
    ax, ay = anchor
    corners = {
        (round(path.xs[i] - ax, 6), round(path.ys[i] - ay, 6))
        for i in range(path.body_start, len(path))
    }
    assert corners >= {(2.5, 2.5), (2.5, -2.5), (-2.5, 2.5), (-2.5, -2.5)}
    for i in range(path.body_start, len(path)):
        assert max(abs(path.xs[i] - ax), abs(path.ys[i] - ay)) == pytest.approx(2.5, abs=TOL)
    assert path.point(0) == (state.x_m, state.y_m, state.z_m)
    assert depth_rate_violations(path, DEPTH_RATE_MPS) == []
    ls = path.loop_start
    assert ls is not None
    assert all(z == pytest.approx(3.0, abs=TOL) for z in path.zs[ls:])


# --- (c) square -> circle around the same anchor ------------------------------------------


def test_scenario_c_square_then_circle_ramps_without_a_step() -> None:
    sq = command("square", speed=0.5, depth=2, side_span=8, direction="cw")
    first = plan(sq, vehicle(-3.0, 6.0, 2.0, 0.0, 0.5))
    anchor = first.anchor
    ls = first.path.loop_start
    assert ls is not None
    state = on_path(first, first.path.times[ls] + 23.0)  # on the second side of the lap
    assert max(abs(state.x_m - anchor[0]), abs(state.y_m - anchor[1])) == pytest.approx(4.0)
    circle = command("circle", speed=0.5, depth=3, radius=5, direction="cw")
    p = plan(circle, state, first)
    path = p.path
    assert p.anchor == anchor
    for i in body_points(p):
        assert dist(xy(path, i), anchor) == pytest.approx(5.0, rel=1e-9)
    # the depth ramps from 2 m to 3 m: no step, never faster than the depth rate
    assert path.zs[0] == 2.0
    assert depth_rate_violations(path, DEPTH_RATE_MPS) == []
    assert all(2.0 - TOL <= z <= 3.0 + TOL for z in path.zs)
    assert all(path.zs[i + 1] >= path.zs[i] - TOL for i in range(len(path) - 1))
    loop = path.loop_start
    assert loop is not None
    assert all(z == pytest.approx(3.0, abs=TOL) for z in path.zs[loop:])
    # the ramp takes 20 s at 0.05 m/s
    reach = next(i for i, z in enumerate(path.zs) if z >= 3.0 - TOL)
    assert path.times[reach] == pytest.approx(1.0 / DEPTH_RATE_MPS, rel=1e-6)
    check_timing(p, circle)


# --- the rule, case by case ----------------------------------------------------------------


CIRCLE = command("circle", speed=0.5, depth=3, radius=5, direction="ccw")


def test_first_command_is_anchored_on_the_vehicle() -> None:
    state = vehicle(7.0, -2.0, 1.0, 80.0)
    assert anchor_for(None, state) == (7.0, -2.0)
    assert plan(CIRCLE, state).anchor == (7.0, -2.0)


def test_after_a_straight_the_anchor_is_where_the_vehicle_is() -> None:
    straight = plan(
        command("straight", speed=0.5, depth=3, duration=60, heading=90),
        vehicle(0.0, 0.0, 3.0, 90.0),
    )
    state = on_path(straight, 40.0)
    assert anchor_for(straight, state) == (state.x_m, state.y_m)
    p = plan(CIRCLE, state, straight)
    assert p.anchor == (state.x_m, state.y_m)
    for i in body_points(p):
        assert dist(xy(p.path, i), (state.x_m, state.y_m)) == pytest.approx(5.0, rel=1e-9)


@pytest.mark.parametrize("interrupt", ["hover", "surface"])
def test_hover_and_surface_keep_the_anchor(interrupt: str) -> None:
    orbit = plan(CIRCLE, vehicle(20.0, 20.0, 3.0, 0.0))
    anchor = orbit.anchor
    state = on_path(orbit, 100.0)
    cmd = (
        command("hover", duration=30, depth=3, heading=0)
        if interrupt == "hover"
        else command("surface")
    )
    pause = plan(cmd, state, orbit)
    assert pause.anchor == anchor
    # the pause itself stays where it took effect
    assert pause.origin == (state.x_m, state.y_m)
    assert all(x == state.x_m for x in pause.path.xs)
    later = on_path(pause, pause.path.times[-1] + 1.0)
    assert anchor_for(pause, later) == anchor
    again = plan(CIRCLE, later, pause)
    assert again.anchor == anchor
    for i in body_points(again):
        assert dist(xy(again.path, i), anchor) == pytest.approx(num(CIRCLE, "radius"), rel=1e-9)


def test_lawnmower_anchor_is_the_centre_of_its_box() -> None:
    mower = plan(
        command("lawnmower", speed=0.5, depth=3, sweep_length=20, lane_spacing=5, laps=2),
        vehicle(0.0, 0.0, 3.0, 90.0),  # lanes run east, stepping south (starboard)
    )
    assert mower.anchor == pytest.approx((-7.5, 10.0), abs=1e-12)
    state = on_path(mower, 120.0)
    assert anchor_for(mower, state) == mower.anchor
    p = plan(CIRCLE, state, mower)
    assert p.anchor == mower.anchor


def test_lawnmower_starts_from_the_vehicle_not_the_anchor() -> None:
    orbit = plan(CIRCLE, vehicle(20.0, 20.0, 3.0, 0.0))
    state = on_path(orbit, 50.0)
    mower = plan(
        command("lawnmower", speed=0.5, depth=3, sweep_length=20, lane_spacing=5, laps=2),
        state,
        orbit,
    )
    assert mower.origin == (state.x_m, state.y_m)
    assert angle_diff_deg(mower.angle_deg, state.heading_deg) < 1e-9


@pytest.mark.parametrize("name", ["square", "circle", "spiral", "helix", "box_orbit"])
def test_orbits_switch_around_the_same_anchor(name: str) -> None:
    table: dict[str, dict[str, ParamValue]] = {
        "square": {"speed": 0.5, "depth": 2, "side_span": 8, "direction": "cw"},
        "circle": {"speed": 0.5, "depth": 2, "radius": 4, "direction": "cw"},
        "spiral": {
            "speed": 0.5,
            "depth": 2,
            "initial_radius": 2,
            "final_radius": 6,
            "loops": 2,
            "direction": "cw",
        },
        "helix": {
            "speed": 0.5,
            "start_depth": 2,
            "end_depth": 3,
            "radius": 4,
            "turns": 1,
            "direction": "ccw",
        },
        "box_orbit": {"speed": 0.5, "depth": 2, "radius": 4, "direction": "ccw", "laps": 1},
    }
    params = table[name]
    orbit = plan(CIRCLE, vehicle(-10.0, 4.0, 3.0, 45.0))
    state = on_path(orbit, 70.0)
    p = plan(command(name, **params), state, orbit)
    assert p.anchor == orbit.anchor
    assert p.origin == orbit.anchor
