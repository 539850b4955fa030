"""Retask joins: the new path starts where the vehicle is, on its heading and depth, and
reaches the pattern tangentially, from any vehicle state."""

from __future__ import annotations

import math

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from codec import ParamValue
from planner import MAX_STEP_RAD, YAW_RATE_DPS, Plan, VehicleState, plan, turn_radius_m
from tests.planner.helpers import (
    CASES,
    TOL,
    case_id,
    check_timing,
    command,
    horizontal,
    turns_between,
    vehicle,
    wrap,
)


def _current(name: str, **params: ParamValue) -> Plan:
    """A plan the vehicle was running, started at the origin heading north at 3 m."""
    return plan(command(name, **params), vehicle(0.0, 0.0, 3.0, 0.0, 0.5))


#: Plans a retask may interrupt (None: the first command of the mission).
CURRENTS: list[tuple[str, Plan | None]] = [
    ("none", None),
    ("circle", _current("circle", speed=0.5, depth=3, radius=5, direction="cw")),
    (
        "helix",
        _current(
            "helix", speed=0.5, start_depth=2, end_depth=4, radius=2.5, turns=3, direction="cw"
        ),
    ),
    (
        "spiral",
        _current(
            "spiral",
            speed=0.5,
            depth=2,
            initial_radius=2,
            final_radius=10,
            loops=3,
            direction="cw",
        ),
    ),
    ("square", _current("square", speed=0.5, depth=2, side_span=8, direction="ccw")),
    ("box_orbit", _current("box_orbit", speed=0.5, depth=2, radius=5, direction="cw", laps=2)),
    (
        "lawnmower",
        _current("lawnmower", speed=0.5, depth=3, sweep_length=20, lane_spacing=5, laps=2),
    ),
    ("straight", _current("straight", speed=0.5, depth=3, duration=60, heading=90)),
    ("hover", _current("hover", duration=60, depth=3, heading=0)),
]

_case = st.sampled_from(CASES)
_current_plan = st.sampled_from(CURRENTS)
_pos = st.floats(-50.0, 50.0)
_depth = st.floats(0.0, 20.0)
_heading = st.floats(0.0, 360.0, exclude_max=True)
_speed = st.floats(0.0, 2.0)


def check_join(p: Plan, state: VehicleState) -> None:
    path = p.path
    # starts exactly at the vehicle, no depth step
    assert path.point(0) == (state.x_m, state.y_m, state.z_m)
    if len(path) == 1:
        return
    # first segment on the vehicle's heading, unless it is vertical: within half of one
    # chord of a turn (at most MAX_STEP_RAD / 2)
    h0 = horizontal(path, 0)
    if h0 > TOL:
        c = math.atan2(path.ys[1] - path.ys[0], path.xs[1] - path.xs[0])
        step = abs(wrap(c - state.heading_rad))
        # the planner takes points within TOL (1e-6 m) as equal (a vehicle that close to a
        # spiral's centre starts it there): that much offset skews the chord by TOL / h0
        assert step <= MAX_STEP_RAD / 2 + 1e-9 + TOL / h0, (
            f"heading step {math.degrees(step):.2f} deg"
        )
    # tangential all along the join and into the body
    bs = path.body_start
    kinks = [
        (i, round(math.degrees(a), 2))
        for i, a in turns_between(path, 0, min(len(path) - 1, bs + 1))
        if a > MAX_STEP_RAD + 1e-9
        and not (i == bs and a <= math.pi / 2 + MAX_STEP_RAD / 2 + 1e-9 and at_corner(p))
    ]
    assert kinks == [], "course changes (waypoint, deg) above MAX_STEP_RAD in the join"


def at_corner(p: Plan) -> bool:
    """Whether the body starts at a corner of the pattern (a square's corner, a lawnmower
    lane's end): there the join arrives along the side or lane that ends at the corner, and
    the pattern's own 90 deg turn follows."""
    path = p.path
    x, y = path.xs[path.body_start], path.ys[path.body_start]
    name = p.pattern
    if name in ("square", "box_orbit"):
        size = p.command.params["side_span" if name == "square" else "radius"]
        assert not isinstance(size, str)
        half = size / 2 if name == "square" else size
        ax, ay = p.anchor
        return abs(abs(x - ax) - half) < 1e-6 and abs(abs(y - ay) - half) < 1e-6
    if name == "lawnmower":
        length = p.command.params["sweep_length"]
        assert not isinstance(length, str)
        h = math.radians(p.angle_deg)
        along = (x - p.origin[0]) * math.cos(h) + (y - p.origin[1]) * math.sin(h)
        return abs(along) < 1e-6 or abs(along - length) < 1e-6
    return False


@settings(max_examples=1000, deadline=None)
@given(
    case=_case,
    current=_current_plan,
    x=_pos,
    y=_pos,
    z=_depth,
    heading=_heading,
    speed=_speed,
)
@example(  # the entry is a corner
    case=CASES[0], current=CURRENTS[0], x=0.0, y=0.0, z=2.0, heading=45.0, speed=0.5
)
@pytest.mark.slow  # a sweep of poses, ~1.5 s
def test_join_starts_on_the_vehicle_pose(
    case: tuple[str, dict[str, ParamValue]],
    current: tuple[str, Plan | None],
    x: float,
    y: float,
    z: float,
    heading: float,
    speed: float,
) -> None:
    name, params = case
    cur = current[1]
    if name == "hover" and cur is not None and cur.pattern == "hover":
        return  # station keeping back to the old hold point: see test_retask
    cmd = command(name, **params)
    state = vehicle(x, y, z, heading, speed)
    p = plan(cmd, state, cur)
    check_join(p, state)
    check_timing(p, cmd)


def _cur(label: str) -> Plan:
    found = dict(CURRENTS)[label]
    assert found is not None
    return found


STOPS: list[tuple[str, str, dict[str, ParamValue], tuple[float, float, float, float, float]]] = [
    # the Dubins join ends a hair (< 1e-6 m) short of its goal, then the ramp finishes there
    (
        "lawnmower",
        "lawnmower",
        {"speed": 0.5, "depth": 3, "sweep_length": 20, "lane_spacing": 5, "laps": 2},
        (0.0, 0.0, 0.12572557932649, 0.12572557932649, 0.12572557932649),
    ),
    (
        "helix",
        "helix",
        {
            "speed": 0.5,
            "start_depth": 9,
            "end_depth": 1,
            "radius": 1,
            "turns": 2,
            "direction": "ccw",
        },
        (23.14269196591833, 5.96e-08, 12.264743853906676, 5.96e-08, 5.96e-08),
    ),
    # a shorter sweep clips the lawnmower's entry to the lane end, which the lane repeats
    (
        "lawnmower",
        "lawnmower",
        {"speed": 1.5, "depth": 0.5, "sweep_length": 7, "lane_spacing": 2, "laps": 1},
        (0.0, 0.0, 3.0, 0.0, 0.5),
    ),
    # the square is entered at a corner: a zero-length first side, then the ramp there
    (
        "circle",
        "square",
        {"speed": 1.2, "depth": 6, "side_span": 3, "direction": "ccw"},
        (19.795381615128278, 19.795381615128278, 1.8571865246246546, 10.84, 1.857),
    ),
]


@pytest.mark.parametrize(
    ("label", "name", "params", "pose"),
    STOPS,
    ids=["dubins-end-lawnmower", "dubins-end-helix", "lane-end-lawnmower", "corner-square"],
)
def test_no_stop_mid_path_to_finish_the_ramp(
    label: str,
    name: str,
    params: dict[str, ParamValue],
    pose: tuple[float, float, float, float, float],
) -> None:
    """Found by the property test above: the depth ramp runs while the vehicle moves; an
    (almost) zero-length segment inside the path must not make it stop and ramp in place."""
    cmd = command(name, **params)
    state = vehicle(*pose)
    p = plan(cmd, state, _cur(label))
    check_join(p, state)
    check_timing(p, cmd)


@pytest.mark.parametrize("heading", [0.0, 45.0, 135.0, 225.0, 315.0, 90.0])
@pytest.mark.parametrize("name", ["square", "box_orbit"])
def test_square_entered_from_its_centre_on_a_diagonal(name: str, heading: float) -> None:
    """From the anchor on a diagonal heading the entry point is (nearly) a corner: the body
    must still start along the side it flies, not turn 90 deg at the entry."""
    params: dict[str, ParamValue] = (
        {"speed": 0.5, "depth": 2, "side_span": 8, "direction": "cw"}
        if name == "square"
        else {"speed": 0.5, "depth": 2, "radius": 4, "direction": "cw", "laps": 1}
    )
    state = vehicle(0.0, 0.0, 2.0, heading, 0.5)
    check_join(plan(command(name, **params), state), state)


@pytest.mark.parametrize("case", CASES, ids=case_id)
@pytest.mark.parametrize(("label", "current"), CURRENTS, ids=[c[0] for c in CURRENTS])
def test_join_grid(
    case: tuple[str, dict[str, ParamValue]], label: str, current: Plan | None
) -> None:
    """Every pattern after every pattern, from a few fixed poses around the anchor."""
    name, params = case
    if name == "hover" and label == "hover":
        return
    cmd = command(name, **params)
    for x, y, z, h in ((7.0, -3.0, 0.0, 10.0), (-30.0, 40.0, 15.0, 250.0), (0.0, 0.0, 3.0, 0.0)):
        state = vehicle(x, y, z, h, 0.5)
        p = plan(cmd, state, current)
        check_join(p, state)
        check_timing(p, cmd)


# --- the join is flyable at the speed it is flown -----------------------------------------


def _circumradius(a: tuple[float, float], b: tuple[float, float], c: tuple[float, float]) -> float:
    ab = math.dist(a, b)
    bc = math.dist(b, c)
    ca = math.dist(c, a)
    cross = abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
    return math.inf if cross < 1e-12 else ab * bc * ca / (2.0 * cross)


@pytest.mark.parametrize("vehicle_speed", [0.0, 0.2, 0.5, 1.5])
@pytest.mark.parametrize("command_speed", [0.2, 0.5, 1.5])
@pytest.mark.parametrize("name", ["circle", "straight", "square"])
def test_join_turns_within_the_yaw_rate(
    name: str, command_speed: float, vehicle_speed: float
) -> None:
    """Turns of the join are flown at the commanded speed, so their radius must be at least
    turn_radius_m(that speed): the yaw rate stays within YAW_RATE_DPS whatever speed the
    vehicle had when the command took effect."""
    table: dict[str, dict[str, ParamValue]] = {
        "circle": {"speed": command_speed, "depth": 3, "radius": 20, "direction": "cw"},
        "straight": {"speed": command_speed, "depth": 3, "duration": 60, "heading": 180},
        "square": {"speed": command_speed, "depth": 3, "side_span": 40, "direction": "ccw"},
    }
    params = table[name]
    state = vehicle(0.0, 0.0, 3.0, 0.0, vehicle_speed)
    p = plan(command(name, **params), state)
    path = p.path
    end = path.body_start
    for i in range(1, end):
        v = max(path.speeds[i - 1], path.speeds[i])
        r = _circumradius(
            (path.xs[i - 1], path.ys[i - 1]),
            (path.xs[i], path.ys[i]),
            (path.xs[i + 1], path.ys[i + 1]),
        )
        need = turn_radius_m(v)
        assert r >= need * (1 - 1e-6), (
            f"turn of radius {r:.3f} m at waypoint {i} flown at {v} m/s needs {need:.3f} m "
            f"(yaw rate {math.degrees(v / r):.1f} deg/s > {YAW_RATE_DPS})"
        )
