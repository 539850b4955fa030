"""The tank test's step figures (the paper's Fig. ``fig:depth_control``), defined so that none
is true by construction.

For each commanded depth step, from the command time ``t0`` to the next command:

* **rise**: the 10 % to 90 % time of the step (from the first sample 10 % of the way to the
  new depth to the first sample 90 % of the way);
* **settle**: from ``t0`` to the last sample outside +-3 cm of the target (after it the depth
  stays inside the band until the next command); ``None`` if it is still outside at the end;
* **steady state**: the deviation from the target over a window fixed in advance, from
  ``t0 + 10 s`` (:data:`STEADY_FROM_S`) to the next command: its mean and its peak ``|dev|``.
  The window does not depend on the settling time, so "within +-3 cm" is a measurement that
  can fail (a step still outside the band 10 s after its command shows its full deviation).
"""

from __future__ import annotations

import statistics
from collections.abc import Sequence
from dataclasses import dataclass

from sim.scenarios import SETTLE_BAND_M, ScenarioResult

#: The steady-state window starts this long after each command (s).
STEADY_FROM_S = 10.0


@dataclass(frozen=True, slots=True)
class TankStep:
    """One commanded depth change (m, s)."""

    t_s: float
    from_m: float
    to_m: float
    rise_s: float | None
    settle_s: float | None
    window_s: tuple[float, float]  # the steady-state window
    steady_mean_m: float | None  # mean deviation (depth - target) in the window
    steady_peak_m: float | None  # peak |deviation| in the window
    samples: int  # samples in the window

    @property
    def within_band(self) -> bool:
        return self.steady_peak_m is not None and self.steady_peak_m <= SETTLE_BAND_M


def tank_steps(
    track: Sequence[tuple[float, float]],
    schedule: Sequence[tuple[float, float]],
    end_s: float,
    steady_from_s: float = STEADY_FROM_S,
) -> list[TankStep]:
    """Each step's figures from ``track`` (time s, depth m) and ``schedule`` (command time s,
    target depth m); the last step runs to ``end_s``."""
    out: list[TankStep] = []
    for k, (t0, target) in enumerate(schedule):
        t1 = schedule[k + 1][0] if k + 1 < len(schedule) else end_s
        seg = [(t, z) for t, z in track if t0 < t <= t1]
        if not seg:
            continue
        before = [z for t, z in track if t <= t0]
        z0 = before[-1] if before else seg[0][1]
        span = target - z0
        rise: float | None = None
        if abs(span) > 1e-9:
            t10 = next((t for t, z in seg if (z - z0) / span >= 0.1), None)
            t90 = next((t for t, z in seg if (z - z0) / span >= 0.9), None)
            rise = t90 - t10 if t10 is not None and t90 is not None else None
        outside = [t for t, z in seg if abs(z - target) > SETTLE_BAND_M]
        settle: float | None
        if not outside:
            settle = 0.0
        elif outside[-1] >= seg[-1][0]:
            settle = None
        else:
            settle = outside[-1] - t0
        w0 = t0 + steady_from_s
        dev = [z - target for t, z in seg if t >= w0]
        out.append(
            TankStep(
                t_s=t0,
                from_m=z0,
                to_m=target,
                rise_s=rise,
                settle_s=settle,
                window_s=(w0, t1),
                steady_mean_m=statistics.fmean(dev) if dev else None,
                steady_peak_m=max((abs(d) for d in dev), default=None),
                samples=len(dev),
            )
        )
    return out


def tank_result_steps(result: ScenarioResult) -> list[TankStep]:
    """:func:`tank_steps` of a ``run_scenario("tank")`` result (its true depth track)."""
    sc = result.scenario
    schedule = [(c.t_s, float(c.params["depth"])) for c in sc.commands]
    return tank_steps([(s.t_s, s.z_m) for s in result.track], schedule, sc.duration_s)


__all__ = ["STEADY_FROM_S", "TankStep", "tank_result_steps", "tank_steps"]
