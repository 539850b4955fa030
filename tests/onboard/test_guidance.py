"""Guidance: LOS path following, station keeping and modes (mostly through Simulation)."""

from __future__ import annotations

import itertools
import math

import pytest

from codec import ParamValue, encode_frame
from onboard.guidance import AT_DEPTH_M, Guidance, GuidanceConfig
from planner import Plan, VehicleState, plan
from sim.environment import CurrentConfig
from sim.simulation import Sample, SimConfig, Simulation
from vehicle_contract.codes import Mode

RECORD_HZ = 10.0


def _sim(config: SimConfig | None = None) -> Simulation:
    return Simulation(config or SimConfig(record_hz=RECORD_HZ))


def _send(sim: Simulation, pattern: str, **params: ParamValue) -> None:
    sim.submit_frame(encode_frame(pattern, params).frame.to_bytes())


def _run(pattern: str, seconds: float, **params: ParamValue) -> Simulation:
    sim = _sim()
    _send(sim, pattern, **params)
    sim.advance(seconds)
    acks = sim.take_missions()
    assert [a["outcome"] for a in acks] == ["accepted"], acks
    return sim


def _mode(sim: Simulation) -> Mode:
    """The mode now (a call, so the type checker does not narrow it across steps)."""
    return sim.mode


def _g_mode(g: Guidance) -> Mode:
    """Guidance's mode now (a call: the type checker does not narrow it across updates)."""
    return g.mode


def _active(sim: Simulation) -> Plan:
    active = sim.agent.active
    assert active is not None
    return active


def _after_join(sim: Simulation, settle_s: float = 5.0) -> list[Sample]:
    """Samples from ``settle_s`` after guidance first tracks a segment past the entry point."""
    body = _active(sim).path.body_start
    t_join = next(s.t_s for s in sim.track if s.segment >= body + 1)
    out = [s for s in sim.track if s.t_s >= t_join + settle_s]
    assert len(out) > 100
    return out


def _rms(values: list[float]) -> float:
    return math.sqrt(sum(v * v for v in values) / len(values))


def _square_distance(dx: float, dy: float, half: float) -> float:
    """Distance from (dx, dy) to the perimeter of the square of half-width ``half`` at 0."""
    ax, ay = abs(dx), abs(dy)
    if ax <= half and ay <= half:
        return half - max(ax, ay)
    return math.hypot(max(ax - half, 0.0), max(ay - half, 0.0))


# --- path following --------------------------------------------------------------------------


CIRCLE_RADIUS_M = 3.0
SQUARE_SIDE_M = 4.0


@pytest.fixture(scope="module")
def circle_run() -> Simulation:
    """A circle at the paper's 0.18 m/s, three laps and a bit (shared: the tests only read)."""
    return _run("circle", 360.0, speed=0.18, depth=2, radius=CIRCLE_RADIUS_M, direction="cw")


@pytest.fixture(scope="module")
def square_run() -> Simulation:
    return _run("square", 330.0, speed=0.18, depth=2, side_span=SQUARE_SIDE_M, direction="ccw")


def test_circle_is_followed_with_small_cross_track(circle_run: Simulation) -> None:
    sim = circle_run
    radius = CIRCLE_RADIUS_M
    ax, ay = _active(sim).anchor
    samples = _after_join(sim)
    errors = [abs(math.hypot(s.x_m - ax, s.y_m - ay) - radius) for s in samples]
    assert _rms(errors) < 0.15
    assert max(errors) < 0.2
    # guidance's own cross-track agrees with the distance to the true circle (chords aside)
    for s, e in zip(samples, errors, strict=True):
        assert s.cross_track_m == pytest.approx(e, abs=0.06)
    # it circles clockwise seen from above (NED: north -> east -> south)
    bearings = [math.atan2(s.y_m - ay, s.x_m - ax) for s in samples]
    turned = sum(math.remainder(b - a, 2 * math.pi) for a, b in itertools.pairwise(bearings))
    assert turned > 2 * math.pi  # at least one full clockwise lap
    depths = [s.z_m for s in samples]
    assert max(abs(z - 2.0) for z in depths) < 0.03
    assert sim.mode is Mode.RUNNING


def test_square_is_followed_with_small_cross_track(square_run: Simulation) -> None:
    sim = square_run
    side = SQUARE_SIDE_M
    ax, ay = _active(sim).anchor
    samples = _after_join(sim)
    errors = [_square_distance(s.x_m - ax, s.y_m - ay, side / 2) for s in samples]
    assert _rms(errors) < 0.15
    assert max(errors) < 0.5  # the lookahead cuts the corners a little
    # away from the corners the sides are tracked closely
    mid_side = [
        e
        for s, e in zip(samples, errors, strict=True)
        if min(abs(abs(s.x_m - ax) - side / 2), abs(abs(s.y_m - ay) - side / 2)) < 0.5
        and min(abs(s.x_m - ax), abs(s.y_m - ay)) < side / 2 - 1.5
    ]
    assert len(mid_side) > 50
    assert max(mid_side) < 0.1
    # counter-clockwise seen from above
    bearings = [math.atan2(s.y_m - ay, s.x_m - ax) for s in samples]
    turned = sum(math.remainder(b - a, 2 * math.pi) for a, b in itertools.pairwise(bearings))
    assert turned < -2 * math.pi
    assert sim.mode is Mode.RUNNING


def test_lawnmower_reaches_every_lane_in_order_and_then_holds() -> None:
    sim = _run("lawnmower", 200.0, speed=0.2, depth=2, sweep_length=6, lane_spacing=2, laps=2)
    active = _active(sim)
    ox, oy = active.origin
    axis = math.radians(active.angle_deg)
    ux, uy = math.cos(axis), math.sin(axis)
    vx, vy = -uy, ux
    assert len(active.lanes) == 4
    times = []
    for offset in active.lanes:
        mx, my = ox + 3.0 * ux + offset * vx, oy + 3.0 * uy + offset * vy  # lane midpoint
        dist, t = min((math.hypot(s.x_m - mx, s.y_m - my), s.t_s) for s in sim.track)
        assert dist < 0.15, offset
        times.append(t)
    assert times == sorted(times)
    assert sim.mode is Mode.HOLDING
    path = active.path
    v = sim.vehicle
    assert math.hypot(v.x - path.xs[-1], v.y - path.ys[-1]) < sim.guidance.config.capture_m


@pytest.mark.parametrize(
    ("pattern", "params", "seconds"),
    [
        ("straight", {"speed": 0.3, "depth": 2, "duration": 30, "heading": 90}, 80.0),
        (
            "box_orbit",
            {"speed": 0.2, "depth": 2, "radius": 2, "direction": "ccw", "laps": 1},
            150.0,
        ),
    ],
)
def test_finite_pattern_ends_holding_at_its_last_waypoint(
    pattern: str, params: dict[str, ParamValue], seconds: float
) -> None:
    sim = _run(pattern, seconds, **params)
    path = _active(sim).path
    assert path.loop_start is None
    assert sim.mode is Mode.HOLDING
    hx, hy, hz, _ = sim.guidance.hold
    assert (hx, hy, hz) == (path.xs[-1], path.ys[-1], path.zs[-1])
    v = sim.vehicle
    assert math.hypot(v.x - hx, v.y - hy) < sim.guidance.config.capture_m
    assert v.z == pytest.approx(hz, abs=0.05)
    # and it stays there
    sim.advance(60.0)
    assert sim.mode is Mode.HOLDING
    assert math.hypot(v.x - hx, v.y - hy) < sim.guidance.config.capture_m
    # it was running before it held
    modes = [s.mode for s in sim.track if s.t_s >= 1.0]
    assert modes[0] == "running"
    first_hold = modes.index("holding")
    assert set(modes[first_hold:]) == {"holding"}


def test_finite_path_ending_in_a_depth_ramp_finishes_at_the_commanded_depth() -> None:
    # 10 s at 0.3 m/s is 3 m of line; 1 m of depth at 0.05 m/s takes 20 s: the planner
    # finishes the ramp in place with a vertical last segment
    sim = _run("straight", 150.0, speed=0.3, depth=3, duration=10, heading=0)
    path = _active(sim).path
    assert (path.xs[-1], path.ys[-1]) == (path.xs[-2], path.ys[-2])
    assert path.zs[-1] == pytest.approx(3.0)
    assert sim.mode is Mode.HOLDING
    assert sim.vehicle.z == pytest.approx(3.0, abs=0.05)


# --- repeating patterns and the window search ------------------------------------------------


@pytest.mark.parametrize("run", ["square_run", "circle_run"])
def test_repeating_patterns_wrap_and_keep_running(run: str, request: pytest.FixtureRequest) -> None:
    sim: Simulation = request.getfixturevalue(run)
    path = _active(sim).path
    loop = path.loop_start
    assert loop is not None
    assert sim.mode is Mode.RUNNING
    segments = [s.segment for s in sim.track]
    # the index only ever falls at a wrap, from the end of the lap back to its start: within
    # a lap it only grows
    wraps = [(a, b) for a, b in itertools.pairwise(segments) if b < a]
    assert len(wraps) >= 3  # several laps
    for before, after in wraps:
        assert before >= len(path) - 3
        assert loop <= after <= loop + 1
    assert {s.mode for s in sim.track if s.t_s >= 1.0} == {"running"}


def test_segment_index_never_jumps_back_on_a_multi_lap_orbit() -> None:
    """A box orbit passes the same places on every lap: the window search stays on the
    current lap, so the segment index only grows."""
    sim = _run("box_orbit", 320.0, speed=0.2, depth=2, radius=2, direction="cw", laps=3)
    path = _active(sim).path
    segments = [s.segment for s in sim.track if s.mode == "running"]
    assert all(b >= a for a, b in itertools.pairwise(segments))
    assert segments[-1] >= len(path) - 3  # it got to the last lap
    assert sim.mode is Mode.HOLDING


def _box_orbit_plan(laps: int) -> Plan:
    cmd = encode_frame("box_orbit", speed=0.2, depth=2, radius=2, direction="cw", laps=laps).command
    return plan(cmd, VehicleState(0.0, 0.0, 2.0, 0.0))


def test_guidance_stays_on_the_later_pass_of_the_same_place() -> None:
    p = _box_orbit_plan(2)
    path = p.path
    g = Guidance()
    g.set_plan(p, 0.0)
    body = path.body_start
    # the same corner appears on both laps
    corner = (path.xs[body + 1], path.ys[body + 1])
    lap2 = next(j for j in range(body + 2, len(path)) if (path.xs[j], path.ys[j]) == corner)
    assert lap2 > body + 4
    # walk the vehicle along the path up to lap 2, then sit on that corner
    for i in range(lap2 + 1):
        g.update(path.xs[i], path.ys[i], path.zs[i], float(i))
    reached = g.segment
    assert reached >= lap2 - 1
    for k in range(20):
        g.update(path.xs[lap2], path.ys[lap2], path.zs[lap2], 100.0 + k)
        assert g.segment >= reached
    assert g.mode is Mode.RUNNING


def test_cutting_a_corner_moves_on_to_the_next_segment() -> None:
    p = _box_orbit_plan(1)
    path = p.path
    g = Guidance()
    g.set_plan(p, 0.0)
    body = path.body_start
    for i in range(body + 1):
        g.update(path.xs[i], path.ys[i], path.zs[i], float(i))
    # halfway along the first side of the pattern
    mid_x = (path.xs[body] + path.xs[body + 1]) / 2
    mid_y = (path.ys[body] + path.ys[body + 1]) / 2
    g.update(mid_x, mid_y, 2.0, 10.0)
    corner = body + 1
    assert g.segment == body
    # inside the corner, nearer the next side than the current one
    cx, cy = path.xs[corner], path.ys[corner]
    nx, ny = path.xs[corner + 1], path.ys[corner + 1]
    px, py = path.xs[corner - 1], path.ys[corner - 1]
    x = cx + 0.3 * (nx - cx) / math.hypot(nx - cx, ny - cy) + 0.1 * (px - cx)
    y = cy + 0.3 * (ny - cy) / math.hypot(nx - cx, ny - cy) + 0.1 * (py - cy)
    g.update(x, y, 2.0, 50.0)
    assert g.segment == corner
    assert g.cross_track_m == pytest.approx(0.2)


# --- station keeping and modes ---------------------------------------------------------------


def test_idle_vehicle_holds_its_start_pose() -> None:
    sim = Simulation(SimConfig(start_x_m=3.0, start_y_m=-2.0, start_z_m=1.5, start_heading_deg=45))
    sim.advance(60.0)
    assert sim.mode is Mode.IDLE
    v = sim.vehicle
    assert math.hypot(v.x - 3.0, v.y + 2.0) < 0.05
    assert v.z == pytest.approx(1.5, abs=0.03)
    assert v.heading_deg == pytest.approx(45.0, abs=1.0)


def test_hover_returns_within_capture_and_holds_heading_against_a_current() -> None:
    cfg = SimConfig(
        record_hz=RECORD_HZ,
        current=CurrentConfig(east_mps=0.03, direction_sigma_deg=10.0, time_constant_s=60.0),
    )
    sim = _sim(cfg)
    _send(sim, "hover", duration=600, depth=2, heading=90)
    gcfg = sim.guidance.config
    max_dist = 0.0
    approaches = 0
    last_approach_s = 0.0  # the turn to the commanded heading counts as an approach
    settled_errors: list[float] = []
    was_approaching = False
    sim.advance(1.0)
    hold_x, hold_y, _, hdg = sim.guidance.hold
    assert math.degrees(hdg) == pytest.approx(90.0)
    assert math.hypot(hold_x, hold_y) < 0.01
    while sim.t_s < 300.0:
        sim.advance(0.1)
        v = sim.vehicle
        dist = math.hypot(v.x - hold_x, v.y - hold_y)
        max_dist = max(max_dist, dist)
        approaching = sim.ref.speed_mps > 0.0  # station keeping moves only to approach
        if approaching:
            last_approach_s = sim.t_s
            approaches += not was_approaching
        elif sim.t_s - last_approach_s > 15.0:
            settled_errors.append(abs(math.remainder(v.heading_deg - 90.0, 360.0)))
        was_approaching = approaching
        assert abs(v.z - 2.0) < 0.05
    assert sim.mode is Mode.RUNNING  # the hover lasts 600 s
    assert approaches >= 3  # the current pushed it out of the capture radius again and again
    assert gcfg.capture_m < max_dist < gcfg.capture_m + 0.4  # and it always came back
    assert len(settled_errors) > 600
    assert max(settled_errors) < 3.0


def test_hover_ends_in_holding_after_its_duration() -> None:
    sim = _run("hover", 40.0, duration=30, depth=2, heading=0)
    assert sim.mode is Mode.HOLDING
    first_hold = next(s.t_s for s in sim.track if s.mode == "holding")
    assert first_hold == pytest.approx(30.0, abs=0.3)


def test_surface_rises_then_floats_with_vertical_thrusters_off() -> None:
    sim = _sim()
    _send(sim, "circle", speed=0.2, depth=2, radius=3, direction="cw")
    sim.advance(20.0)
    assert _mode(sim) is Mode.RUNNING
    _send(sim, "surface")
    sim.advance(0.2)
    assert _mode(sim) is Mode.SURFACING
    seen: list[Mode] = []
    powered = False
    while sim.t_s < 80.0:
        sim.advance(0.1)
        if not seen or seen[-1] is not sim.mode:
            seen.append(sim.mode)
        if _mode(sim) is Mode.SURFACING:
            powered |= sim.vehicle.tc[2] < 0.0 and sim.vehicle.tc[3] < 0.0  # pushing up
    assert seen == [Mode.SURFACING, Mode.SURFACED]
    assert powered
    v = sim.vehicle
    assert v.z == pytest.approx(0.0, abs=0.01)
    assert sim.depth_m <= sim.guidance.config.surfaced_depth_m
    assert v.tc[2:] == (0.0, 0.0)
    assert sim.ref.vertical is False
    assert sim.ref.speed_mps == 0.0
    # it stays surfaced and does not wander off
    x, y = v.x, v.y
    sim.advance(30.0)
    assert _mode(sim) is Mode.SURFACED
    assert math.hypot(v.x - x, v.y - y) < 0.3


def test_guidance_config_is_used() -> None:
    g = Guidance(GuidanceConfig(capture_m=2.0, settle_m=0.5))
    g.hold_here(0.0, 0.0, 1.0, 90.0)
    ref = g.update(1.5, 0.0, 1.0, 0.0)  # inside 2 m capture: hold the heading
    assert ref.speed_mps == 0.0
    assert ref.course_rad == pytest.approx(math.pi / 2)
    ref = g.update(3.0, 0.0, 1.0, 1.0)  # beyond capture: face the point and approach
    assert ref.speed_mps > 0.0
    assert ref.course_rad == pytest.approx(math.pi)
    ref = g.update(1.0, 0.0, 1.0, 2.0)  # hysteresis: still approaching until settle
    assert ref.speed_mps > 0.0
    ref = g.update(0.4, 0.0, 1.0, 3.0)
    assert ref.speed_mps == 0.0
    assert ref.depth_m == 1.0
    assert g.mode is Mode.IDLE


# --- holding means done: at the path's end *and* its depth (issue 20) ------------------------


def test_the_path_end_above_its_depth_is_running_until_the_depth_is_reached() -> None:
    """The straight's ramp outlasts its 3 m of line: guidance reaches the horizontal end with
    the vehicle well above the commanded depth and flies the rest in place. The mode (what
    the status reports) stays ``running`` until the vehicle is at the depth, then
    ``holding``: never holding short of it, as it was (7 m short, issue 20)."""
    sim = _run("straight", 250.0, speed=0.3, depth=6, duration=10, heading=0)
    path = _active(sim).path
    end = (path.xs[-1], path.ys[-1])
    assert path.zs[-1] == pytest.approx(6.0) and (path.xs[-2], path.ys[-2]) == end
    capture = sim.guidance.config.capture_m
    at_end = [s for s in sim.track if math.hypot(s.x_m - end[0], s.y_m - end[1]) < capture]
    short = [s for s in at_end if s.z_m < 6.0 - 1.0]
    assert short, "the vehicle reached the line's end well above its depth"
    assert {s.mode for s in short} == {"running"}
    holding = [s for s in sim.track if s.mode == "holding"]
    assert holding and sim.mode is Mode.HOLDING
    # holding only at the depth (the sensor's reading within AT_DEPTH_M; the true depth a
    # little more, for the sensor's noise)
    assert all(abs(s.z_m - 6.0) <= AT_DEPTH_M + 0.03 for s in holding)
    first = holding[0].t_s
    assert all(s.mode == "running" for s in sim.track if 1.0 <= s.t_s < first)
    # the simulator's completion reads the same mode: done when it first held
    assert sim.completion.done_s == pytest.approx(first, abs=1.0 / RECORD_HZ)


def test_guidance_holds_the_end_in_running_until_at_depth() -> None:
    """Guidance alone: at the path's horizontal end it keeps station (the hold point and the
    path's last depth as its references), ``running``, until the depth is within
    :data:`AT_DEPTH_M`; a hover likewise after its time."""
    cmd = encode_frame("straight", speed=0.3, depth=6, duration=10, heading=0).command
    p = plan(cmd, VehicleState(0.0, 0.0, 2.0, 0.0))
    g = Guidance()
    g.set_plan(p, 0.0)
    path = p.path
    for i in range(len(path)):
        g.update(path.xs[i], path.ys[i], 3.0, float(i))
    ref = g.update(path.xs[-1], path.ys[-1], 3.0, 20.0)
    assert g.at_end and _g_mode(g) is Mode.RUNNING
    assert ref.speed_mps == 0.0 and ref.depth_m == pytest.approx(6.0)
    assert g.hold[:3] == (path.xs[-1], path.ys[-1], path.zs[-1])
    g.update(path.xs[-1], path.ys[-1], 6.0 - 1.5 * AT_DEPTH_M, 60.0)
    assert _g_mode(g) is Mode.RUNNING
    g.update(path.xs[-1], path.ys[-1], 6.0 - 0.5 * AT_DEPTH_M, 80.0)
    assert _g_mode(g) is Mode.HOLDING
    hover = plan(
        encode_frame("hover", duration=10, depth=4, heading=0).command,
        VehicleState(0.0, 0.0, 2.0, 0.0),
    )
    g.set_plan(hover, 100.0)
    assert not g.at_end
    up_s = 100.0 + hover.path.duration_s  # its duration, or the planner's descent if longer
    g.update(0.0, 0.0, 2.5, up_s - 1.0)
    assert _g_mode(g) is Mode.RUNNING and not g.at_end  # its time is not up
    g.update(0.0, 0.0, 2.5, up_s)
    assert _g_mode(g) is Mode.RUNNING and g.at_end  # up, but 1.5 m short of its depth
    g.update(0.0, 0.0, 4.0, up_s + 30.0)
    assert _g_mode(g) is Mode.HOLDING
