"""The simulated vehicle's surroundings and onboard supplies: current, depth sensor, battery.

Pure Python (``math`` and a seeded :class:`random.Random` each), cheap per call: the simulated
vehicle steps these at 50 Hz for up to 20 vehicles. Same seed, same calls, same results. SI
units, NED frame (north, east, down); depth is positive down.

* :class:`Current`: a constant NED water current plus an optional first-order Gauss-Markov drift
  of its speed and direction, bounded.
* :class:`DepthSensor`: a Bar30 (MS5837-30BA) pressure sensor: 2 mm steps, Gaussian noise,
  20 Hz sample-and-hold.
* :class:`Battery`: the paper's state-of-charge curve (100/71/54/42/32/22 % after 0..5 h),
  made to respond to thruster load.

Sources: the research note ``sim.md`` sections 2.1-2.5 (Fossen ch. 8 for the Gauss-Markov
current; the MS5837-30BA datasheet for 0.2 mbar = 2 mm resolution; the battery fit).
"""

from __future__ import annotations

import math
import random
from collections.abc import Iterable
from dataclasses import dataclass

from sim._checks import in_range, non_negative, number, positive

__all__ = [
    "CALIBRATED_THRUST_N",
    "HOTEL_POWER_W",
    "NOMINAL_THRUSTS_N",
    "NOMINAL_THRUST_POWER_W",
    "PAPER_SOC_TABLE",
    "SOC_FAST_PCT",
    "SOC_FAST_TAU_H",
    "SOC_LINEAR_PCT_PER_H",
    "THRUST_POWER_COEFF_W_PER_N1_5",
    "Battery",
    "BatteryConfig",
    "Current",
    "CurrentConfig",
    "DepthSensor",
    "DepthSensorConfig",
    "paper_soc_pct",
    "thrust_power_w",
]


def _check_dt(dt_s: float) -> None:
    if not 0.0 <= dt_s < math.inf:
        raise ValueError(f"dt_s must be in [0, inf), got {dt_s!r}")


# --------------------------------------------------------------------------------------------
# Current
# --------------------------------------------------------------------------------------------

#: Largest mean current component accepted (m/s): catches cm/s or knots passed as m/s.
MAX_CURRENT_MPS = 5.0


@dataclass(frozen=True, slots=True)
class CurrentConfig:
    """A constant NED current plus an optional Gauss-Markov drift of its speed and direction.

    The drift is two independent first-order Gauss-Markov (Ornstein-Uhlenbeck) processes, the
    speed deviation dV and the direction deviation dB, each with time constant
    ``time_constant_s`` and *stationary* standard deviation ``speed_sigma_mps`` or
    ``direction_sigma_deg``. Each is clamped to +-``bound_sigmas`` standard deviations, and
    the speed ``V0 + dV`` is clamped at 0 (it never reverses the current). Both sigmas 0 (the
    default) turn the drift off: the current is then exactly (north_mps, east_mps).
    """

    #: Mean current towards north (m/s), in [-5, 5].
    north_mps: float = 0.0
    #: Mean current towards east (m/s), in [-5, 5].
    east_mps: float = 0.0
    #: Stationary std of the speed deviation (m/s), in [0, 5].
    speed_sigma_mps: float = 0.0
    #: Stationary std of the direction deviation (deg), in [0, 180].
    direction_sigma_deg: float = 0.0
    #: Correlation time of both drifts (s), in (0, inf).
    time_constant_s: float = 600.0
    #: The deviations are clamped to this many standard deviations, in (0, 10].
    bound_sigmas: float = 3.0

    def __post_init__(self) -> None:
        span = f"[-{MAX_CURRENT_MPS:g}, {MAX_CURRENT_MPS:g}]"
        in_range("north_mps", self.north_mps, -MAX_CURRENT_MPS, MAX_CURRENT_MPS, span)
        in_range("east_mps", self.east_mps, -MAX_CURRENT_MPS, MAX_CURRENT_MPS, span)
        in_range(
            "speed_sigma_mps",
            self.speed_sigma_mps,
            0.0,
            MAX_CURRENT_MPS,
            f"[0, {MAX_CURRENT_MPS:g}]",
        )
        in_range("direction_sigma_deg", self.direction_sigma_deg, 0.0, 180.0, "[0, 180]")
        positive("time_constant_s", self.time_constant_s)
        x = number("bound_sigmas", self.bound_sigmas)
        if not 0.0 < x <= 10.0:
            raise ValueError(f"bound_sigmas must be in (0, 10], got {self.bound_sigmas!r}")

    @property
    def drift(self) -> bool:
        """Whether the current drifts (a sigma is non-zero)."""
        return self.speed_sigma_mps > 0.0 or self.direction_sigma_deg > 0.0


class Current:
    """The water current at the vehicle, stepped with the simulation.

    The drift starts at zero deviation (the configured mean current) and is advanced with the
    exact discretisation of the Gauss-Markov process, ``x' = a x + sigma sqrt(1 - a^2) n`` with
    ``a = exp(-dt / T)``, so its statistics do not depend on the step. With no mean current
    (V0 = 0) the drifting current flows towards north turned by dB, at speed ``max(0, dV)``.
    """

    __slots__ = ("_a", "_b", "_config", "_dpsi_rad", "_dt_s", "_dv_mps", "_rng", "_ve", "_vn")

    def __init__(self, config: CurrentConfig | None = None, seed: int = 0) -> None:
        self._rng = random.Random(seed)
        self._dv_mps = 0.0
        self._dpsi_rad = 0.0
        self._vn = 0.0
        self._ve = 0.0
        self._dt_s = -1.0  # the step whose a, b are cached
        self._a = 1.0
        self._b = 0.0
        self.set_config(config if config is not None else CurrentConfig())

    @property
    def config(self) -> CurrentConfig:
        return self._config

    def set_config(self, config: CurrentConfig) -> None:
        """Change the current; the drift keeps its state, clamped to the new bounds."""
        if not isinstance(config, CurrentConfig):
            raise TypeError(f"config must be a CurrentConfig, got {type(config).__name__}")
        self._config = config
        self._dt_s = -1.0
        lim_v = config.bound_sigmas * config.speed_sigma_mps
        lim_psi = config.bound_sigmas * math.radians(config.direction_sigma_deg)
        self._dv_mps = min(lim_v, max(-lim_v, self._dv_mps))
        self._dpsi_rad = min(lim_psi, max(-lim_psi, self._dpsi_rad))
        self._update_velocity()

    def _update_velocity(self) -> None:
        cfg = self._config
        dv = self._dv_mps
        dpsi = self._dpsi_rad
        if dv == 0.0 and dpsi == 0.0:
            self._vn = float(cfg.north_mps)
            self._ve = float(cfg.east_mps)
            return
        n = cfg.north_mps
        e = cfg.east_mps
        c = math.cos(dpsi)
        s = math.sin(dpsi)
        v0 = math.hypot(n, e)
        if v0 > 0.0:
            scale = max(0.0, v0 + dv) / v0
            self._vn = scale * (n * c - e * s)
            self._ve = scale * (n * s + e * c)
        else:
            speed = max(0.0, dv)
            self._vn = speed * c
            self._ve = speed * s

    def step(self, dt_s: float) -> tuple[float, float]:
        """Advance the drift by ``dt_s`` and return the current (north_mps, east_mps)."""
        _check_dt(dt_s)
        cfg = self._config
        if not cfg.drift or dt_s == 0.0:
            return (self._vn, self._ve)
        if dt_s != self._dt_s:
            self._dt_s = dt_s
            self._a = math.exp(-dt_s / cfg.time_constant_s)
            self._b = math.sqrt(-math.expm1(-2.0 * dt_s / cfg.time_constant_s))
        a = self._a
        b = self._b
        gauss = self._rng.gauss
        sigma_v = cfg.speed_sigma_mps
        if sigma_v > 0.0:
            lim = cfg.bound_sigmas * sigma_v
            dv = a * self._dv_mps + sigma_v * b * gauss(0.0, 1.0)
            self._dv_mps = lim if dv > lim else -lim if dv < -lim else dv
        sigma_psi = math.radians(cfg.direction_sigma_deg)
        if sigma_psi > 0.0:
            lim = cfg.bound_sigmas * sigma_psi
            dpsi = a * self._dpsi_rad + sigma_psi * b * gauss(0.0, 1.0)
            self._dpsi_rad = lim if dpsi > lim else -lim if dpsi < -lim else dpsi
        self._update_velocity()
        return (self._vn, self._ve)

    @property
    def velocity(self) -> tuple[float, float]:
        """The current now (north_mps, east_mps)."""
        return (self._vn, self._ve)

    @property
    def speed_mps(self) -> float:
        return math.hypot(self._vn, self._ve)

    @property
    def direction_deg(self) -> float:
        """Where the water flows to, degrees clockwise from north in [0, 360)."""
        return math.degrees(math.atan2(self._ve, self._vn)) % 360.0

    @property
    def speed_deviation_mps(self) -> float:
        """The drift's speed deviation dV (before clamping the speed at 0)."""
        return self._dv_mps

    @property
    def direction_deviation_deg(self) -> float:
        """The drift's direction deviation dB."""
        return math.degrees(self._dpsi_rad)


# --------------------------------------------------------------------------------------------
# Depth sensor
# --------------------------------------------------------------------------------------------

#: MS5837-30BA resolution: 0.2 mbar at the finest oversampling, 2 mm of seawater.
BAR30_QUANTUM_M = 0.002


@dataclass(frozen=True, slots=True)
class DepthSensorConfig:
    """A Bar30 (MS5837-30BA) depth sensor."""

    #: Standard deviation of the Gaussian noise (m), in [0, 1].
    noise_sigma_m: float = 0.002
    #: Reading resolution (m), in [0, 1]; 0 for none.
    quantum_m: float = BAR30_QUANTUM_M
    #: Sample rate (Hz), in (0, inf), or None for a new sample on every read.
    rate_hz: float | None = 20.0

    def __post_init__(self) -> None:
        in_range("noise_sigma_m", self.noise_sigma_m, 0.0, 1.0, "[0, 1]")
        in_range("quantum_m", self.quantum_m, 0.0, 1.0, "[0, 1]")
        if self.rate_hz is not None:
            positive("rate_hz", self.rate_hz)


class DepthSensor:
    """Reads depth like a Bar30: noisy, quantised, sampled at its rate and held in between.

    Samples are taken on the grid ``t = k / rate_hz``: a read in a new grid interval (or the
    first read) takes a sample, any other read returns the held one. A sample is
    ``q * round((max(true, 0) + noise) / q)``. Above the surface (negative true depth) the
    sensor sees atmospheric pressure, which the zeroed sensor reads as depth 0, so it reads 0
    plus noise, a few millimetres either side of 0 as a real zeroed Bar30 in air does.
    """

    __slots__ = ("_config", "_k", "_reading_m", "_rng", "_sample_t_s", "samples")

    def __init__(self, config: DepthSensorConfig | None = None, seed: int = 0) -> None:
        self._rng = random.Random(seed)
        self._reading_m = 0.0
        self._sample_t_s = math.nan
        #: How many samples have been taken.
        self.samples = 0
        self.set_config(config if config is not None else DepthSensorConfig())

    @property
    def config(self) -> DepthSensorConfig:
        return self._config

    def set_config(self, config: DepthSensorConfig) -> None:
        """Change the sensor's settings; the next read takes a new sample."""
        if not isinstance(config, DepthSensorConfig):
            raise TypeError(f"config must be a DepthSensorConfig, got {type(config).__name__}")
        self._config = config
        self._k: int | None = None

    def read(self, true_depth_m: float, t_s: float) -> float:
        """The reading (m, positive down) at simulated time ``t_s`` for the true depth."""
        if math.isnan(true_depth_m):
            raise ValueError("true_depth_m is NaN")
        cfg = self._config
        rate = cfg.rate_hz
        if rate is not None:
            # The epsilon puts t = k / rate in slot k even when the clock adds up to a hair less
            # (ten steps of 0.02 s make 0.19999999999999998 s).
            k = math.floor(t_s * rate + 1e-9)
            if k == self._k:
                return self._reading_m
            self._k = k
        depth = true_depth_m if true_depth_m > 0.0 else 0.0
        if cfg.noise_sigma_m > 0.0:
            depth += cfg.noise_sigma_m * self._rng.gauss(0.0, 1.0)
        q = cfg.quantum_m
        if q > 0.0:
            depth = round(depth / q) * q
        self._reading_m = depth
        self._sample_t_s = t_s
        self.samples += 1
        return depth

    @property
    def last_reading_m(self) -> float:
        """The held reading (0.0 before the first read)."""
        return self._reading_m

    @property
    def last_sample_t_s(self) -> float:
        """When the held reading was sampled (NaN before the first read)."""
        return self._sample_t_s


# --------------------------------------------------------------------------------------------
# Battery
# --------------------------------------------------------------------------------------------

#: The paper's battery test: (hours of operation, state of charge %).
PAPER_SOC_TABLE: tuple[tuple[float, float], ...] = (
    (0.0, 100.0),
    (1.0, 71.0),
    (2.0, 54.0),
    (3.0, 42.0),
    (4.0, 32.0),
    (5.0, 22.0),
)
#: Fit SOC(t) = 100 - 9.23 t - 32.0 (1 - exp(-t / 1.03)), t in h (sim.md 2.5, RMS 0.13 %).
SOC_LINEAR_PCT_PER_H = 9.23
SOC_FAST_PCT = 32.0
SOC_FAST_TAU_H = 1.03

#: Thruster electrical power P = k |T|^1.5 (W, T in N). Momentum theory gives the ideal
#: 1/sqrt(2 rho A) = 0.33 W/N^1.5 for the T200's 76 mm propeller in seawater; the T200 at
#: nameplate (51.5 N, about 390 W at 16 V) runs at about 1.05, three times ideal. At the
#: calibrated ~0.8 N (1.5 % of nameplate) ESC and motor losses dominate, so k is set to about
#: nine times ideal: 2.1 W per thruster at 0.8 N. An estimate for the low-thrust regime the
#: vehicle runs in; it overstates power above ~10 N, which the calibrated vehicle never uses.
THRUST_POWER_COEFF_W_PER_N1_5 = 3.0
#: Effective full thrust per thruster that reproduces the paper's heave and yaw rates (N).
CALIBRATED_THRUST_N = 0.8
#: The nominal load the paper's curve is taken to be at: cruising, both horizontal thrusters
#: at the calibrated 0.8 N, the vertical pair holding the +0.7 N buoyancy (0.35 N each).
NOMINAL_THRUSTS_N: tuple[float, ...] = (CALIBRATED_THRUST_N, CALIBRATED_THRUST_N, 0.35, 0.35)
#: Everything but the thrusters (W): single-board computer ~5 W, autopilot and sensors ~2 W,
#: ME transceiver listening ~5 W, lights/camera and conversion losses ~3 W. An estimate; with
#: the nominal thrust it makes ~20.5 W, and the fit's 9.23 %/h then implies a ~220 Wh pack,
#: the size of a 4S 15.6 Ah Li-ion pack.
HOTEL_POWER_W = 15.0


def thrust_power_w(
    thrusts_n: Iterable[float], coeff_w_per_n1_5: float = THRUST_POWER_COEFF_W_PER_N1_5
) -> float:
    """Electrical power of the thrusters (W): ``sum(k |T_i|^1.5)``, T in N, either direction."""
    total = 0.0
    for t in thrusts_n:
        a = abs(t)
        total += a * math.sqrt(a)
    return coeff_w_per_n1_5 * total


#: Thrust power at the nominal load (W), about 5.5 W.
NOMINAL_THRUST_POWER_W = thrust_power_w(NOMINAL_THRUSTS_N)


def paper_soc_pct(t_h: float) -> float:
    """The fit to the paper's table at nominal load (%), floored at 0."""
    soc = 100.0 - SOC_LINEAR_PCT_PER_H * t_h - SOC_FAST_PCT * -math.expm1(-t_h / SOC_FAST_TAU_H)
    return max(0.0, soc)


@dataclass(frozen=True, slots=True)
class BatteryConfig:
    """Loads and thresholds of the battery model."""

    #: Power drawn by everything but the thrusters (W), in (0, inf).
    hotel_power_w: float = HOTEL_POWER_W
    #: Thrust power at which the paper's curve holds (W), in [0, inf).
    nominal_thrust_power_w: float = NOMINAL_THRUST_POWER_W
    #: The battery is empty at or below this SOC (%), in [0, reserve_pct].
    cutoff_pct: float = 0.0
    #: The battery is low at or below this SOC (%), in [cutoff_pct, 100]; 20 % is the
    #: manufacturer's recommended floor quoted in the paper.
    reserve_pct: float = 20.0

    def __post_init__(self) -> None:
        positive("hotel_power_w", self.hotel_power_w)
        non_negative("nominal_thrust_power_w", self.nominal_thrust_power_w)
        in_range("reserve_pct", self.reserve_pct, 0.0, 100.0, "[0, 100]")
        in_range(
            "cutoff_pct",
            self.cutoff_pct,
            0.0,
            self.reserve_pct,
            f"[0, reserve_pct = {self.reserve_pct:g}]",
        )


class Battery:
    """State of charge following the paper's curve, faster or slower with thruster load.

    ``SOC = 100 - 9.23 L - 32.0 (1 - exp(-t / 1.03))`` (%, hours), where t is the time of
    operation and L the load-weighted time, ``dL = dt (P_hotel + P_thrust) /
    (P_hotel + P_thrust_nominal)``. At nominal load L = t and this is the paper's fit. The
    fast initial term stays a function of time only (it looks like an artefact of a
    voltage-based SOC estimate, not energy) and is evaluated in closed form, so stepping is
    exact for any ``dt`` when the load is constant over each step. SOC is floored at 0.
    """

    __slots__ = ("_config", "_elapsed_h", "_inv_nominal_w", "_load_h", "_soc_pct")

    thrust_power_w = staticmethod(thrust_power_w)

    def __init__(self, config: BatteryConfig | None = None, start_h: float = 0.0) -> None:
        """``start_h``: hours already run at nominal load (a part-used battery; 0 = full)."""
        in_range("start_h", start_h, 0.0, math.inf, "[0, inf)")
        self.set_config(config if config is not None else BatteryConfig())
        self._elapsed_h = self._load_h = float(start_h)
        self._soc_pct = paper_soc_pct(start_h)

    @property
    def config(self) -> BatteryConfig:
        return self._config

    def set_config(self, config: BatteryConfig) -> None:
        """Change loads and thresholds from the next step on (the charge used so far stays)."""
        if not isinstance(config, BatteryConfig):
            raise TypeError(f"config must be a BatteryConfig, got {type(config).__name__}")
        self._config = config
        self._inv_nominal_w = 1.0 / (config.hotel_power_w + config.nominal_thrust_power_w)

    def step(self, dt_s: float, thrust_power_w: float) -> float:
        """Run ``dt_s`` seconds with the thrusters drawing ``thrust_power_w``; return SOC (%)."""
        _check_dt(dt_s)
        if not 0.0 <= thrust_power_w < math.inf:
            raise ValueError(f"thrust_power_w must be in [0, inf), got {thrust_power_w!r}")
        dt_h = dt_s / 3600.0
        self._elapsed_h += dt_h
        self._load_h += dt_h * (self._config.hotel_power_w + thrust_power_w) * self._inv_nominal_w
        soc = (
            100.0
            - SOC_LINEAR_PCT_PER_H * self._load_h
            - SOC_FAST_PCT * -math.expm1(-self._elapsed_h / SOC_FAST_TAU_H)
        )
        self._soc_pct = soc if soc > 0.0 else 0.0
        return self._soc_pct

    @property
    def soc_pct(self) -> float:
        """State of charge (%), in [0, 100]."""
        return self._soc_pct

    @property
    def empty(self) -> bool:
        """SOC at or below ``cutoff_pct``: the thrusters should stop."""
        return self._soc_pct <= self._config.cutoff_pct

    @property
    def low(self) -> bool:
        """SOC at or below ``reserve_pct`` (20 % by default): time to come home."""
        return self._soc_pct <= self._config.reserve_pct

    @property
    def elapsed_s(self) -> float:
        """Time of operation so far (s)."""
        return self._elapsed_h * 3600.0

    @property
    def load_hours(self) -> float:
        """Load-weighted time of operation L (h): equals the elapsed hours at nominal load."""
        return self._load_h
