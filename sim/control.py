"""The low-level autopilot (the Pixhawk's job on NemeSys): references in, thrust commands out.

* Depth: PD on the Bar30 reading (derivative on the measurement, low-pass filtered, so a
  depth step gives no derivative kick) plus a constant buoyancy trim, in force units. The
  paper's tank test: 0.5 <-> 1.0 m steps with ~5 s transients and +-3 cm steady state.
* Heading: a yaw-rate reference ``r_d = k_psi * error``, limited to the planner's 20 deg/s,
  tracked with the yaw damping as feed-forward plus a P term.
* Surge: drag feed-forward plus a P term on the speed through the water.
* Roll: PD towards zero (the vertical pair's differential).
* Allocation: yaw before surge and heave before roll when a pair saturates.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from planner import YAW_RATE_DPS
from sim.model import VehicleParams


@dataclass(frozen=True, slots=True)
class AutopilotGains:
    """Controller gains (SI, force units)."""

    depth_kp_n_per_m: float = 40.0
    depth_kd_ns_per_m: float = 30.0
    depth_filter_s: float = 0.3
    #: Constant downward force that cancels the known positive buoyancy (N).
    buoyancy_trim_n: float = 0.7
    heading_k_per_s: float = 1.0
    yaw_rate_max_dps: float = YAW_RATE_DPS
    yaw_rate_kp_nms: float = 0.5
    surge_kp_ns_per_m: float = 10.0
    roll_kp_nm: float = 0.5
    roll_kd_nms: float = 0.2


def wrap_rad(a: float) -> float:
    """Angle wrapped to [-pi, pi)."""
    return (a + math.pi) % (2 * math.pi) - math.pi


def _pair(common: float, diff: float, lo: float, hi: float) -> tuple[float, float]:
    """Split into ``(common + diff, common - diff)`` within [lo, hi], the difference first."""
    diff = min((hi - lo) / 2, max(-(hi - lo) / 2, diff))
    c_hi = hi - abs(diff)
    c_lo = lo + abs(diff)
    common = min(c_hi, max(c_lo, common)) if c_lo <= c_hi else (c_lo + c_hi) / 2
    return common + diff, common - diff


class Autopilot:
    """Turns (course, speed, depth) references into the four thrust commands."""

    __slots__ = ("_dz_filt", "_z_prev", "gains", "params")

    def __init__(self, params: VehicleParams, gains: AutopilotGains | None = None) -> None:
        self.params = params
        self.gains = gains or AutopilotGains()
        self._z_prev: float | None = None
        self._dz_filt = 0.0

    def reset(self) -> None:
        self._z_prev = None
        self._dz_filt = 0.0

    def depth_force(self, z_ref_m: float, z_meas_m: float, dt_s: float) -> float:
        """Heave force (N, down positive) from the PD law and the buoyancy trim."""
        g = self.gains
        if self._z_prev is None:
            self._z_prev = z_meas_m
        rate = (z_meas_m - self._z_prev) / dt_s
        self._z_prev = z_meas_m
        a = dt_s / (g.depth_filter_s + dt_s)
        self._dz_filt += a * (rate - self._dz_filt)
        return (
            g.depth_kp_n_per_m * (z_ref_m - z_meas_m)
            - g.depth_kd_ns_per_m * self._dz_filt
            + g.buoyancy_trim_n
        )

    def thrusts(
        self,
        course_rad: float,
        speed_mps: float,
        heave_n: float,
        heading_rad: float,
        yaw_rate_rps: float,
        surge_mps: float,
        roll_rad: float,
        roll_rate_rps: float,
    ) -> tuple[float, float, float, float]:
        """Thrust commands (N) for thrusters 1..4."""
        q, g = self.params, self.gains
        r_max = math.radians(g.yaw_rate_max_dps)
        err = wrap_rad(course_rad - heading_rad)
        r_d = min(r_max, max(-r_max, g.heading_k_per_s * err))
        yaw_n = (q.nr + q.nrr * abs(r_d)) * r_d + g.yaw_rate_kp_nms * (r_d - yaw_rate_rps)
        # slow down while turning hard: full speed only when facing the course
        u_d = speed_mps * max(0.0, math.cos(err)) ** 2
        surge_n = (q.xu + q.xuu * abs(u_d)) * u_d + g.surge_kp_ns_per_m * (u_d - surge_mps)
        roll_k = -g.roll_kp_nm * roll_rad - g.roll_kd_nms * roll_rate_rps
        lo, hi = q.thrust_min_n, q.thrust_max_n
        t1, t2 = _pair(surge_n / 2, yaw_n / (2 * q.arm_h_m), lo, hi)
        t4, t3 = _pair(heave_n / 2, roll_k / (2 * q.arm_v_m), lo, hi)
        return t1, t2, t3, t4
