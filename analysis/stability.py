"""Passive stability of the three design configurations (the paper's Fig.
``fig:stability_comparison``), redone with the twin.

The paper's restoring moment is ``M = W h sin(theta)`` (``h`` = GM, positive when the centre
of gravity lies below the centre of buoyancy); Table ``tab:design_comparison`` gives GM = 0
(Cfg #1), -2.0 mm (Cfg #2) and 6.5 mm (Cfg #3), and the figure shows Cfg #2 flipping upside
down while Cfg #3 keeps its posture. The twin's roll equation is exactly that moment with
damping: ``(Ix+A44) dp = K - (Kp + Kpp|p|) p - W GM sin(phi)``.

The disturbance (:data:`PUSH_DPS`): the vehicle hangs upright and at rest at 5 m with its
thrusters off; at :data:`PUSH_AT_S` it is given a roll rate of 30 deg/s, the result of an
impulsive push about its long axis (an angular impulse ``(Ix+A44) p0`` = 0.105 N m s, e.g. a
1 N push 0.1 m off the centreline for about 0.1 s). No controller acts: passive stability is
the response without actuation. Each configuration is the calibrated Cfg #3 model
(:class:`sim.model.VehicleParams`: mass, inertia, damping) with only GM changed: the
paper gives no other figures for the earlier hardware, so the *shape* of each response
(capsize, neutral, righting) is what this reproduces, not Cfg #1/#2's exact timing.

:func:`compare` runs the three, :func:`plot_stability` draws roll against time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from pathlib import Path

from analysis.twin import PAPER_DESIGNS, _pyplot, _save
from sim.model import G_MPS2, Vehicle, VehicleParams

#: The disturbance: a roll rate (deg/s) given at PUSH_AT_S from upright rest.
PUSH_DPS = 30.0
PUSH_AT_S = 1.0
#: How long each run lasts (s) and the twin's physics step (s, 50 Hz).
DURATION_S = 30.0
DT_S = 0.02
START_DEPTH_M = 5.0
#: "Rights itself": back within this band (deg) and staying there.
UPRIGHT_BAND_DEG = 2.0
#: "Capsized": past this roll (deg).
CAPSIZE_DEG = 90.0


@dataclass(frozen=True, slots=True)
class ConfigParams(VehicleParams):
    """:class:`VehicleParams` that also admits a negative GM (the centre of gravity above the
    centre of buoyancy, Cfg #2). Every other parameter is checked as the base class does."""

    def __post_init__(self) -> None:
        values = {f.name: getattr(self, f.name) for f in fields(VehicleParams)}
        VehicleParams(**{**values, "gm_m": abs(self.gm_m)})  # raises on any bad value


def config_params(gm_mm: float, base: VehicleParams | None = None) -> ConfigParams:
    """The twin's vehicle with metacentric height ``gm_mm`` (mm), everything else as ``base``."""
    q = base or VehicleParams()
    values = {f.name: getattr(q, f.name) for f in fields(VehicleParams)}
    return ConfigParams(**{**values, "gm_m": gm_mm / 1e3})


@dataclass(frozen=True, slots=True)
class StabilityRun:
    """One configuration's roll response to the push."""

    name: str  # "Cfg #1"
    gm_mm: float
    times_s: tuple[float, ...]
    roll_deg: tuple[float, ...]
    peak_deg: float  # largest |roll| after the push
    final_deg: float  # roll at the end of the run
    capsize_s: float | None  # first time |roll| > 90 deg, after the push
    upright_s: float | None  # from the push until |roll| stays within 2 deg to the end

    @property
    def outcome(self) -> str:
        """``capsizes``, ``rights itself`` or ``neutral`` (stays where it was pushed)."""
        if self.capsize_s is not None:
            return "capsizes"
        if self.upright_s is not None:
            return "rights itself"
        return "neutral"


def simulate(
    gm_mm: float,
    *,
    push_dps: float = PUSH_DPS,
    duration_s: float = DURATION_S,
    dt_s: float = DT_S,
    name: str = "",
    base: VehicleParams | None = None,
) -> StabilityRun:
    """Roll against time, thrusters off, pushed at :data:`PUSH_AT_S` (the twin's RK4)."""
    veh = Vehicle(config_params(gm_mm, base), z_m=START_DEPTH_M)
    times: list[float] = []
    rolls: list[float] = []
    steps = round(duration_s / dt_s)
    push_step = round(PUSH_AT_S / dt_s)
    for k in range(steps + 1):
        if k == push_step:
            veh.p = math.radians(push_dps)
        times.append(k * dt_s)
        rolls.append(veh.roll_deg)
        veh.command(0.0, 0.0, 0.0, 0.0)
        veh.step(dt_s)
    after = [(t, r) for t, r in zip(times, rolls, strict=True) if t >= PUSH_AT_S]
    capsize = next((t - PUSH_AT_S for t, r in after if abs(r) > CAPSIZE_DEG), None)
    outside = [t for t, r in after if abs(r) > UPRIGHT_BAND_DEG]
    upright: float | None
    if not outside:
        upright = 0.0
    elif outside[-1] >= after[-1][0]:
        upright = None
    else:
        upright = outside[-1] - PUSH_AT_S
    return StabilityRun(
        name=name,
        gm_mm=gm_mm,
        times_s=tuple(times),
        roll_deg=tuple(rolls),
        peak_deg=max(abs(r) for _, r in after),
        final_deg=rolls[-1],
        capsize_s=capsize,
        upright_s=None if capsize is not None else upright,
    )


def compare(
    *, push_dps: float = PUSH_DPS, duration_s: float = DURATION_S, dt_s: float = DT_S
) -> list[StabilityRun]:
    """The three configurations of Table ``tab:design_comparison``, pushed the same way."""
    return [
        simulate(gm_mm, push_dps=push_dps, duration_s=duration_s, dt_s=dt_s, name=name)
        for name, (gm_mm, _, _) in PAPER_DESIGNS.items()
    ]


@dataclass(frozen=True, slots=True)
class RollMode:
    """The linearised roll mode about upright: ``m44 s^2 + Kp s + W GM = 0``."""

    gm_mm: float
    stiffness_nm_per_rad: float  # W GM
    period_s: float | None  # damped natural period, GM > 0
    damping_ratio: float | None  # GM > 0
    growth_per_s: float | None  # the unstable root, GM < 0: roll grows as exp(s t)


def roll_mode(gm_mm: float, params: VehicleParams | None = None) -> RollMode:
    q = params or VehicleParams()
    m44 = q.ix_kgm2 + q.a44_kgm2
    k = q.mass_kg * G_MPS2 * gm_mm / 1e3
    if k > 0:
        wn = math.sqrt(k / m44)
        zeta = q.kp / (2 * math.sqrt(m44 * k))
        wd = wn * math.sqrt(max(0.0, 1 - zeta * zeta))
        return RollMode(gm_mm, k, 2 * math.pi / wd if wd > 0 else None, zeta, None)
    if k < 0:
        growth = (-q.kp + math.sqrt(q.kp * q.kp - 4 * m44 * k)) / (2 * m44)
        return RollMode(gm_mm, k, None, None, growth)
    return RollMode(gm_mm, 0.0, None, None, None)


def push_impulse_nms(params: VehicleParams | None = None, push_dps: float = PUSH_DPS) -> float:
    """The angular impulse (N m s) that gives the vehicle the push's roll rate."""
    q = params or VehicleParams()
    return (q.ix_kgm2 + q.a44_kgm2) * math.radians(push_dps)


_COLOURS = {"Cfg #1": "#7f7f7f", "Cfg #2": "#d62728", "Cfg #3": "#1f77b4"}


def plot_stability(runs: list[StabilityRun], path: Path) -> Path:
    """Roll against time for each configuration, the push marked, 0 and 180 deg drawn."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(9, 4.2))
    for level in (0.0, 180.0):
        ax.axhline(level, color="#444444", lw=0.7, alpha=0.6)
    ax.axvline(PUSH_AT_S, color="#ff7f0e", lw=1.0, ls=":", label=f"push ({PUSH_DPS:g} deg/s)")
    for run in runs:
        ax.plot(
            run.times_s,
            run.roll_deg,
            color=_COLOURS.get(run.name, "k"),
            lw=1.5,
            label=f"{run.name}, GM {run.gm_mm:g} mm: {run.outcome}",
        )
    ax.set_xlim(0, runs[0].times_s[-1] if runs else DURATION_S)
    ax.set_ylim(-30, 200)
    ax.set_yticks([0, 30, 60, 90, 120, 150, 180])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("roll (deg)")
    ax.set_title(
        "Twin: passive roll response to a push, thrusters off (Cfg #1-#3 differ only in GM)",
        fontsize=10,
    )
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="center right")
    return _save(plt, fig, path)


__all__ = [
    "CAPSIZE_DEG",
    "PUSH_AT_S",
    "PUSH_DPS",
    "UPRIGHT_BAND_DEG",
    "ConfigParams",
    "RollMode",
    "StabilityRun",
    "compare",
    "config_params",
    "plot_stability",
    "push_impulse_nms",
    "roll_mode",
    "simulate",
]
