"""Dead reckoning along a plan, and its uncertainty (hand-computed on a straight 0.5 m/s line
north and an L-shaped path at 1 m/s)."""

from __future__ import annotations

import math

import pytest

from backend.belief.reckoning import (
    CURRENT_MODEL_FRACTION,
    FIX_SIGMA_M,
    MODEL_ERROR_FRACTION,
    TURN_ERROR_M_PER_RAD,
    Current,
    Reckoned,
    off_path_m,
    plan_time_at,
    run_along,
    sigma_m,
    spread_m,
)
from codec import decode_frame, encode_frame
from planner import Path, Plan, VehicleState

STILL = Current(0.0, 0.0, 0.0, "none")
STRAIGHT = encode_frame("straight", speed=0.5, depth=2, duration=200, heading=0)
COMMAND = decode_frame(STRAIGHT.frame.bits).command


def plan_of(xs: tuple[float, ...], ys: tuple[float, ...], times: tuple[float, ...]) -> Plan:
    n = len(xs)
    legs = [math.hypot(xs[i + 1] - xs[i], ys[i + 1] - ys[i]) for i in range(n - 1)]
    speeds = (*(legs[i] / (times[i + 1] - times[i]) for i in range(n - 1)), 0.0)
    path = Path(xs, ys, (2.0,) * n, speeds, times, times)
    return Plan(COMMAND, path, (0.0, 0.0), (0.0, 0.0))


#: 100 m north at 0.5 m/s (200 s).
LINE = plan_of((0.0, 100.0), (0.0, 0.0), (0.0, 200.0))
#: 10 m north, then 10 m east, at 1 m/s.
ELL = plan_of((0.0, 10.0, 10.0), (0.0, 0.0, 10.0), (0.0, 10.0, 20.0))


def test_the_fix_is_placed_on_the_path() -> None:
    fix = VehicleState(7.0, 1.0, 2.0, t_s=50.0)
    tau = plan_time_at(LINE, fix)
    assert tau == pytest.approx(14.0)  # 7 m at 0.5 m/s
    assert off_path_m(LINE, fix, tau) == pytest.approx(1.0)


def test_run_along_a_line_without_current() -> None:
    run = run_along(LINE, 10.0, 20.0, STILL, t_s=100.0)
    assert run.state.x_m == pytest.approx(15.0)  # 5 m + 20 s at 0.5 m/s
    assert run.state.y_m == pytest.approx(0.0)
    assert run.distance_m == pytest.approx(10.0)
    assert run.state.t_s == pytest.approx(120.0)
    assert run.state.heading_deg == pytest.approx(0.0) and run.turned_rad == 0.0


def test_a_current_along_the_path_speeds_the_vehicle_up() -> None:
    run = run_along(LINE, 10.0, 20.0, Current(0.1, 0.0, 0.0, "along"))
    assert run.state.x_m == pytest.approx(5.0 + 20.0 * 0.6)
    assert run.distance_m == pytest.approx(12.0)


def test_a_current_across_the_path_is_crabbed_against() -> None:
    # 0.5 m/s through the water, 0.3 m/s across: sqrt(0.25 - 0.09) = 0.4 m/s along the path
    run = run_along(LINE, 10.0, 20.0, Current(0.0, 0.3, 0.0, "across"))
    assert run.state.x_m == pytest.approx(5.0 + 20.0 * 0.4)
    assert run.state.y_m == pytest.approx(0.0)


def test_a_finite_path_holds_its_end() -> None:
    run = run_along(LINE, 190.0, 100.0, STILL)
    assert run.state.x_m == pytest.approx(100.0) and run.state.speed_mps == 0.0
    assert run.distance_m == pytest.approx(5.0)


def test_a_corner_is_counted_as_a_sharp_turn() -> None:
    before = run_along(ELL, 0.0, 5.0, STILL)  # 5 m to go: the corner is not near yet
    assert before.turned_rad == 0.0
    near = run_along(ELL, 0.0, 9.0, STILL)  # 1 m before it: guidance starts turning
    assert near.turned_rad == pytest.approx(math.pi / 2)
    after = run_along(ELL, 0.0, 15.0, STILL)
    assert after.turned_rad == pytest.approx(math.pi / 2)
    assert (after.state.x_m, after.state.y_m) == pytest.approx((10.0, 5.0))


def test_sigma_adds_its_terms_in_quadrature_and_the_offset_in_full() -> None:
    run = Reckoned(VehicleState(0.0, 0.0, 2.0), 0.0, distance_m=10.0, turned_rad=0.0)
    current = Current(0.0, 0.0, 0.05, "assumed")
    expected = math.sqrt(FIX_SIGMA_M**2 + (MODEL_ERROR_FRACTION * 10.0) ** 2 + 0.5**2) + 1.0
    assert sigma_m(10.0, run, off_path=1.0, current=current) == pytest.approx(expected)
    # FIX 0.25, model 0.3, current 0.5: sqrt(0.0625 + 0.09 + 0.25) + 1 = 1.6344
    assert expected == pytest.approx(1.63443, abs=1e-5)


def test_sigma_grows_with_turns_a_known_current_and_an_unknown_plan() -> None:
    turned = Reckoned(VehicleState(0.0, 0.0, 2.0), 0.0, 0.0, turned_rad=math.pi)
    assert sigma_m(0.0, turned, current=STILL) == pytest.approx(
        math.hypot(FIX_SIGMA_M, TURN_ERROR_M_PER_RAD * math.pi)
    )
    flowing = Current(0.3, 0.4, 0.0, "known")  # 0.5 m/s
    assert sigma_m(10.0, None, current=flowing) == pytest.approx(
        math.hypot(FIX_SIGMA_M, CURRENT_MODEL_FRACTION * 0.5 * 10.0)
    )
    assert sigma_m(10.0, None, current=STILL, unknown_speed_mps=0.2) == pytest.approx(
        FIX_SIGMA_M + 2.0
    )


def test_the_spread_of_the_candidates() -> None:
    assert spread_m([(0.5, 3.0, 4.0)], 0.0, 0.0) == pytest.approx(math.sqrt(0.5 * 25.0))
    assert spread_m([(0.25, 6.0, 0.0), (0.25, 0.0, 8.0)], 0.0, 0.0) == pytest.approx(5.0)
    assert spread_m([], 1.0, 1.0) == 0.0
