"""Continuity of time and depth, speeds, and the sampling bound of the curved patterns.

The chord bound is checked against the analytic curve (circle, helix, Archimedean spiral)
rebuilt from the plan's anchor, radii, reference angle and turning sense, sampled densely
between consecutive waypoints.
"""

from __future__ import annotations

import itertools
import math

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from codec import Command, ParamValue
from planner import (
    CHORD_TOL_M,
    MAX_STEP_RAD,
    Plan,
    VehicleState,
    plan,
)
from tests.planner.helpers import (
    CASES,
    case_id,
    check_timing,
    chord_error,
    command,
    dist,
    num,
    sense,
    splits,
    swept_angles,
    turns_between,
    vehicle,
    xy,
)

#: Dense samples of the true curve per chord.
DENSE = 64


ROUND_CASES = [c for c in CASES if c[0] in ("circle", "helix", "spiral")]

STATES = [
    vehicle(0.0, 0.0, 2.0, 90.0, 0.5),
    vehicle(-12.0, 30.0, 11.0, 200.0, 1.0),
    vehicle(3.0, -1.0, 0.0, 359.0, 0.0),
]


@pytest.mark.parametrize("state", STATES)
@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_time_depth_and_speed_continuity(
    case: tuple[str, dict[str, ParamValue]], state: VehicleState
) -> None:
    cmd = command(case[0], **case[1])
    p = plan(cmd, state)
    assert p.path.point(0) == (state.x_m, state.y_m, state.z_m)
    check_timing(p, cmd)


# --- the chord bound on the analytic curve ------------------------------------------------


def round_curve(
    p: Plan, r0: float, r1: float, total: float, s: int
) -> tuple[list[tuple[int, float]], float]:
    """The body's waypoints with their swept angle theta, checked to lie ON the curve
    ``r(theta) = r0 + (r1 - r0) theta / total`` at bearing ``angle_deg + s * theta``."""
    path = p.path
    bs = path.body_start
    phi0 = math.radians(p.angle_deg)
    thetas = [(i, t) for i, t in swept_angles(p.anchor, path, bs, phi0, s) if i not in splits(p)]
    if dist(xy(path, bs), p.anchor) < 1e-9:
        thetas.insert(0, (bs, 0.0))  # the spiral starts at the centre
    if dist(xy(path, len(path) - 1), p.anchor) < 1e-9:
        thetas.append((len(path) - 1, total))  # ... or ends there
    for i, theta in thetas:
        expect = r0 + (r1 - r0) * theta / total
        assert dist(xy(path, i), p.anchor) == pytest.approx(expect, abs=1e-9), f"off curve {i}"
    return thetas, phi0


def check_chords(p: Plan, r0: float, r1: float, total: float, s: int) -> float:
    """Largest chord error of the body against the analytic curve; also checks that no
    chord subtends more than MAX_STEP_RAD at the centre. Returns the error found."""
    thetas, phi0 = round_curve(p, r0, r1, total, s)
    ax, ay = p.anchor
    worst = 0.0
    for (i, t0), (j, t1) in itertools.pairwise(thetas):
        assert -1e-9 <= t1 - t0 <= MAX_STEP_RAD + 1e-9, f"chord {i} turns {t1 - t0} rad"
        curve = []
        for k in range(DENSE + 1):
            th = t0 + (t1 - t0) * k / DENSE
            r = r0 + (r1 - r0) * th / total
            a = phi0 + s * th
            curve.append((ax + r * math.cos(a), ay + r * math.sin(a)))
        # the chord between consecutive curve points (a split point lies on it)
        err = chord_error(curve, xy(p.path, i), xy(p.path, j))
        assert err <= CHORD_TOL_M + 1e-9, f"chord {i}: {err} m from the curve"
        worst = max(worst, err)
    return worst


def test_chord_bound_is_used_not_just_met() -> None:
    """On a large circle the chords come close to the bound: it is what sets the step."""
    cmd = command("circle", speed=0.5, depth=2, radius=50, direction="cw")
    p = plan(cmd, vehicle(0.0, 0.0, 2.0, 0.0))
    worst = check_chords(p, 50.0, 50.0, 2 * math.pi, 1)
    assert worst > 0.8 * CHORD_TOL_M


@pytest.mark.parametrize("case", ROUND_CASES, ids=case_id)
@pytest.mark.parametrize("state", STATES)
def test_chord_bound_of_round_bodies(
    case: tuple[str, dict[str, ParamValue]], state: VehicleState
) -> None:
    cmd = command(case[0], **case[1])
    p = plan(cmd, state)
    check_chords(p, *_shape(cmd))


def _shape(cmd: Command) -> tuple[float, float, float, int]:
    """``(r0, r1, total swept angle, sense)`` of a circle, helix or spiral command.

    A circle's body may fly several laps (the depth ramp) before the one that repeats: its
    swept angle is counted to the end of the path, so r0 = r1 and total only scales theta.
    """
    name = cmd.pattern.name
    if name == "spiral":
        r0, r1 = num(cmd, "initial_radius"), num(cmd, "final_radius")
        return r0, r1, num(cmd, "loops") * 2 * math.pi, sense(cmd)
    r = num(cmd, "radius")
    turns = num(cmd, "turns") if name == "helix" else 1.0
    return r, r, turns * 2 * math.pi, sense(cmd)


_speeds = st.floats(0.05, 2.5)
_radii = st.floats(0.5, 60.0)
_depths = st.floats(0.0, 20.0)
_dirs = st.sampled_from(["cw", "ccw"])


@st.composite
def round_commands(draw: st.DrawFn) -> Command:
    kind = draw(st.sampled_from(["circle", "helix", "spiral"]))
    params: dict[str, ParamValue] = {"speed": draw(_speeds), "direction": draw(_dirs)}
    if kind == "circle":
        params |= {"depth": draw(_depths), "radius": draw(_radii)}
    elif kind == "helix":
        params |= {
            "start_depth": draw(_depths),
            "end_depth": draw(_depths),
            "radius": draw(_radii),
            "turns": draw(st.integers(1, 4)),
        }
    else:
        r0 = draw(st.one_of(st.just(0.0), _radii))
        r1 = draw(st.one_of(st.just(0.0), _radii)) if r0 > 0 else draw(_radii)
        params |= {
            "depth": draw(_depths),
            "initial_radius": r0,
            "final_radius": r1,
            "loops": draw(st.integers(1, 6)),
        }
    return command(kind, **params)


@settings(max_examples=150, deadline=None)
@given(
    cmd=round_commands(),
    x=st.floats(-50, 50),
    y=st.floats(-50, 50),
    z=st.floats(0, 20),
    heading=st.floats(0, 360, exclude_max=True),
)
# found by the sweep: 1e-6 m off the commanded depth, ramped in a 1e-6 m chord at cruise speed
@example(
    cmd=command("circle", speed=0.05, depth=0, radius=1, direction="cw"),
    x=0.0,
    y=1.0,
    z=1e-6,
    heading=0.0,
)
@pytest.mark.slow  # a randomized sweep, ~3 s
def test_chord_bound_random(cmd: Command, x: float, y: float, z: float, heading: float) -> None:
    r0, r1, total, s = _shape(cmd)
    p = plan(cmd, vehicle(x, y, z, heading, num(cmd, "speed")))
    check_chords(p, r0, r1, total, s)
    check_timing(p, cmd)


def test_spiral_through_the_centre_keeps_the_bound() -> None:
    """Tight spirals near r = 0, where the curvature is highest."""
    for r1, loops in ((0.5, 1), (1.0, 4), (3.0, 1), (40.0, 2)):
        for r0, r1_ in ((0.0, r1), (r1, 0.0)):
            cmd = command(
                "spiral",
                speed=0.5,
                depth=2,
                initial_radius=r0,
                final_radius=r1_,
                loops=loops,
                direction="ccw",
            )
            p = plan(cmd, vehicle(1.0, 1.0, 2.0, 0.0))
            check_chords(p, *_shape(cmd))


@pytest.mark.parametrize("case", ROUND_CASES, ids=case_id)
def test_round_bodies_turn_smoothly(case: tuple[str, dict[str, ParamValue]]) -> None:
    """Consecutive chords of a round body turn by at most MAX_STEP_RAD: no chord subtends
    more than that at the centre of curvature (``planner._geometry``'s sampling bound)."""
    cmd = command(case[0], **case[1])
    path = plan(cmd, vehicle(0.0, 0.0, 3.0, 0.0)).path
    corners = [
        (i, round(math.degrees(a), 1))
        for i, a in turns_between(path, path.body_start, len(path) - 1)
        if a > MAX_STEP_RAD + 1e-9
    ]
    assert corners == [], "course changes (waypoint, deg) above MAX_STEP_RAD"
