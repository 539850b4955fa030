"""The NemeSys vehicle model: 4 actuated DOF (surge, heave, roll, yaw) in Fossen form.

Body velocities are relative to the water (``u, v, w`` m/s, ``p, r`` rad/s); the current is
added in the kinematics, which for an irrotational current is Fossen's relative-velocity
formulation. Pitch is held at zero (the vehicle cannot pitch). Sway ``v`` is passive. NED
frame: x north, y east, z down (depth), heading clockwise from north. ::

    (m+A11) du = X + (m+A22) v r - (Xu + Xuu|u|) u
    (m+A22) dv =   - (m+A11) u r - (Yv + Yvv|v|) v
    (m+A33) dw = Z - (Zw + Zww|w|) w - (B-W) cos(phi)        (B-W > 0: positively buoyant)
    (Ix+A44) dp = K - (Kp + Kpp|p|) p - W GM sin(phi)
    (Iz+A66) dr = N - (Nr + Nrr|r|) r

Four thrusters: a horizontal pair (1 port, 2 starboard: surge and yaw, ``X = T1+T2``,
``N = l_h (T1-T2)``) and a vertical pair (3 port, 4 starboard: heave and roll, ``Z = T3+T4``
pushing down, ``K = l_v (T4-T3)``), each saturated to ``[-reverse_ratio T_max, T_max]`` and
lagged by a first-order ``tau_thrust_s``. RK4 at the physics step, thrust held over the step.

The rigid-body, added-mass and damping values are estimates (``../shared/research/sim.md``
table 2.2); only the mass, GM and the two rates come from the paper. The effective thrust
limit and the quadratic yaw damping are *calibrated* (:func:`calibrate`) so that full thrust
gives the paper's Table ``tab:design_comparison`` Cfg #3 figures measured the paper's way:
73.1 mm/s heave over a 1.5 m descent and 30.3 deg/s yaw over 60 s at 0.5 m depth. That takes
about 0.8 N per thruster, ~1.5 % of a T200's 51.5 N nameplate: the as-tested vehicle ran
software-capped thrust (sim.md 2.4). Set ``thrust_max_n`` to model the nameplate instead.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields, replace

from planner._geometry import heading_deg

G_MPS2 = 9.81
#: T200 reverse/forward thrust at 16 V (40.2 N / 51.5 N).
T200_REVERSE_RATIO = 40.2 / 51.5
#: The paper's full-thrust rates (Table tab:design_comparison, Cfg #3).
PAPER_HEAVE_MPS = 0.0731
PAPER_YAW_DPS = 30.3
#: How the paper measured them: a 1.5 m descent; a 60 s rotation at 0.5 m depth.
HEAVE_TEST_DESCENT_M = 1.5
YAW_TEST_DURATION_S = 60.0
TEST_START_DEPTH_M = 0.5


@dataclass(frozen=True, slots=True)
class VehicleParams:
    """Physical parameters (SI). Defaults: NemeSys Cfg #3, calibrated (see module doc)."""

    mass_kg: float = 13.9
    buoyancy_margin_n: float = 0.7  # B - W, positive: the vehicle floats up without thrust
    gm_m: float = 0.0065  # metacentric height
    ix_kgm2: float = 0.15
    iz_kgm2: float = 0.35
    a11_kg: float = 1.5
    a22_kg: float = 10.0
    a33_kg: float = 12.0
    a44_kgm2: float = 0.05
    a66_kgm2: float = 0.15
    xu: float = 4.0  # N s/m
    xuu: float = 25.0  # N s^2/m^2
    yv: float = 6.0
    yvv: float = 80.0
    zw: float = 5.0
    zww: float = 90.0
    kp: float = 0.10  # N m s
    kpp: float = 0.20  # N m s^2
    nr: float = 0.10  # N m s
    nrr: float = 0.4312  # N m s^2, calibrated: 30.3 deg/s
    arm_h_m: float = 0.12  # lateral arm of the horizontal thrusters
    arm_v_m: float = 0.12  # lateral arm of the vertical thrusters
    thrust_max_n: float = 0.8408  # forward limit per thruster, calibrated: 73.1 mm/s
    reverse_ratio: float = T200_REVERSE_RATIO
    tau_thrust_s: float = 0.1

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not math.isfinite(value) or value < 0:
                raise ValueError(f"vehicle parameter {f.name} must be finite and >= 0: {value}")
        for name in ("mass_kg", "ix_kgm2", "iz_kgm2", "arm_h_m", "arm_v_m", "tau_thrust_s"):
            if getattr(self, name) <= 0:
                raise ValueError(f"vehicle parameter {name} must be > 0")

    @property
    def weight_n(self) -> float:
        return self.mass_kg * G_MPS2

    @property
    def thrust_min_n(self) -> float:
        """Reverse limit per thruster (a negative thrust, N)."""
        return -self.reverse_ratio * self.thrust_max_n


class Vehicle:
    """State and integration of one vehicle. Plain floats: this runs at 50 Hz x 20 vehicles.

    State: ``x, y, z`` (m NED), ``phi`` roll and ``psi`` heading (rad), ``u, v, w`` (m/s,
    relative to the water, body frame), ``p, r`` (rad/s), thrusts ``t1..t4`` (N) and their
    commands. ``current_n, current_e`` (m/s) is the water's velocity over ground.
    """

    __slots__ = (
        "_c",
        "_lag",
        "_lag_dt_s",
        "current_e",
        "current_n",
        "p",
        "params",
        "phi",
        "psi",
        "r",
        "t1",
        "t2",
        "t3",
        "t4",
        "tc",
        "u",
        "v",
        "w",
        "x",
        "y",
        "z",
    )

    def __init__(
        self,
        params: VehicleParams | None = None,
        x_m: float = 0.0,
        y_m: float = 0.0,
        z_m: float = 0.0,
        heading_deg: float = 0.0,
    ) -> None:
        self.params = params or VehicleParams()
        q = self.params
        w_n = q.weight_n
        # constants the derivative needs, flattened once
        self._c = (
            q.mass_kg + q.a11_kg,
            q.mass_kg + q.a22_kg,
            q.mass_kg + q.a33_kg,
            q.ix_kgm2 + q.a44_kgm2,
            q.iz_kgm2 + q.a66_kgm2,
            q.xu,
            q.xuu,
            q.yv,
            q.yvv,
            q.zw,
            q.zww,
            q.kp,
            q.kpp,
            q.nr,
            q.nrr,
            q.buoyancy_margin_n,
            w_n * q.gm_m,
        )
        self.x, self.y, self.z = float(x_m), float(y_m), float(z_m)
        self.phi, self.psi = 0.0, math.radians(heading_deg)
        self.u = self.v = self.w = self.p = self.r = 0.0
        self.t1 = self.t2 = self.t3 = self.t4 = 0.0
        self.tc = (0.0, 0.0, 0.0, 0.0)
        self.current_n = self.current_e = 0.0
        # the thruster lag's step factor, for the step it was computed for
        self._lag_dt_s = self._lag = 0.0

    # --- commands ------------------------------------------------------------------------

    def command(self, t1: float, t2: float, t3: float, t4: float) -> None:
        """Thrust commands (N) for thrusters 1..4, saturated to each thruster's limits."""
        hi = self.params.thrust_max_n
        lo = self.params.thrust_min_n
        self.tc = (
            min(hi, max(lo, t1)),
            min(hi, max(lo, t2)),
            min(hi, max(lo, t3)),
            min(hi, max(lo, t4)),
        )

    @property
    def thrusts(self) -> tuple[float, float, float, float]:
        return self.t1, self.t2, self.t3, self.t4

    # --- outputs -------------------------------------------------------------------------

    @property
    def heading_deg(self) -> float:
        return heading_deg(self.psi)

    @property
    def roll_deg(self) -> float:
        return math.degrees(self.phi)

    @property
    def speed_mps(self) -> float:
        """Horizontal speed through the water (m/s)."""
        return math.hypot(self.u, self.v)

    @property
    def ground_velocity(self) -> tuple[float, float]:
        """(north, east) velocity over ground (m/s)."""
        c, s = math.cos(self.psi), math.sin(self.psi)
        cphi = math.cos(self.phi)
        sphi = math.sin(self.phi)
        u, v, w = self.u, self.v, self.w
        return (
            u * c - v * cphi * s + w * sphi * s + self.current_n,
            u * s + v * cphi * c - w * sphi * c + self.current_e,
        )

    # --- integration ---------------------------------------------------------------------

    def step(self, dt_s: float) -> None:
        """Advance by ``dt_s``: thruster lag (exact), then RK4 on the rigid body."""
        if dt_s != self._lag_dt_s:
            self._lag_dt_s = dt_s
            self._lag = 1.0 - math.exp(-dt_s / self.params.tau_thrust_s)
        a = self._lag
        c1, c2, c3, c4 = self.tc
        self.t1 += (c1 - self.t1) * a
        self.t2 += (c2 - self.t2) * a
        self.t3 += (c3 - self.t3) * a
        self.t4 += (c4 - self.t4) * a
        q = self.params
        force_x = self.t1 + self.t2
        force_n = q.arm_h_m * (self.t1 - self.t2)
        force_z = self.t3 + self.t4
        force_k = q.arm_v_m * (self.t4 - self.t3)
        s0 = (self.u, self.v, self.w, self.p, self.r, self.x, self.y, self.z, self.phi, self.psi)
        f = self._deriv
        h = dt_s
        k1 = f(s0, force_x, force_z, force_k, force_n)
        k2 = f(_axpy(s0, k1, h / 2), force_x, force_z, force_k, force_n)
        k3 = f(_axpy(s0, k2, h / 2), force_x, force_z, force_k, force_n)
        k4 = f(_axpy(s0, k3, h), force_x, force_z, force_k, force_n)
        h6 = h / 6
        s = [
            x0 + h6 * (b1 + 2 * b2 + 2 * b3 + b4)
            for x0, b1, b2, b3, b4 in zip(s0, k1, k2, k3, k4, strict=True)
        ]
        self.u, self.v, self.w, self.p, self.r, self.x, self.y, self.z, self.phi, self.psi = s
        if self.z < 0.0:  # afloat at the surface: it cannot rise out of the water
            self.z = 0.0
            self.w = max(self.w, 0.0)

    def _deriv(
        self,
        s: Sequence[float],
        force_x: float,
        force_z: float,
        force_k: float,
        force_n: float,
    ) -> tuple[float, ...]:
        u, v, w, p, r, _, _, _, phi, psi = s
        m11, m22, m33, m44, m66, xu, xuu, yv, yvv, zw, zww, kp, kpp, nr, nrr, bw, wgm = self._c
        cphi, sphi = math.cos(phi), math.sin(phi)
        cpsi, spsi = math.cos(psi), math.sin(psi)
        return (
            (force_x + m22 * v * r - (xu + xuu * abs(u)) * u) / m11,
            (-m11 * u * r - (yv + yvv * abs(v)) * v) / m22,
            (force_z - (zw + zww * abs(w)) * w - bw * cphi) / m33,
            (force_k - (kp + kpp * abs(p)) * p - wgm * sphi) / m44,
            (force_n - (nr + nrr * abs(r)) * r) / m66,
            u * cpsi - v * cphi * spsi + w * sphi * spsi + self.current_n,
            u * spsi + v * cphi * cpsi - w * sphi * cpsi + self.current_e,
            v * sphi + w * cphi,
            p,
            r * cphi,
        )


def _axpy(s: Sequence[float], k: Sequence[float], h: float) -> list[float]:
    """``s + h k``, element by element (a list comprehension: this runs 3 times a step)."""
    return [a + h * b for a, b in zip(s, k, strict=True)]


# --- the paper's full-thrust tests ---------------------------------------------------------


def heave_test(params: VehicleParams, dt_s: float = 0.02) -> float:
    """Full-thrust descent of 1.5 m from rest at 0.5 m: mean rate (m/s), as the paper measured."""
    veh = Vehicle(params, z_m=TEST_START_DEPTH_M)
    t = 0.0
    target = TEST_START_DEPTH_M + HEAVE_TEST_DESCENT_M
    hi = params.thrust_max_n
    while veh.z < target:
        veh.command(0.0, 0.0, hi, hi)
        veh.step(dt_s)
        t += dt_s
        if t > 600.0:
            return 0.0
    return HEAVE_TEST_DESCENT_M / t


def ascent_test(params: VehicleParams, dt_s: float = 0.02) -> float:
    """Full-thrust ascent of 1.5 m from rest at 2 m: mean rate (m/s), the heave test reversed.

    The paper measured the descent only; the model rises faster (about 0.12 m/s over 1.5 m),
    its positive buoyancy adding to the thrusters' reverse, and the estimates time an ascent
    at this rate, not the descent's."""
    start = TEST_START_DEPTH_M + HEAVE_TEST_DESCENT_M
    veh = Vehicle(params, z_m=start)
    t = 0.0
    lo = params.thrust_min_n
    while veh.z > TEST_START_DEPTH_M:
        veh.command(0.0, 0.0, lo, lo)
        veh.step(dt_s)
        t += dt_s
        if t > 600.0:
            return 0.0
    return HEAVE_TEST_DESCENT_M / t


def yaw_test(params: VehicleParams, dt_s: float = 0.02) -> float:
    """Full-thrust rotation for 60 s at 0.5 m depth: mean yaw rate (deg/s), as measured."""
    veh = Vehicle(params, z_m=TEST_START_DEPTH_M)
    hi, lo = params.thrust_max_n, params.thrust_min_n
    steps = round(YAW_TEST_DURATION_S / dt_s)
    for _ in range(steps):
        veh.command(hi, lo, 0.0, 0.0)
        veh.step(dt_s)
    return math.degrees(veh.psi) / YAW_TEST_DURATION_S


def calibrate(
    params: VehicleParams | None = None,
    heave_mps: float = PAPER_HEAVE_MPS,
    yaw_dps: float = PAPER_YAW_DPS,
) -> VehicleParams:
    """Fit ``thrust_max_n`` to the heave rate, then ``nrr`` to the yaw rate (bisection)."""
    q = params or VehicleParams()

    def solve(
        name: str,
        lo: float,
        hi: float,
        rate: Callable[[VehicleParams], float],
        target: float,
        rising: bool,
    ) -> float:
        """The value of ``name`` in [lo, hi] at which ``rate`` meets ``target``; ``rising``:
        the rate grows with the parameter."""
        for _ in range(40):
            mid = (lo + hi) / 2
            if (rate(replace(q, **{name: mid})) < target) == rising:
                lo = mid
            else:
                hi = mid
        return (lo + hi) / 2

    # heave rate grows with thrust; yaw rate falls with damping
    q = replace(q, thrust_max_n=solve("thrust_max_n", 0.1, 5.0, heave_test, heave_mps, True))
    return replace(q, nrr=solve("nrr", 0.0, 5.0, yaw_test, yaw_dps, False))
