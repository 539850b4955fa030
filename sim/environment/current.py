"""The water current at the vehicle: a constant NED current plus an optional first-order
Gauss-Markov drift of its speed and direction, bounded (the research note ``sim.md`` 2.1,
Fossen ch. 8). Seeded :class:`random.Random`; SI units, NED frame.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

from sim._checks import check_dt, in_range, number, positive

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
        check_dt(dt_s)
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
