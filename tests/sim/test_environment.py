"""Current, Bar30 depth sensor and battery of the simulated vehicle."""

from __future__ import annotations

import math
import statistics

import pytest

from sim.environment import (
    HOTEL_POWER_W,
    NOMINAL_THRUST_POWER_W,
    NOMINAL_THRUSTS_N,
    PAPER_SOC_TABLE,
    THRUST_POWER_COEFF_W_PER_N1_5,
    Battery,
    BatteryConfig,
    Current,
    CurrentConfig,
    DepthSensor,
    DepthSensorConfig,
    paper_soc_pct,
    thrust_power_w,
)

# --- battery ---------------------------------------------------------------------------------


@pytest.mark.parametrize("dt_s", [1.0, 60.0])
def test_battery_reproduces_the_papers_table_at_nominal_load(dt_s: float) -> None:
    battery = Battery()
    assert battery.soc_pct == 100.0
    steps_per_hour = round(3600 / dt_s)
    previous = battery.soc_pct
    for hour, table_pct in PAPER_SOC_TABLE[1:]:
        for _ in range(steps_per_hour):
            soc = battery.step(dt_s, NOMINAL_THRUST_POWER_W)
            assert soc <= previous  # never charges
            previous = soc
        assert battery.elapsed_s == pytest.approx(hour * 3600.0)
        assert abs(battery.soc_pct - table_pct) <= 0.5, (hour, battery.soc_pct)
        assert battery.soc_pct == pytest.approx(paper_soc_pct(hour), abs=1e-9)
        assert battery.load_hours == pytest.approx(hour)


def test_the_fit_matches_the_table() -> None:
    for hour, table_pct in PAPER_SOC_TABLE:
        assert abs(paper_soc_pct(hour) - table_pct) <= 0.5


def test_stepping_is_exact_for_piecewise_constant_load() -> None:
    """The fast term is evaluated in closed form: coarse and fine steps agree."""
    coarse = Battery()
    fine = Battery()
    for power_w in (0.0, 30.0, NOMINAL_THRUST_POWER_W):
        for _ in range(30):
            coarse.step(60.0, power_w)
        for _ in range(1800):
            fine.step(1.0, power_w)
    assert coarse.soc_pct == pytest.approx(fine.soc_pct, abs=1e-9)


def test_higher_load_drains_faster_by_the_power_ratio() -> None:
    nominal_total_w = HOTEL_POWER_W + NOMINAL_THRUST_POWER_W
    socs = {}
    for power_w in (0.0, NOMINAL_THRUST_POWER_W, 4 * NOMINAL_THRUST_POWER_W, 100.0):
        battery = Battery()
        for _ in range(60):
            battery.step(60.0, power_w)
        socs[power_w] = battery.soc_pct
        factor = (HOTEL_POWER_W + power_w) / nominal_total_w
        expected = 100.0 - 9.23 * factor - 32.0 * (1.0 - math.exp(-1.0 / 1.03))
        assert battery.soc_pct == pytest.approx(expected, abs=1e-9)
    values = list(socs.values())
    assert values == sorted(values, reverse=True)
    assert socs[0.0] > socs[NOMINAL_THRUST_POWER_W] + 2.0  # hovering idle saves >2 pp per hour


def test_battery_flags_and_floor() -> None:
    battery = Battery()
    hours = 0.0
    seen_low_at = seen_empty_at = None
    while hours < 10.0:
        battery.step(60.0, NOMINAL_THRUST_POWER_W)
        hours += 1 / 60
        assert 0.0 <= battery.soc_pct <= 100.0
        assert battery.low == (battery.soc_pct <= 20.0)
        assert battery.empty == (battery.soc_pct <= 0.0)
        if battery.low and seen_low_at is None:
            seen_low_at = hours
        if battery.empty and seen_empty_at is None:
            seen_empty_at = hours
    assert seen_low_at is not None and 5.0 < seen_low_at < 5.5  # 22 % at 5 h
    assert seen_empty_at is not None and 7.0 < seen_empty_at < 7.8  # fit reaches 0 at ~7.4 h
    assert battery.soc_pct == 0.0
    assert battery.step(3600.0, 100.0) == 0.0  # stays at the floor


def test_cutoff_and_reserve_are_configurable() -> None:
    battery = Battery(BatteryConfig(cutoff_pct=35.0, reserve_pct=50.0))
    for _ in range(3 * 60):
        battery.step(60.0, NOMINAL_THRUST_POWER_W)
    assert battery.low and not battery.empty  # 42 % at 3 h
    for _ in range(60):
        battery.step(60.0, NOMINAL_THRUST_POWER_W)
    assert battery.empty  # 31.7 % at 4 h
    battery.set_config(BatteryConfig())
    assert not battery.empty and not battery.low


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"hotel_power_w": 0.0}, "hotel_power_w"),
        ({"hotel_power_w": math.inf}, "hotel_power_w"),
        ({"nominal_thrust_power_w": -1.0}, "nominal_thrust_power_w"),
        ({"nominal_thrust_power_w": math.inf}, "nominal_thrust_power_w"),
        ({"reserve_pct": 101.0}, "reserve_pct"),
        ({"cutoff_pct": 25.0}, "cutoff_pct"),  # above the default 20 % reserve
        ({"cutoff_pct": -1.0}, "cutoff_pct"),
        ({"cutoff_pct": math.nan}, "cutoff_pct"),
    ],
)
def test_battery_config_validation(kwargs: dict[str, float], field: str) -> None:
    with pytest.raises(ValueError, match=field):
        BatteryConfig(**kwargs)


def test_battery_step_arguments() -> None:
    battery = Battery()
    assert battery.step(0.0, 10.0) == 100.0
    with pytest.raises(ValueError, match="dt_s"):
        battery.step(-1.0, 0.0)
    with pytest.raises(ValueError, match="thrust_power_w"):
        battery.step(1.0, -0.1)
    with pytest.raises(ValueError, match="thrust_power_w"):
        battery.step(1.0, math.nan)


def test_thrust_power() -> None:
    one = thrust_power_w([0.8])
    assert 1.0 < one < 5.0  # a few watts per T200 at the calibrated thrust
    assert one == pytest.approx(THRUST_POWER_COEFF_W_PER_N1_5 * 0.8**1.5)
    assert thrust_power_w([-0.8]) == one  # reverse thrust costs the same
    assert thrust_power_w([1.6]) == pytest.approx(one * 2**1.5)
    assert thrust_power_w([0.8, -0.8, 0.0, 0.0]) == pytest.approx(2 * one)
    assert thrust_power_w([]) == 0.0
    assert Battery.thrust_power_w(NOMINAL_THRUSTS_N) == NOMINAL_THRUST_POWER_W
    assert 3.0 < NOMINAL_THRUST_POWER_W < 10.0


# --- depth sensor ----------------------------------------------------------------------------

Q = 0.002


def _is_multiple(x: float, q: float = Q) -> bool:
    return abs(x / q - round(x / q)) < 1e-6


def test_depth_readings_are_2mm_steps_with_the_right_noise() -> None:
    sensor = DepthSensor(DepthSensorConfig(rate_hz=None), seed=1)
    true_m = 1.2345
    n = 20_000
    readings = [sensor.read(true_m, i * 0.01) for i in range(n)]
    assert all(_is_multiple(r) for r in readings)
    sigma = 0.002
    std = statistics.pstdev(readings)
    # Quantisation adds at most q^2 / 12 of variance on top of the noise.
    assert 0.96 * sigma < std < 1.04 * math.sqrt(sigma**2 + Q**2 / 12)
    mean = statistics.fmean(readings)
    assert abs(mean - true_m) < 4 * std / math.sqrt(n)  # unbiased
    assert len(set(readings)) > 5  # really noisy


def test_depth_noise_sigma_is_configurable() -> None:
    sensor = DepthSensor(DepthSensorConfig(noise_sigma_m=0.005, rate_hz=None), seed=2)
    readings = [sensor.read(3.0, 0.0) for _ in range(10_000)]
    assert 0.0048 < statistics.pstdev(readings) < 0.0053
    quiet = DepthSensor(DepthSensorConfig(noise_sigma_m=0.0, quantum_m=0.0, rate_hz=None))
    assert quiet.read(1.23456, 0.0) == 1.23456


def test_depth_sensor_holds_between_samples() -> None:
    sensor = DepthSensor(DepthSensorConfig(noise_sigma_m=0.0), seed=0)
    assert sensor.read(1.0, 0.0) == 1.0
    assert sensor.read(2.0, 0.02) == 1.0  # still the sample taken at t = 0
    assert sensor.read(2.0, 0.04) == 1.0
    assert sensor.read(2.0, 0.05) == 2.0  # next 20 Hz slot
    assert sensor.last_sample_t_s == 0.05
    assert sensor.read(3.0, 0.0999) == 2.0
    assert sensor.read(3.0, 0.15) == 3.0
    t_s = sum([0.02] * 10)  # 0.19999999999999998, as a simulation clock adds up to 0.2 s
    assert sensor.read(4.0, t_s) == 4.0  # counts as t = 0.2: a new slot
    assert sensor.last_reading_m == 4.0


def test_depth_sensor_samples_at_its_rate() -> None:
    sensor = DepthSensor(seed=5)
    readings = [sensor.read(2.0 + 0.01 * i, i * 0.02) for i in range(500)]  # 50 Hz for 10 s
    assert sensor.samples == 200  # 20 Hz
    for i in range(1, len(readings)):
        same_slot = math.floor(i * 0.02 * 20 + 1e-9) == math.floor((i - 1) * 0.02 * 20 + 1e-9)
        if same_slot:
            assert readings[i] == readings[i - 1]
    assert len(set(readings)) > 100  # the depth ramps: new samples differ


def test_depth_sensor_is_seeded() -> None:
    def run(seed: int) -> list[float]:
        sensor = DepthSensor(seed=seed)
        return [sensor.read(1.5, i * 0.02) for i in range(300)]

    assert run(7) == run(7)
    assert run(7) != run(8)


def test_depth_sensor_in_air_reads_about_zero() -> None:
    sensor = DepthSensor(DepthSensorConfig(rate_hz=None), seed=3)
    readings = [sensor.read(-0.5, 0.0) for _ in range(5_000)]
    assert abs(statistics.fmean(readings)) < 0.0002
    assert max(abs(r) for r in readings) < 0.012  # a few mm of noise, never -0.5


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"noise_sigma_m": -0.001}, "noise_sigma_m"),
        ({"quantum_m": -0.001}, "quantum_m"),
        ({"quantum_m": 2.0}, "quantum_m"),
        ({"rate_hz": 0.0}, "rate_hz"),
        ({"rate_hz": math.inf}, "rate_hz"),
    ],
)
def test_depth_config_validation(kwargs: dict[str, float], field: str) -> None:
    with pytest.raises(ValueError, match=field):
        DepthSensorConfig(**kwargs)


def test_depth_refuses_nan() -> None:
    with pytest.raises(ValueError, match="NaN"):
        DepthSensor().read(math.nan, 0.0)


# --- current ---------------------------------------------------------------------------------


def test_current_is_zero_by_default() -> None:
    current = Current()
    assert current.velocity == (0.0, 0.0)
    assert all(current.step(0.02) == (0.0, 0.0) for _ in range(1000))


def test_constant_current_is_exact() -> None:
    current = Current(CurrentConfig(north_mps=0.1, east_mps=-0.05), seed=3)
    for _ in range(1000):
        assert current.step(0.02) == (0.1, -0.05)
    assert current.velocity == (0.1, -0.05)
    assert current.speed_mps == pytest.approx(math.hypot(0.1, 0.05))
    east = Current(CurrentConfig(east_mps=0.2))
    assert east.direction_deg == pytest.approx(90.0)
    assert Current(CurrentConfig(east_mps=-0.2)).direction_deg == pytest.approx(270.0)


def test_drift_is_bounded_with_the_configured_statistics() -> None:
    sigma_v = 0.02
    sigma_deg = 10.0
    tau_s = 20.0
    cfg = CurrentConfig(
        north_mps=0.1,
        east_mps=0.05,
        speed_sigma_mps=sigma_v,
        direction_sigma_deg=sigma_deg,
        time_constant_s=tau_s,
    )
    v0 = math.hypot(0.1, 0.05)
    psi0 = math.degrees(math.atan2(0.05, 0.1))
    current = Current(cfg, seed=11)
    dv: list[float] = []
    dpsi: list[float] = []
    for _ in range(40_000):
        vn, ve = current.step(1.0)
        d_v = current.speed_deviation_mps
        d_psi = current.direction_deviation_deg
        assert abs(d_v) <= 3 * sigma_v + 1e-15
        assert abs(d_psi) <= 3 * sigma_deg + 1e-12
        speed = math.hypot(vn, ve)
        assert abs(speed - max(0.0, v0 + d_v)) < 1e-12
        assert abs(math.degrees(math.atan2(ve, vn)) - (psi0 + d_psi)) < 1e-9
        dv.append(d_v)
        dpsi.append(d_psi)
    for series, sigma in ((dv, sigma_v), (dpsi, sigma_deg)):
        assert abs(statistics.fmean(series)) < 0.15 * sigma
        assert 0.85 * sigma < statistics.pstdev(series) < 1.1 * sigma
        # Correlation one time constant apart: exp(-1) = 0.37 for a first-order process.
        lag = round(tau_s)
        r = statistics.correlation(series[:-lag], series[lag:])
        assert 0.27 < r < 0.47
    assert max(dv) > 2 * sigma_v and min(dv) < -2 * sigma_v  # it really wanders


def test_drift_without_mean_current_never_reverses() -> None:
    cfg = CurrentConfig(speed_sigma_mps=0.05, direction_sigma_deg=20.0, time_constant_s=5.0)
    current = Current(cfg, seed=4)
    for _ in range(2_000):
        vn, ve = current.step(0.5)
        assert math.hypot(vn, ve) == pytest.approx(max(0.0, current.speed_deviation_mps))
        assert math.hypot(vn, ve) <= 3 * 0.05 + 1e-12


def test_current_is_seeded() -> None:
    cfg = CurrentConfig(north_mps=0.1, speed_sigma_mps=0.02, direction_sigma_deg=5.0)

    def run(seed: int) -> list[tuple[float, float]]:
        current = Current(cfg, seed=seed)
        return [current.step(0.02) for _ in range(500)]

    assert run(1) == run(1)
    assert run(1) != run(2)


def test_current_config_changes_at_run_time() -> None:
    current = Current(CurrentConfig(north_mps=0.1, speed_sigma_mps=0.05, time_constant_s=1.0))
    for _ in range(100):
        current.step(0.1)
    assert current.velocity != (0.1, 0.0)
    current.set_config(CurrentConfig(north_mps=0.1))  # drift off: back to the exact mean
    assert current.velocity == (0.1, 0.0)
    assert current.step(1.0) == (0.1, 0.0)
    assert current.step(0.0) == (0.1, 0.0)
    with pytest.raises(ValueError, match="dt_s"):
        current.step(-0.02)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"north_mps": 6.0}, "north_mps"),
        ({"east_mps": math.nan}, "east_mps"),
        ({"speed_sigma_mps": -0.01}, "speed_sigma_mps"),
        ({"direction_sigma_deg": 200.0}, "direction_sigma_deg"),
        ({"time_constant_s": 0.0}, "time_constant_s"),
        ({"bound_sigmas": 0.0}, "bound_sigmas"),
        ({"bound_sigmas": 11.0}, "bound_sigmas"),
    ],
)
def test_current_config_validation(kwargs: dict[str, float], field: str) -> None:
    with pytest.raises(ValueError, match=field):
        CurrentConfig(**kwargs)
