"""Parameter-only retasks continue from the vehicle's progress instead of starting over."""

from __future__ import annotations

import math

import pytest

from planner import LEAD_TURN_RADII, MAX_STEP_RAD, Plan, plan, turn_radius_m
from tests.planner.helpers import (
    TOL,
    angle_diff_deg,
    bearing,
    body_points,
    check_timing,
    command,
    dist,
    horizontal,
    on_path,
    swept_angles,
    unwrapped_bearings,
    vehicle,
    wrap,
    xy,
)


@pytest.mark.parametrize("direction", ["cw", "ccw"])
@pytest.mark.parametrize("new_speed", [0.3, 1.0])
def test_circle_speed_change_continues_from_the_vehicle(direction: str, new_speed: float) -> None:
    old = plan(
        command("circle", speed=0.5, depth=3, radius=10, direction=direction),
        vehicle(0.0, 0.0, 3.0, 0.0, 0.5),
    )
    ls = old.path.loop_start
    assert ls is not None
    lap_t = old.path.times[-1] - old.path.times[ls]
    state = on_path(old, old.path.times[ls] + 0.55 * lap_t)  # past half a lap
    cmd = command("circle", speed=new_speed, depth=3, radius=10, direction=direction)
    p = plan(cmd, state, old)
    path = p.path
    check_timing(p, cmd)
    assert p.anchor == old.anchor
    for i in body_points(p):
        assert dist(xy(path, i), p.anchor) == pytest.approx(10.0, rel=1e-9)
    # the body starts a little ahead of the vehicle in the turning sense, not at the old
    # plan's start (half a lap away)
    s = 1 if direction == "cw" else -1
    b_v = bearing(p.anchor, state.x_m, state.y_m)
    b_0 = bearing(p.anchor, *xy(path, path.body_start))
    ahead = s * wrap(b_0 - b_v)
    reach = (LEAD_TURN_RADII + 1) * turn_radius_m(new_speed)
    assert 0.0 < ahead * 10.0 <= reach, f"body starts {ahead * 10.0:.2f} m of arc ahead"
    assert dist((state.x_m, state.y_m), xy(path, path.body_start)) <= reach
    start_old = bearing(old.anchor, *xy(old.path, old.path.body_start))
    assert abs(wrap(b_0 - start_old)) > math.radians(90)
    # the join is short: well under a lap
    assert path.times[path.body_start] < 0.5 * lap_t * 0.5 / new_speed


@pytest.mark.parametrize("new_end", [8.0, 3.0, 4.0])
def test_helix_new_end_depth_continues_the_turns(new_end: float) -> None:
    old_cmd = command(
        "helix", speed=0.5, start_depth=2, end_depth=4, radius=5, turns=3, direction="cw"
    )
    old = plan(old_cmd, vehicle(0.0, 0.0, 2.0, 90.0, 0.5))
    bs = old.path.body_start
    state = on_path(old, (old.path.times[bs] + old.path.times[-1]) / 2)  # 1.5 turns in
    done = old.progress(state)
    assert done == pytest.approx(1.5, abs=0.02)
    cmd = command(
        "helix", speed=0.5, start_depth=2, end_depth=new_end, radius=5, turns=3, direction="cw"
    )
    p = plan(cmd, state, old)
    path = p.path
    check_timing(p, cmd)
    assert p.anchor == old.anchor
    assert angle_diff_deg(p.angle_deg, old.angle_deg) < 1e-9  # same turn 0
    nbs = path.body_start
    m0 = path.marks[nbs]
    # the turn count continues: marks go on from where the vehicle is, up to 3 turns
    assert done < m0 <= done + 0.5
    assert path.marks[-1] == pytest.approx(3.0)
    assert all(path.marks[i + 1] >= path.marks[i] for i in range(nbs, len(path) - 1))
    b = unwrapped_bearings(p.anchor, path, nbs, len(path) - 1)
    assert b[-1] - b[0] == pytest.approx((3.0 - m0) * 2 * math.pi, abs=1e-6)
    # the body flies the new depth profile from the turn it resumes at
    assert path.zs[-1] == pytest.approx(new_end, abs=TOL)
    expect = 2.0 + (new_end - 2.0) * m0 / 3.0
    if abs(expect - state.z_m) < 0.05:  # no ramp needed to get on it
        assert path.zs[nbs] == pytest.approx(expect, abs=TOL)
    # the turn the body resumes at is where the old plan had it (same phase)
    thetas = swept_angles(p.anchor, path, nbs, math.radians(p.angle_deg), 1)
    assert thetas[0][1] % (2 * math.pi) == pytest.approx((m0 * 2 * math.pi) % (2 * math.pi))


@pytest.mark.parametrize("tracked", [True, False], ids=["segment-known", "segment-none"])
def test_flat_helix_keeps_the_turns_done(tracked: bool) -> None:
    """A helix between equal depths revisits its points every turn: progress must still
    count the turns flown (2.5 of 3 here), not fall back to the first turn."""
    old_cmd = command(
        "helix", speed=0.5, start_depth=3, end_depth=3, radius=4, turns=3, direction="ccw"
    )
    old = plan(old_cmd, vehicle(0.0, 0.0, 3.0, 0.0, 0.5))
    bs = old.path.body_start
    t = old.path.times[bs] + (old.path.times[-1] - old.path.times[bs]) * 2.5 / 3
    state = on_path(old, t, tracked)
    assert old.progress(state) == pytest.approx(2.5, abs=0.01)
    cmd = command(
        "helix", speed=0.5, start_depth=3, end_depth=6, radius=4, turns=3, direction="ccw"
    )
    p = plan(cmd, state, old)
    assert 2.5 < p.path.marks[p.path.body_start] <= 3.0


def test_straight_longer_duration_keeps_elapsed_time() -> None:
    old = plan(
        command("straight", speed=0.5, depth=3, duration=60, heading=90),
        vehicle(0.0, 0.0, 3.0, 90.0, 0.5),
    )
    state = on_path(old, 30.0)
    assert old.progress(state) == pytest.approx(30.0)
    cmd = command("straight", speed=0.5, depth=3, duration=90, heading=90)
    p = plan(cmd, state, old)
    path = p.path
    check_timing(p, cmd)
    assert path.marks[path.body_start] == pytest.approx(30.0)
    assert path.marks[-1] == pytest.approx(90.0)
    assert path.times[-1] == pytest.approx(60.0)
    assert horizontal(path, path.body_start) == pytest.approx(30.0)
    # still on the same line
    assert path.xs[-1] == pytest.approx(0.0, abs=TOL)
    assert path.ys[-1] == pytest.approx(45.0)


def test_straight_shorter_than_elapsed_holds() -> None:
    old = plan(
        command("straight", speed=0.5, depth=3, duration=60, heading=90),
        vehicle(0.0, 0.0, 3.0, 90.0, 0.5),
    )
    state = on_path(old, 40.0)
    p = plan(command("straight", speed=0.5, depth=3, duration=30, heading=90), state, old)
    assert len(p.path) == 1
    assert p.path.point(0) == (state.x_m, state.y_m, state.z_m)
    assert p.path.sample(10.0).speed_mps == 0.0


def test_hover_depth_change_keeps_hold_point_and_elapsed_time() -> None:
    old = plan(command("hover", duration=120, depth=3, heading=30), vehicle(5.0, 5.0, 3.0, 0.0))
    drifted = vehicle(5.3, 4.9, 3.1, 10.0, 0.0, t=50.0)
    assert old.progress(drifted) == pytest.approx(50.0)
    cmd = command("hover", duration=120, depth=5, heading=30)
    p = plan(cmd, drifted, old)
    path = p.path
    assert p.origin == (5.0, 5.0)
    assert path.point(0) == (5.3, 4.9, 3.1)
    assert path.point(len(path) - 1) == pytest.approx((5.0, 5.0, 5.0))
    assert path.times[-1] == pytest.approx(70.0)
    assert path.marks[0] == pytest.approx(50.0)
    assert path.marks[-1] == pytest.approx(120.0)
    assert path.hold_heading_deg == 30.0
    check_timing(p, cmd)


@pytest.mark.parametrize("tracked", [True, False], ids=["segment-known", "segment-none"])
@pytest.mark.parametrize("when", [0.3, 1.5, 2.2])
def test_box_orbit_keeps_laps_done(when: float, tracked: bool) -> None:
    """Laps revisit the same points: without the tracked segment the planner must still
    tell lap 2 from lap 1 (the mission clock says which)."""
    old_cmd = command("box_orbit", speed=0.5, depth=2, radius=5, direction="cw", laps=3)
    old = plan(old_cmd, vehicle(0.0, 0.0, 2.0, 0.0, 0.5))
    bs = old.path.body_start
    lap_t = 40.0 / 0.5
    state = on_path(old, old.path.times[bs] + when * lap_t, tracked)
    assert old.progress(state) == pytest.approx(when, abs=1e-6)
    cmd = command("box_orbit", speed=0.8, depth=2, radius=5, direction="cw", laps=3)
    p = plan(cmd, state, old)
    path = p.path
    check_timing(p, cmd)
    done = math.floor(when)
    nbs = path.body_start
    assert path.marks[nbs] == pytest.approx(done)
    assert path.marks[-1] == pytest.approx(3.0)
    b = unwrapped_bearings(p.anchor, path, nbs, len(path) - 1)
    assert b[-1] - b[0] == pytest.approx((3 - done) * 2 * math.pi, abs=1e-9)
    # the body starts near the vehicle, not back at the old entry
    assert dist((state.x_m, state.y_m), xy(path, nbs)) <= (LEAD_TURN_RADII + 2) * turn_radius_m(
        0.8
    ) + 5.0 * math.sqrt(2)


def test_box_orbit_complete_holds() -> None:
    old = plan(
        command("box_orbit", speed=0.5, depth=2, radius=5, direction="cw", laps=1),
        vehicle(0.0, 0.0, 2.0, 0.0, 0.5),
    )
    state = on_path(old, old.path.times[-1] - 0.5)
    p = plan(command("box_orbit", speed=0.5, depth=2, radius=5, direction="cw", laps=1), state, old)
    assert old.progress(state) < 1.0
    assert p.path.marks[-1] == pytest.approx(1.0)
    # the orbit in progress is flown again in full: one whole lap
    b = unwrapped_bearings(p.anchor, p.path, p.path.body_start, len(p.path) - 1)
    assert b[-1] - b[0] == pytest.approx(2 * math.pi, abs=1e-9)


def test_spiral_parameter_change_continues_the_loops() -> None:
    old = plan(
        command(
            "spiral",
            speed=0.5,
            depth=2,
            initial_radius=2,
            final_radius=10,
            loops=3,
            direction="ccw",
        ),
        vehicle(0.0, 0.0, 2.0, 0.0, 0.5),
    )
    bs = old.path.body_start
    state = on_path(old, (old.path.times[bs] + old.path.times[-1]) / 2)
    done = old.progress(state)
    p = plan(
        command(
            "spiral",
            speed=0.8,
            depth=2,
            initial_radius=2,
            final_radius=10,
            loops=3,
            direction="ccw",
        ),
        state,
        old,
    )
    path = p.path
    assert done < path.marks[path.body_start] <= done + MAX_STEP_RAD
    assert path.marks[-1] == pytest.approx(3.0)
    assert dist(xy(path, len(path) - 1), p.anchor) == pytest.approx(10.0, abs=TOL)


def _progress_is_monotone(p: Plan) -> None:
    m = p.path.marks
    assert all(m[i + 1] >= m[i] - 1e-12 for i in range(len(m) - 1))


def test_marks_never_run_backwards() -> None:
    for name, params in (
        (
            "helix",
            {
                "speed": 0.5,
                "start_depth": 2,
                "end_depth": 6,
                "radius": 3,
                "turns": 2,
                "direction": "cw",
            },
        ),
        ("lawnmower", {"speed": 0.5, "depth": 3, "sweep_length": 20, "lane_spacing": 5, "laps": 2}),
        ("box_orbit", {"speed": 0.5, "depth": 2, "radius": 5, "direction": "ccw", "laps": 2}),
        ("straight", {"speed": 0.5, "depth": 3, "duration": 60, "heading": 45}),
    ):
        cmd = command(name, **params)
        old = plan(cmd, vehicle(1.0, 2.0, 3.0, 10.0, 0.5))
        _progress_is_monotone(old)
        for frac in (0.2, 0.5, 0.8):
            state = on_path(old, old.path.times[-1] * frac)
            _progress_is_monotone(plan(cmd, state, old))
