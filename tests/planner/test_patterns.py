"""Geometry of each pattern, checked against the analytic shape it should fly.

Every command goes through the codec first (snapped, framed, decoded), and the expected
values are the decoded ones.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from planner import (
    DEPTH_RATE_MPS,
    HEAVE_CAPABILITY_MPS,
    Path,
    plan,
    turn_radius_m,
)
from tests.planner.helpers import (
    TOL,
    angle_diff_deg,
    bearing,
    command,
    dist,
    horizontal,
    num,
    sense,
    straight_legs,
    swept_angles,
    unwrapped_bearings,
    vehicle,
    xy,
)

DIRECTIONS = ("cw", "ccw")


def _lap_closes(path: Path) -> None:
    """A repeating path's last waypoint is its ``loop_start`` waypoint (x, y and z)."""
    assert path.loop_start is not None
    ls = path.loop_start
    assert path.point(ls) == pytest.approx(path.point(len(path) - 1), abs=TOL)


def _body_duration_flat(path: Path, lo: int, hi: int, speed: float) -> None:
    """At constant depth each segment takes its horizontal length / speed."""
    for i in range(lo, hi):
        dt = path.times[i + 1] - path.times[i]
        assert dt == pytest.approx(horizontal(path, i) / speed, rel=1e-9, abs=1e-9), i
        assert path.zs[i + 1] == pytest.approx(path.zs[i], abs=TOL), i


# --- square and box orbit -------------------------------------------------------------------


@pytest.mark.parametrize("direction", DIRECTIONS)
@pytest.mark.parametrize(("x", "y", "heading"), [(0.0, 0.0, 90.0), (3.0, -2.0, 30.0)])
def test_square_closes_with_the_given_side(
    direction: str, x: float, y: float, heading: float
) -> None:
    cmd = command("square", speed=0.5, depth=2, side_span=8, direction=direction)
    side, speed = num(cmd, "side_span"), num(cmd, "speed")
    half = side / 2
    p = plan(cmd, vehicle(x, y, 2.0, heading))
    path = p.path
    assert p.anchor == (x, y)
    assert p.origin == (x, y)
    ax, ay = p.anchor
    body = range(path.body_start, len(path))
    # every body point is on the square's outline
    for i in body:
        on = max(abs(path.xs[i] - ax), abs(path.ys[i] - ay))
        assert on == pytest.approx(half, abs=TOL), i
        assert path.zs[i] == pytest.approx(num(cmd, "depth"), abs=TOL)
    # its four corners are at anchor +- side/2
    corners = {(round(path.xs[i] - ax, 6), round(path.ys[i] - ay, 6)) for i in body}
    for cx in (half, -half):
        for cy in (half, -half):
            assert (cx, cy) in corners
    # the repeated lap returns to its start and is one perimeter long
    _lap_closes(path)
    ls = path.loop_start
    assert ls is not None
    lap_len = sum(horizontal(path, i) for i in range(ls, len(path) - 1))
    assert lap_len == pytest.approx(4 * side, abs=1e-9)
    assert path.times[-1] - path.times[ls] == pytest.approx(4 * side / speed, rel=1e-9)
    _body_duration_flat(path, ls, len(path) - 1, speed)
    # direction: the bearing from the anchor runs one full turn in the commanded sense
    b = unwrapped_bearings(p.anchor, path, ls, len(path) - 1)
    s = sense(cmd)
    assert all(s * (b[k + 1] - b[k]) > 0 for k in range(len(b) - 1))
    assert s * (b[-1] - b[0]) == pytest.approx(2 * math.pi, abs=1e-9)


def test_square_ramp_ends_before_the_repeated_lap() -> None:
    """From far off the depth, the lap that repeats is flown entirely at the square's depth."""
    cmd = command("square", speed=1.0, depth=2, side_span=4, direction="cw")
    p = plan(cmd, vehicle(0.0, 0.0, 20.0, 0.0, 1.0))
    ls = p.path.loop_start
    assert ls is not None
    assert all(z == pytest.approx(2.0, abs=TOL) for z in p.path.zs[ls:])
    _lap_closes(p.path)


@pytest.mark.parametrize("direction", DIRECTIONS)
@pytest.mark.parametrize("laps", [1, 3])
def test_box_orbit_half_width_is_the_radius(direction: str, laps: int) -> None:
    cmd = command("box_orbit", speed=0.4, depth=3, radius=6, direction=direction, laps=laps)
    half, speed = num(cmd, "radius"), num(cmd, "speed")
    p = plan(cmd, vehicle(1.0, 2.0, 3.0, 200.0, 0.4))
    path = p.path
    ax, ay = p.anchor
    assert (ax, ay) == (1.0, 2.0)
    bs = path.body_start
    for i in range(bs, len(path)):
        assert max(abs(path.xs[i] - ax), abs(path.ys[i] - ay)) == pytest.approx(half, abs=TOL)
    corners = {(round(path.xs[i] - ax, 6), round(path.ys[i] - ay, 6)) for i in range(bs, len(path))}
    assert corners >= {(half, half), (half, -half), (-half, half), (-half, -half)}
    # laps orbits: the bearing sweeps laps full turns in the commanded sense, then holds
    assert path.loop_start is None
    b = unwrapped_bearings(p.anchor, path, bs, len(path) - 1)
    assert sense(cmd) * (b[-1] - b[0]) == pytest.approx(laps * 2 * math.pi, abs=1e-9)
    assert path.point(bs) == pytest.approx(path.point(len(path) - 1), abs=TOL)
    body_len = sum(horizontal(path, i) for i in range(bs, len(path) - 1))
    assert body_len == pytest.approx(laps * 8 * half, abs=1e-9)
    assert path.times[-1] - path.times[bs] == pytest.approx(laps * 8 * half / speed, rel=1e-9)
    assert path.marks[bs] == 0.0
    assert path.marks[-1] == pytest.approx(laps)


# --- circle ---------------------------------------------------------------------------------


@pytest.mark.parametrize("direction", DIRECTIONS)
@pytest.mark.parametrize("radius", [0.5, 5.0, 40.0])
def test_circle_points_are_on_the_circle(direction: str, radius: float) -> None:
    cmd = command("circle", speed=0.5, depth=3, radius=radius, direction=direction)
    r, speed = num(cmd, "radius"), num(cmd, "speed")
    p = plan(cmd, vehicle(-4.0, 7.0, 3.0, 300.0))
    path = p.path
    bs = path.body_start
    for i in range(bs, len(path)):
        assert dist(xy(path, i), p.anchor) == pytest.approx(r, rel=1e-9), i
        assert path.zs[i] == pytest.approx(num(cmd, "depth"), abs=TOL)
    # mark 0 of the body is at the plan's reference angle
    assert angle_diff_deg(
        math.degrees(bearing(p.anchor, *xy(path, bs))), p.angle_deg
    ) == pytest.approx(0.0, abs=1e-6)
    _lap_closes(path)
    ls = path.loop_start
    assert ls is not None
    b = unwrapped_bearings(p.anchor, path, bs, len(path) - 1)
    s = sense(cmd)
    assert all(s * (b[k + 1] - b[k]) > 0 for k in range(len(b) - 1)), "wrong turning sense"
    lap = unwrapped_bearings(p.anchor, path, ls, len(path) - 1)
    assert s * (lap[-1] - lap[0]) == pytest.approx(2 * math.pi, abs=1e-9)
    # one lap takes (polygon perimeter) / speed: a little under 2 pi r / speed
    lap_t = path.times[-1] - path.times[ls]
    assert 0.97 * 2 * math.pi * r / speed <= lap_t <= 2 * math.pi * r / speed + 1e-9
    _body_duration_flat(path, ls, len(path) - 1, speed)


@pytest.mark.parametrize(("direction", "east"), [("cw", 1.0), ("ccw", -1.0)])
def test_circle_sense_seen_from_above(direction: str, east: float) -> None:
    """cw seen from above: passing north of the anchor the vehicle heads east; ccw: west."""
    cmd = command("circle", speed=0.5, depth=2, radius=10, direction=direction)
    p = plan(cmd, vehicle(0.0, 0.0, 2.0, 0.0))
    path = p.path
    ls = path.loop_start
    assert ls is not None
    # the lap segment that crosses the anchor's north (y = 0, x > 0)
    crossing = [
        i
        for i in range(ls, len(path) - 1)
        if path.xs[i] > 0 and path.ys[i] * path.ys[i + 1] <= 0 and path.ys[i] != path.ys[i + 1]
    ]
    assert len(crossing) == 1
    i = crossing[0]
    assert east * (path.ys[i + 1] - path.ys[i]) > 0


def test_circle_ramp_ends_before_the_repeated_lap() -> None:
    """Circle far from the vehicle's depth: the repeated lap is flat at the commanded depth."""
    for z0 in (0.0, 6.0, 9.3, 12.7, 20.0):
        cmd = command("circle", speed=0.5, depth=3, radius=2, direction="ccw")
        p = plan(cmd, vehicle(0.0, 0.0, z0, 45.0))
        path = p.path
        ls = path.loop_start
        assert ls is not None
        assert all(z == pytest.approx(3.0, abs=TOL) for z in path.zs[ls:]), z0
        _lap_closes(path)


@settings(max_examples=150, deadline=None)
@given(
    name=st.sampled_from(["circle", "square", "helix"]),
    size=st.floats(0.5, 30.0),
    speed=st.floats(0.1, 2.5),
    depth=st.floats(0.0, 20.0),
    z0=st.floats(0.0, 20.0),
    heading=st.floats(0.0, 360.0, exclude_max=True),
)
def test_depth_ramp_is_done_when_the_pattern_proper_starts(
    name: str, size: float, speed: float, depth: float, z0: float, heading: float
) -> None:
    """Circle and square: the repeated lap is flat at the commanded depth and closes on
    itself; helix: the body starts at its start depth (it circles there until the ramp ends)."""
    if name == "circle":
        cmd = command(name, speed=speed, depth=depth, radius=size, direction="cw")
    elif name == "square":
        cmd = command(name, speed=speed, depth=depth, side_span=size, direction="ccw")
    else:
        cmd = command(
            name,
            speed=speed,
            start_depth=depth,
            end_depth=10,
            radius=size,
            turns=1,
            direction="cw",
        )
    target = num(cmd, "start_depth" if name == "helix" else "depth")
    path = plan(cmd, vehicle(0.0, 0.0, z0, heading, speed)).path
    if name == "helix":
        assert path.zs[path.body_start] == pytest.approx(target, abs=TOL)
        return
    _lap_closes(path)
    ls = path.loop_start
    assert ls is not None
    assert all(z == pytest.approx(target, abs=TOL) for z in path.zs[ls:])


# --- spiral ---------------------------------------------------------------------------------


SPIRALS = [
    (2.0, 10.0, 3),  # outward
    (10.0, 2.0, 3),  # inward
    (0.0, 6.0, 2),  # from the centre
    (6.0, 0.0, 2),  # into the centre
    (1.0, 30.0, 5),
]


@pytest.mark.parametrize("direction", DIRECTIONS)
@pytest.mark.parametrize(("r0", "r1", "loops"), SPIRALS)
def test_spiral_radii_and_loops(direction: str, r0: float, r1: float, loops: int) -> None:
    cmd = command(
        "spiral",
        speed=0.5,
        depth=4,
        initial_radius=r0,
        final_radius=r1,
        loops=loops,
        direction=direction,
    )
    r0, r1, loops = num(cmd, "initial_radius"), num(cmd, "final_radius"), int(num(cmd, "loops"))
    speed, s = num(cmd, "speed"), sense(cmd)
    p = plan(cmd, vehicle(3.0, 3.0, 4.0, 120.0))
    path = p.path
    bs = path.body_start
    assert dist(xy(path, bs), p.anchor) == pytest.approx(r0, abs=TOL)
    assert dist(xy(path, len(path) - 1), p.anchor) == pytest.approx(r1, abs=TOL)
    assert path.loop_start is None
    # every body point is on the Archimedean spiral r = r0 + (r1 - r0) theta / total, where
    # theta is the angle swept from the plan's reference bearing in the commanded sense
    # (followed point to point: no chord spans half a turn); the centre has no bearing
    thetas = swept_angles(p.anchor, path, bs, math.radians(p.angle_deg), s)
    total = loops * 2 * math.pi
    for i, theta in thetas:
        expect = r0 + (r1 - r0) * theta / total
        assert dist(xy(path, i), p.anchor) == pytest.approx(expect, abs=1e-9), i
    assert all(thetas[k + 1][1] > thetas[k][1] for k in range(len(thetas) - 1)), "wrong sense"
    assert thetas[0][1] == pytest.approx(0.0, abs=1e-9) or r0 == 0
    if r1 > 0:
        assert thetas[-1][1] == pytest.approx(total, abs=1e-9)
    else:
        assert total - math.pi / 4 - 1e-9 <= thetas[-1][1] < total
    # radius monotonic from r0 to r1, constant depth, time = length / speed
    radii = [dist(xy(path, i), p.anchor) for i in range(bs, len(path))]
    step = 1 if r1 > r0 else -1
    assert all(step * (radii[k + 1] - radii[k]) > 0 for k in range(len(radii) - 1))
    _body_duration_flat(path, bs, len(path) - 1, speed)


# --- helix ----------------------------------------------------------------------------------


HELICES = [
    (2.0, 4.0, 2.5, 3),
    (8.0, 2.0, 5.0, 2),  # rising
    (1.0, 9.0, 1.0, 1),  # steep: slower than the cruise speed
]


@pytest.mark.parametrize("direction", DIRECTIONS)
@pytest.mark.parametrize(("z0", "z1", "radius", "turns"), HELICES)
def test_helix_depths_turns_and_radius(
    direction: str, z0: float, z1: float, radius: float, turns: int
) -> None:
    cmd = command(
        "helix",
        speed=0.5,
        start_depth=z0,
        end_depth=z1,
        radius=radius,
        turns=turns,
        direction=direction,
    )
    z0, z1, r = num(cmd, "start_depth"), num(cmd, "end_depth"), num(cmd, "radius")
    speed, s = num(cmd, "speed"), sense(cmd)
    for vz in (z0, 12.0):  # at the start depth, and far below it
        p = plan(cmd, vehicle(-6.0, 2.0, vz, 45.0))
        path = p.path
        bs = path.body_start
        assert path.loop_start is None
        assert path.zs[bs] == pytest.approx(z0, abs=TOL), f"body starts off its depth from {vz}"
        assert path.zs[-1] == pytest.approx(z1, abs=TOL)
        for i in range(bs, len(path)):
            assert dist(xy(path, i), p.anchor) == pytest.approx(r, rel=1e-9), i
        b = unwrapped_bearings(p.anchor, path, bs, len(path) - 1)
        assert s * (b[-1] - b[0]) == pytest.approx(turns * 2 * math.pi, abs=1e-9)
        assert all(s * (b[k + 1] - b[k]) > 0 for k in range(len(b) - 1))
        # depth linear in the swept angle
        total = turns * 2 * math.pi
        for k, i in enumerate(range(bs, len(path))):
            expect = z0 + (z1 - z0) * s * (b[k] - b[0]) / total
            assert path.zs[i] == pytest.approx(expect, abs=1e-6), i
        # duration: the slower of horizontal length / speed and depth change / depth rate
        length = sum(horizontal(path, i) for i in range(bs, len(path) - 1))
        expect_t = max(length / speed, abs(z1 - z0) / DEPTH_RATE_MPS)
        assert path.times[-1] - path.times[bs] == pytest.approx(expect_t, rel=1e-9)


# --- lawnmower ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("heading", "length", "spacing", "laps"),
    [(0.0, 20.0, 5.0, 2), (90.0, 20.0, 5.0, 2), (37.5, 30.0, 3.0, 3), (270.0, 12.0, 4.0, 1)],
)
def test_lawnmower_lanes(heading: float, length: float, spacing: float, laps: int) -> None:
    cmd = command(
        "lawnmower", speed=0.5, depth=3, sweep_length=length, lane_spacing=spacing, laps=laps
    )
    length, spacing = num(cmd, "sweep_length"), num(cmd, "lane_spacing")
    n = 2 * int(num(cmd, "laps"))
    speed = num(cmd, "speed")
    x0, y0 = 4.0, -3.0
    p = plan(cmd, vehicle(x0, y0, 3.0, heading))
    path = p.path
    h = math.radians(heading)
    ux, uy = math.cos(h), math.sin(h)
    vx, vy = -uy, ux  # starboard of the heading (NED, seen from above)
    assert p.origin == (x0, y0)
    assert angle_diff_deg(p.angle_deg, heading) < 1e-9
    legs = straight_legs(path, path.body_start)
    lanes = legs[0::2]
    steps = legs[1::2]
    assert len(lanes) == n
    assert len(steps) == n - 1
    offsets = []
    for k, (a, b) in enumerate(lanes):
        along_a = (a[0] - x0) * ux + (a[1] - y0) * uy
        along_b = (b[0] - x0) * ux + (b[1] - y0) * uy
        cross_a = (a[0] - x0) * vx + (a[1] - y0) * vy
        cross_b = (b[0] - x0) * vx + (b[1] - y0) * vy
        assert cross_a == pytest.approx(cross_b, abs=TOL)  # parallel to the heading
        assert abs(along_b - along_a) == pytest.approx(length, abs=TOL)
        # even lanes run along the heading, odd ones back
        assert (along_a, along_b) == pytest.approx(
            (0.0, length) if k % 2 == 0 else (length, 0.0), abs=TOL
        )
        offsets.append(cross_a)
    # lanes step to starboard by the lane spacing
    assert offsets == pytest.approx([k * spacing for k in range(n)], abs=TOL)
    assert p.lanes == pytest.approx(offsets, abs=TOL)
    for a, b in steps:
        assert dist(a, b) == pytest.approx(spacing, abs=TOL)
    # the anchor is the centre of the box
    mid = offsets[-1] / 2
    assert p.anchor == pytest.approx(
        (x0 + length / 2 * ux + mid * vx, y0 + length / 2 * uy + mid * vy), abs=TOL
    )
    # coverage: every point of the swept box is within half a spacing of a lane
    for i in range(21):
        for j in range(41):
            along = length * i / 20
            cross = offsets[-1] * j / 40
            nearest = min(abs(cross - o) for o in offsets)
            assert nearest <= spacing / 2 + TOL, (along, cross)
    # durations: each lane at the cruise speed
    _body_duration_flat(path, path.body_start, len(path) - 1, speed)
    assert path.times[-1] == pytest.approx((n * length + (n - 1) * spacing) / speed, rel=1e-9)


def test_lawnmower_coverage_from_the_path() -> None:
    """Grid of points in the box: each is within lane_spacing/2 of the flown lanes."""
    cmd = command("lawnmower", speed=0.5, depth=3, sweep_length=20, lane_spacing=5, laps=2)
    p = plan(cmd, vehicle(0.0, 0.0, 3.0, 60.0))
    path = p.path
    h = math.radians(60.0)
    ux, uy, vx, vy = math.cos(h), math.sin(h), -math.sin(h), math.cos(h)
    lanes = straight_legs(path, path.body_start)[0::2]
    width = 3 * 5.0
    for i in range(11):
        for j in range(16):
            a, c = 20.0 * i / 10, width * j / 15
            px, py = a * ux + c * vx, a * uy + c * vy
            best = math.inf
            for (ax, ay), (bx, by) in lanes:
                dx, dy = bx - ax, by - ay
                f = min(1.0, max(0.0, ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy)))
                best = min(best, math.hypot(ax + f * dx - px, ay + f * dy - py))
            assert best <= 2.5 + TOL, (a, c)


def test_lawnmower_depth_ramp_slows_nothing() -> None:
    """A lawnmower entered 1 m off its depth ramps at the depth rate along the first lane."""
    cmd = command("lawnmower", speed=0.5, depth=3, sweep_length=20, lane_spacing=5, laps=1)
    p = plan(cmd, vehicle(0.0, 0.0, 2.0, 0.0))
    path = p.path
    # the ramp needs 20 s, i.e. 10 m of lane: a waypoint where it meets the lane's depth
    k = next(i for i in range(len(path)) if path.zs[i] == pytest.approx(3.0, abs=TOL))
    assert path.times[k] == pytest.approx(1.0 / DEPTH_RATE_MPS, rel=1e-9)
    assert xy(path, k) == pytest.approx((10.0, 0.0), abs=TOL)
    assert path.times[-1] == pytest.approx((40 + 5) / 0.5, rel=1e-9)


# --- hover, surface, straight ---------------------------------------------------------------


@pytest.mark.parametrize("vz", [3.0, 1.0, 8.0])
def test_hover_holds_position_and_heading(vz: float) -> None:
    cmd = command("hover", duration=90, depth=3, heading=135)
    duration, depth, heading = num(cmd, "duration"), num(cmd, "depth"), num(cmd, "heading")
    p = plan(cmd, vehicle(2.0, -7.0, vz, 10.0))
    path = p.path
    assert p.origin == (2.0, -7.0)
    assert path.hold_heading_deg == heading
    assert all(x == 2.0 for x in path.xs)
    assert all(y == -7.0 for y in path.ys)
    assert path.zs[-1] == pytest.approx(depth, abs=TOL)
    assert path.times[-1] == pytest.approx(max(duration, abs(vz - depth) / DEPTH_RATE_MPS))
    for k in range(0, 201):
        sp = path.sample(duration * k / 200)
        assert (sp.x_m, sp.y_m) == (2.0, -7.0)
    end = path.sample(path.times[-1] + 5.0)
    assert end.z_m == pytest.approx(depth, abs=TOL)
    assert end.speed_mps == 0.0
    assert path.marks[-1] == pytest.approx(duration)


@pytest.mark.parametrize("vz", [0.0, 2.0, 37.5])
def test_surface_rises_in_place(vz: float) -> None:
    p = plan(command("surface"), vehicle(5.0, 6.0, vz, 77.0))
    path = p.path
    assert all(x == 5.0 for x in path.xs)
    assert all(y == 6.0 for y in path.ys)
    assert path.zs[0] == vz
    assert path.zs[-1] == 0.0
    assert path.times[-1] == pytest.approx(vz / HEAVE_CAPABILITY_MPS, rel=1e-9)
    assert path.hold_heading_deg == pytest.approx(77.0)
    for i in range(len(path) - 1):
        dt = path.times[i + 1] - path.times[i]
        assert abs(path.zs[i + 1] - path.zs[i]) / dt <= HEAVE_CAPABILITY_MPS + 1e-9
    assert p.anchor == (5.0, 6.0)


@pytest.mark.parametrize(("h0", "h1"), [(90.0, 180.0), (0.0, 0.0), (350.0, 10.5), (10.0, 190.5)])
def test_straight_runs_duration_on_heading(h0: float, h1: float) -> None:
    cmd = command("straight", speed=0.8, depth=2, duration=45, heading=h1)
    speed, duration, heading = num(cmd, "speed"), num(cmd, "duration"), num(cmd, "heading")
    p = plan(cmd, vehicle(1.0, 1.0, 2.0, h0, 0.8))
    path = p.path
    bs = path.body_start
    assert bs == len(path) - 2
    # the turn: on a circle of the turn radius, tangent to the start heading
    r = turn_radius_m(speed)
    for i in range(1, bs + 1):
        assert dist(xy(path, i), (1.0, 1.0)) <= 2 * r + TOL
    # the line: duration s at speed on the commanded heading
    assert (
        angle_diff_deg(
            math.degrees(math.atan2(path.ys[-1] - path.ys[bs], path.xs[-1] - path.xs[bs])), heading
        )
        < 1e-9
    )
    assert horizontal(path, bs) == pytest.approx(duration * speed, rel=1e-9)
    assert path.times[-1] - path.times[bs] == pytest.approx(duration, rel=1e-9)
    assert p.origin == pytest.approx(xy(path, bs))
    assert angle_diff_deg(p.angle_deg, heading) < 1e-9
    assert path.loop_start is None
    assert path.marks[-1] == pytest.approx(duration)
