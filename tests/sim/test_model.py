"""The Fossen 4-DOF vehicle model: calibration to the paper, thrusters, restoring, current."""

from __future__ import annotations

import itertools
import math
from dataclasses import fields, replace

import pytest

from sim.model import (
    G_MPS2,
    PAPER_HEAVE_MPS,
    PAPER_YAW_DPS,
    T200_REVERSE_RATIO,
    Vehicle,
    VehicleParams,
    calibrate,
    heave_test,
    yaw_test,
)

DT_S = 0.02


def _run(veh: Vehicle, seconds: float, dt_s: float = DT_S) -> None:
    for _ in range(round(seconds / dt_s)):
        veh.step(dt_s)


def _state(veh: Vehicle) -> tuple[float, ...]:
    return (
        veh.x,
        veh.y,
        veh.z,
        veh.phi,
        veh.psi,
        veh.u,
        veh.v,
        veh.w,
        veh.p,
        veh.r,
        *veh.thrusts,
    )


# --- calibration to the paper's full-thrust figures ------------------------------------------


def test_default_params_reproduce_the_papers_heave_rate() -> None:
    rate = heave_test(VehicleParams())
    assert rate == pytest.approx(PAPER_HEAVE_MPS, rel=0.01)
    assert PAPER_HEAVE_MPS == 0.0731


def test_default_params_reproduce_the_papers_yaw_rate() -> None:
    rate = yaw_test(VehicleParams())
    assert rate == pytest.approx(PAPER_YAW_DPS, rel=0.01)
    assert PAPER_YAW_DPS == 30.3


def test_calibration_is_about_one_and_a_half_percent_of_nameplate() -> None:
    """sim.md 2.4: about 0.8 N per thruster, far below the T200's 51.5 N."""
    q = VehicleParams()
    assert 0.7 < q.thrust_max_n < 0.9
    assert q.thrust_max_n / 51.5 < 0.02


def test_more_thrust_is_faster_and_more_yaw_damping_is_slower() -> None:
    """The monotonic relations calibrate() bisects on."""
    q = VehicleParams()
    assert (
        heave_test(replace(q, thrust_max_n=1.2))
        > heave_test(q)
        > heave_test(replace(q, thrust_max_n=0.6))
    )
    assert yaw_test(replace(q, nrr=0.2)) > yaw_test(q) > yaw_test(replace(q, nrr=0.8))


@pytest.mark.slow  # a calibration fit, ~1.5 s
def test_calibrate_from_wrong_starting_values_recovers_both_rates() -> None:
    wrong = replace(VehicleParams(), thrust_max_n=2.5, nrr=0.1)
    assert heave_test(wrong) > 2 * PAPER_HEAVE_MPS  # really wrong to start with
    assert yaw_test(wrong) > 3 * PAPER_YAW_DPS
    fitted = calibrate(wrong)
    assert heave_test(fitted) == pytest.approx(PAPER_HEAVE_MPS, rel=0.01)
    assert yaw_test(fitted) == pytest.approx(PAPER_YAW_DPS, rel=0.01)
    # only the two calibrated parameters move
    for f in fields(VehicleParams):
        if f.name not in ("thrust_max_n", "nrr"):
            assert getattr(fitted, f.name) == getattr(wrong, f.name), f.name
    # and they land on the shipped defaults
    assert fitted.thrust_max_n == pytest.approx(VehicleParams().thrust_max_n, rel=0.01)
    assert fitted.nrr == pytest.approx(VehicleParams().nrr, rel=0.02)


# --- thrusters: saturation and lag -----------------------------------------------------------


def test_reverse_limit_is_the_t200_ratio() -> None:
    q = VehicleParams()
    assert math.isclose(T200_REVERSE_RATIO, 40.2 / 51.5)
    assert q.thrust_min_n == pytest.approx(-T200_REVERSE_RATIO * q.thrust_max_n)
    assert q.thrust_min_n < 0 < q.thrust_max_n


def test_commands_beyond_the_limits_are_clipped() -> None:
    veh = Vehicle()
    q = veh.params
    veh.command(10.0, -10.0, 1e9, -1e9)
    assert veh.tc == (q.thrust_max_n, q.thrust_min_n, q.thrust_max_n, q.thrust_min_n)
    inside = (0.5 * q.thrust_max_n, 0.5 * q.thrust_min_n, 0.0, 0.1)
    veh.command(*inside)
    assert veh.tc == inside
    # the clipped command is what the thrusters converge to
    veh.command(10.0, -10.0, 10.0, -10.0)
    _run(veh, 2.0)
    hi, lo = q.thrust_max_n, q.thrust_min_n
    assert veh.thrusts == pytest.approx((hi, lo, hi, lo), rel=1e-6)


def test_nameplate_limit_is_configurable() -> None:
    veh = Vehicle(replace(VehicleParams(), thrust_max_n=51.5))
    veh.command(60.0, -60.0, 0.0, 0.0)
    assert veh.tc[0] == 51.5
    assert veh.tc[1] == pytest.approx(-40.2)


def test_first_order_lag_reaches_63_percent_after_tau() -> None:
    q = VehicleParams()
    veh = Vehicle(q, z_m=5.0)
    cmd = 0.5
    veh.command(cmd, cmd, -cmd, -cmd)
    veh.step(DT_S)
    assert 0.0 < veh.t1 < 0.2 * cmd  # no instant jump
    veh2 = Vehicle(q, z_m=5.0)
    veh2.command(cmd, cmd, -cmd, -cmd)
    _run(veh2, q.tau_thrust_s)
    expected = cmd * (1.0 - math.exp(-1.0))
    assert veh2.t1 == pytest.approx(expected, rel=1e-9)
    assert veh2.t3 == pytest.approx(-expected, rel=1e-9)
    _run(veh2, 5 * q.tau_thrust_s)
    assert veh2.t1 == pytest.approx(cmd, rel=0.01)


def test_lag_scales_with_tau() -> None:
    q = replace(VehicleParams(), tau_thrust_s=0.5)
    veh = Vehicle(q)
    veh.command(0.4, 0.0, 0.0, 0.0)
    _run(veh, 0.5)
    assert veh.t1 == pytest.approx(0.4 * (1.0 - math.exp(-1.0)), rel=1e-9)


# --- buoyancy and roll restoring -------------------------------------------------------------


def test_positively_buoyant_vehicle_rises_and_stops_at_the_surface() -> None:
    veh = Vehicle(z_m=1.0)
    depths = []
    for _ in range(round(40.0 / DT_S)):
        veh.step(DT_S)
        depths.append(veh.z)
        assert veh.z >= 0.0
    assert all(b <= a + 1e-12 for a, b in itertools.pairwise(depths))
    assert depths[0] < 1.0
    assert veh.z == 0.0
    assert veh.w == 0.0  # afloat: not rising out of the water
    _run(veh, 10.0)
    assert veh.z == 0.0


def test_terminal_ascent_rate_balances_buoyancy_and_heave_drag() -> None:
    q = VehicleParams()
    veh = Vehicle(q, z_m=20.0)
    _run(veh, 30.0)
    # (B - W) = Zw |w| + Zww w^2
    w_t = (-q.zw + math.sqrt(q.zw**2 + 4 * q.zww * q.buoyancy_margin_n)) / (2 * q.zww)
    assert veh.w == pytest.approx(-w_t, rel=1e-3)


def test_neutral_vehicle_stays_put() -> None:
    veh = Vehicle(replace(VehicleParams(), buoyancy_margin_n=0.0), z_m=3.0)
    _run(veh, 20.0)
    assert veh.z == 3.0


def test_roll_released_from_10_degrees_oscillates_with_a_3_s_period_and_decays() -> None:
    q = VehicleParams()
    dt = 0.01
    veh = Vehicle(q, z_m=5.0)
    veh.phi = math.radians(10.0)
    prev = veh.phi
    ups: list[float] = []
    peaks = [0.0] * 6
    for k in range(round(18.0 / dt)):
        veh.step(dt)
        t = (k + 1) * dt
        if prev < 0.0 <= veh.phi:
            ups.append(t - dt * veh.phi / (veh.phi - prev))
        prev = veh.phi
        window = min(5, int(t // 3.0))
        peaks[window] = max(peaks[window], abs(veh.phi))
    periods = [b - a for a, b in itertools.pairwise(ups)]
    assert len(periods) >= 4
    for period in periods:
        assert period == pytest.approx(3.0, abs=0.15)
    # the undamped estimate from GM: 2 pi sqrt((Ix + A44) / (W GM))
    natural = 2 * math.pi * math.sqrt((q.ix_kgm2 + q.a44_kgm2) / (q.weight_n * q.gm_m))
    assert natural == pytest.approx(3.0, abs=0.1)
    assert all(b < a for a, b in itertools.pairwise(peaks))
    assert peaks[-1] < 0.05 * math.radians(10.0)
    assert q.weight_n == pytest.approx(13.9 * G_MPS2)
    assert q.gm_m == 0.0065


# --- current ---------------------------------------------------------------------------------


def test_constant_current_carries_an_unpowered_vehicle_at_its_velocity() -> None:
    veh = Vehicle(z_m=5.0, heading_deg=37.0)
    veh.current_n, veh.current_e = 0.1, -0.05
    _run(veh, 20.0)
    assert veh.x == pytest.approx(2.0, abs=1e-9)
    assert veh.y == pytest.approx(-1.0, abs=1e-9)
    assert veh.ground_velocity == pytest.approx((0.1, -0.05), abs=1e-12)
    assert veh.speed_mps == 0.0  # no motion through the water
    assert veh.heading_deg == pytest.approx(37.0)


def test_current_adds_to_motion_through_the_water() -> None:
    still = Vehicle(z_m=5.0)
    drift = Vehicle(z_m=5.0)
    drift.current_e = 0.1
    for veh in (still, drift):
        for _ in range(round(30.0 / DT_S)):
            veh.command(0.3, 0.3, 0.0, 0.0)
            veh.step(DT_S)
    assert drift.x == pytest.approx(still.x, abs=1e-9)
    assert drift.y - still.y == pytest.approx(3.0, abs=1e-9)
    assert still.speed_mps > 0.05


# --- parameter validation --------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("mass_kg", 0.0),
        ("xu", -1.0),
        ("zww", math.nan),
        ("gm_m", math.inf),
        ("tau_thrust_s", 0.0),
        ("arm_h_m", 0.0),
        ("thrust_max_n", -0.1),
        ("iz_kgm2", 0.0),
    ],
)
def test_invalid_params_name_the_field(name: str, value: float) -> None:
    with pytest.raises(ValueError, match=name):
        replace(VehicleParams(), **{name: value})


def test_zero_is_allowed_for_damping_and_buoyancy() -> None:
    q = replace(VehicleParams(), buoyancy_margin_n=0.0, nrr=0.0, kpp=0.0)
    assert q.nrr == 0.0


# --- determinism -----------------------------------------------------------------------------


def _scripted_run() -> list[tuple[float, ...]]:
    veh = Vehicle(z_m=2.0, heading_deg=10.0)
    veh.current_n, veh.current_e = 0.02, 0.01
    out = []
    for k in range(1500):
        phase = k // 250
        veh.command(0.8 if phase % 2 else 0.2, 0.3, 0.5 - 0.2 * phase, 0.1 * phase)
        veh.step(DT_S)
        out.append(_state(veh))
    return out


def test_two_runs_are_identical() -> None:
    first = _scripted_run()
    second = _scripted_run()
    assert first == second
    assert first[0] != first[-1]  # it did move
