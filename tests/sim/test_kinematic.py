"""The kinematic twin (sim/kinematic.py) and the completion rule it shares with the simulator
(sim/completion.py): done at the path's end and depth, or after the join and one lap."""

from __future__ import annotations

import math
from itertools import pairwise

import pytest

from codec import DICTIONARY, decode_frame, encode_frame
from onboard.guidance import Guidance
from planner import DEPTH_RATE_MPS, Plan, VehicleState, plan
from sim.completion import AT_DEPTH_M, Completion
from sim.kinematic import Rates, fly
from sim.simulation import SimConfig, Simulation
from vehicle_contract.codes import Mode

TOP, DOWN, UP = 0.19, 0.073, 0.11
TWIN = Rates(TOP, DOWN, UP)
AT_2M = VehicleState(0.0, 0.0, 2.0)


def planned(pattern: str, state: VehicleState = AT_2M, **params: float | str) -> Plan:
    values = {**DICTIONARY[pattern].defaults, **params}
    return plan(decode_frame(encode_frame(pattern, values).frame.bits).command, state)


def test_a_level_straight_takes_its_duration() -> None:
    p = planned("straight", speed=0.15, depth=2, duration=60, heading=0)
    f = fly(p, TWIN)
    assert f.done_s == pytest.approx(60.0, abs=0.5)
    assert f.length_m == pytest.approx(9.0, abs=0.1)
    assert f.depth_wait_s == 0.0 and f.turning_s == pytest.approx(0.0, abs=1e-6)


def test_a_straight_too_fast_is_flown_at_the_top_speed() -> None:
    p = planned("straight", speed=0.8, depth=2, duration=60, heading=0)
    assert fly(p, TWIN).done_s == pytest.approx(60 * 0.8 / TOP, rel=0.01)
    assert fly(p, Rates()).done_s == pytest.approx(60.0, abs=0.5)  # unknown: as commanded


@pytest.mark.parametrize(("z0", "rate"), [(2.0, DOWN), (12.0, UP)])
def test_the_depth_left_for_the_end_is_flown_in_place_at_the_vehicles_rate(
    z0: float, rate: float
) -> None:
    """The plan ramps 0.05 m/s while it moves (3 m over 60 s) and finishes the ramp in place;
    guidance gives the depth as a step there, flown at the descent or the ascent rate."""
    p = planned("straight", VehicleState(0.0, 0.0, z0), speed=0.15, depth=7, duration=60)
    left = abs(7.0 - z0) - 60 * DEPTH_RATE_MPS
    assert p.path.duration_s == pytest.approx(60 + left / DEPTH_RATE_MPS)
    f = fly(p, TWIN)
    assert f.done_s is not None
    assert f.depth_wait_s == pytest.approx((left - AT_DEPTH_M) / rate, abs=0.6)
    assert f.done_s == pytest.approx(60 + (left - AT_DEPTH_M) / rate, abs=1.0)
    # unknown rates: the path's own in-place rate, as planned
    assert fly(p, Rates()).done_s == pytest.approx(p.path.duration_s, abs=3.0)


def test_a_hover_ends_on_guidances_clock() -> None:
    """Guidance holds a hover for its plan's duration: its ``duration``, or the plan's own
    approach when that is longer (10 m at the planner's 0.05 m/s: 200 s, though the vehicle
    is there after ~136 s)."""
    short = planned("hover", duration=60, depth=3, heading=90)
    assert fly(short, TWIN).done_s == pytest.approx(60.0, abs=0.2)
    deep = planned("hover", duration=60, depth=12, heading=90)
    assert deep.path.duration_s == pytest.approx(200.0)
    assert fly(deep, TWIN).done_s == pytest.approx(200.0, abs=0.2)


def test_a_small_square_is_flown_inside_its_corners() -> None:
    p = planned("square", speed=0.15, depth=2, side_span=2, direction="cw")
    f = fly(p, TWIN)
    assert f.done_s is not None and f.done_s < 0.85 * p.path.duration_s
    assert f.turning_s > 0


@pytest.mark.parametrize("name", [n for n in DICTIONARY if n != "surface"])
def test_the_times_cover_every_waypoint_in_order(name: str) -> None:
    speed = {"speed": 0.15} if any(f.name == "speed" for f in DICTIONARY[name].fields) else {}
    p = planned(name, VehicleState(3.0, -2.0, 4.0, 45.0), **speed)
    f = fly(p, TWIN)
    assert f.done_s is not None and len(f.times) == len(p.path)
    assert f.times[0] == 0.0 and f.times[-1] == pytest.approx(f.done_s)
    assert all(b >= a - 1e-9 for a, b in pairwise(f.times))


def test_surface_is_done_at_the_surface_at_the_ascent_rate() -> None:
    p = planned("surface", VehicleState(0.0, 0.0, 5.0))
    f = fly(p, TWIN)
    assert f.done_s == pytest.approx((5.0 - 0.05) / UP, abs=1.0)  # surfaced at 5 cm


# --- the completion rule ------------------------------------------------------------------


def _mode(g: Guidance) -> Mode:
    """Guidance's mode now (a call: the type checker does not narrow it across updates)."""
    return g.mode


def test_holding_is_not_done_until_the_depth_is_reached() -> None:
    """Guidance reports ``holding`` (done) only at the held depth: at the horizontal end it
    keeps station, ``running``, while the depth change left for the end is flown; completion
    reads guidance's mode, as the console reads the vehicle's status."""
    g = Guidance()
    p = planned("straight", speed=0.15, depth=7, duration=10, heading=0)
    g.set_plan(p, 0.0)
    c = Completion()
    end = (p.path.xs[-1], p.path.ys[-1])
    g.update(*end, 2.5, 60.0)  # at the horizontal end, 4.5 m short of the depth
    assert _mode(g) is Mode.RUNNING and g.at_end
    assert c.update(g, 60.0) is None
    g.update(*end, 7.0 - 2 * AT_DEPTH_M, 110.0)  # still short of it
    assert _mode(g) is Mode.RUNNING and c.update(g, 110.0) is None
    g.update(*end, 7.0 - AT_DEPTH_M / 2, 120.0)
    assert _mode(g) is Mode.HOLDING
    assert c.update(g, 120.0) == 120.0
    g.update(*end, 6.5, 130.0)  # done is done: a depth excursion later does not undo it
    assert _mode(g) is Mode.HOLDING and c.update(g, 130.0) == 120.0  # the first time stays
    g.set_plan(planned("hover", duration=5, depth=7, heading=0), 130.0)
    assert c.update(g, 130.5) is None and c.plan is g.plan  # a new plan: afresh


def test_a_repeating_pattern_is_done_with_the_join_and_one_lap_in_the_simulator() -> None:
    sim = Simulation(SimConfig())
    p = planned("circle", speed=0.18, depth=2, radius=5, direction="cw")
    sim.submit_frame(encode_frame("circle", p.command.params).frame.to_bytes())
    sim.run_until(0.5 * p.path.duration_s)
    assert sim.completion.done_s is None and sim.mode is Mode.RUNNING
    sim.run_until(1.2 * p.path.duration_s)
    done = sim.completion.done_s
    assert done is not None and done == pytest.approx(p.path.duration_s, rel=0.1)
    # it flies on: a repeating pattern never holds
    assert sim.mode is Mode.RUNNING and math.isfinite(done)
