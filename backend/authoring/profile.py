"""The vehicle profile: what the vehicle can do, for every estimate and check.

Top speed through the water (m/s), heave (descent) and ascent rates (m/s), yaw rate (deg/s),
maximum depth (m) and endurance (s). A real vehicle's come from the settings
(``NEMESYS_TOP_SPEED_MPS``...): an unset figure is unknown (``None``) and the checks that need
it are skipped, saying so. In training they come from the twin (``sim``), once per parameter
set (cached):

* top speed: the steady surge with both horizontal thrusters at their (calibrated) limit,
  ``2 T = (Xu + Xuu u) u``, solved for ``u``: about 0.19 m/s;
* heave and yaw rates: the paper's own full-thrust manoeuvres run in the model
  (:func:`sim.model.heave_test`, :func:`sim.model.yaw_test`): 73.1 mm/s and
  30.3 deg/s, what the model is calibrated to;
* ascent rate: the heave test reversed (:func:`sim.model.ascent_test`), about 0.11 m/s: the
  buoyancy helps the thrusters up (unknown on a real vehicle without its setting: ascents are
  then timed at the heave rate);
* endurance: the battery fit run to the empty cut-off at cruise load (hotel power, both
  horizontal thrusters at their limit, the vertical pair holding the buoyancy), ~7.2 h.

A setting, when given, overrides the twin's figure in training too.

The battery estimate (:func:`battery_use_pct`) uses the whole fit of the paper's table,
``SOC = 100 - 9.23 t - 32.0 (1 - exp(-t / 1.03 h))``: the fast initial term matters most in
the first hours of a dive, which is where a plan's cost is asked.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from typing import Final, Literal

from backend.settings import Settings
from sim.environment import (
    SOC_FAST_PCT,
    SOC_FAST_TAU_H,
    SOC_LINEAR_PCT_PER_H,
    BatteryConfig,
    paper_soc_pct,
    thrust_power_w,
)
from sim.model import VehicleParams, ascent_test, heave_test, yaw_test

#: Longest dive the battery fit is searched over (h): beyond the fit's reach in any case.
_MAX_HOURS = 100.0


@dataclass(frozen=True, slots=True)
class VehicleProfile:
    """What the vehicle can do; ``None``: unknown (the checks needing it are skipped)."""

    #: Top speed through the water (m/s).
    top_speed_mps: float | None
    #: Largest vertical speed (m/s): the descent's, as the paper measured it.
    heave_rate_mps: float | None
    #: Largest turn rate (deg/s).
    yaw_rate_dps: float | None
    #: Deepest allowed depth (m): the console's limit.
    max_depth_m: float
    #: Time on a full battery at cruise (s).
    endurance_s: float | None
    #: Where the figures come from: the training twin, or the settings (a real vehicle).
    source: Literal["twin", "settings"]
    #: Largest ascent rate (m/s); None: the heave rate (for a vehicle without the figure).
    ascent_rate_mps: float | None = None

    def skipped_checks(self) -> list[str]:
        """What cannot be checked or estimated for lack of a figure, in words."""
        return [why for figure, why in UNKNOWN.items() if getattr(self, figure) is None]


#: What an unknown figure of the profile prevents, by figure, in words (the preview's
#: ``skipped_checks``, the send checks' skipped lines).
UNKNOWN: Final[dict[str, str]] = {
    "top_speed_mps": (
        "top speed unknown (setting top_speed_mps): speeds are not checked against it and "
        "durations are at the commanded speed"
    ),
    "heave_rate_mps": (
        "heave rate unknown (setting heave_rate_mps): depth changes are timed at the planner's "
        "rates"
    ),
    "endurance_s": (
        "endurance unknown (setting endurance_s): durations are not checked against the battery"
    ),
}


def top_speed_mps(params: VehicleParams) -> float:
    """Steady speed through the water with both horizontal thrusters at their limit (m/s):
    the positive root of ``Xuu u^2 + Xu u - 2 T = 0``."""
    thrust = 2.0 * params.thrust_max_n
    if params.xuu <= 0.0:
        return thrust / params.xu if params.xu > 0 else math.inf
    disc = params.xu * params.xu + 4.0 * params.xuu * thrust
    return (-params.xu + math.sqrt(disc)) / (2.0 * params.xuu)


def cruise_thrust_power_w(params: VehicleParams) -> float:
    """Thruster power cruising at top speed (W): the horizontal pair at the limit, the
    vertical pair sharing the buoyancy margin."""
    hold = params.buoyancy_margin_n / 2.0
    t = params.thrust_max_n
    return thrust_power_w((t, t, hold, hold))


def endurance_s(battery: BatteryConfig, thrust_w: float) -> float:
    """Time from a full battery to the cut-off (s) at a constant thruster load (W): the fit
    with its linear term scaled by the load, as the twin's battery does."""
    load = (battery.hotel_power_w + thrust_w) / (
        battery.hotel_power_w + battery.nominal_thrust_power_w
    )

    def soc(t_h: float) -> float:
        return (
            100.0
            - SOC_LINEAR_PCT_PER_H * load * t_h
            - SOC_FAST_PCT * -math.expm1(-t_h / SOC_FAST_TAU_H)
        )

    lo, hi = 0.0, _MAX_HOURS
    for _ in range(60):
        mid = (lo + hi) / 2
        if soc(mid) > battery.cutoff_pct:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2 * 3600.0


@lru_cache(maxsize=8)
def _twin_figures(
    params: VehicleParams, battery: BatteryConfig
) -> tuple[float, float, float, float, float]:
    """(top speed m/s, heave m/s, yaw deg/s, endurance s, ascent m/s) of the twin; ~70 ms,
    once each."""
    return (
        top_speed_mps(params),
        heave_test(params),
        yaw_test(params),
        endurance_s(battery, cruise_thrust_power_w(params)),
        ascent_test(params),
    )


def twin_profile(
    max_depth_m: float,
    params: VehicleParams | None = None,
    battery: BatteryConfig | None = None,
) -> VehicleProfile:
    """The training twin's profile (its default parameters unless given)."""
    top, heave, yaw, endurance, ascent = _twin_figures(
        params or VehicleParams(), battery or BatteryConfig()
    )
    return VehicleProfile(top, heave, yaw, max_depth_m, endurance, "twin", ascent)


def profile_for(settings: Settings) -> VehicleProfile:
    """The vehicle's profile: the settings' figures, the twin's for those unset in training."""
    s = settings
    if not s.training:
        return VehicleProfile(
            s.top_speed_mps,
            s.heave_rate_mps,
            s.yaw_rate_dps,
            s.max_depth_m,
            s.endurance_s,
            "settings",
            s.ascent_rate_mps,
        )
    twin = twin_profile(s.max_depth_m)
    # the twin's ascent goes with its heave rate: a heave setting alone times ascents at it
    ascent = twin.ascent_rate_mps if s.heave_rate_mps is None else None
    return VehicleProfile(
        s.top_speed_mps if s.top_speed_mps is not None else twin.top_speed_mps,
        s.heave_rate_mps if s.heave_rate_mps is not None else twin.heave_rate_mps,
        s.yaw_rate_dps if s.yaw_rate_dps is not None else twin.yaw_rate_dps,
        s.max_depth_m,
        s.endurance_s if s.endurance_s is not None else twin.endurance_s,
        "twin",
        s.ascent_rate_mps if s.ascent_rate_mps is not None else ascent,
    )


# --- battery --------------------------------------------------------------------------------


def hours_run(soc_pct: float) -> float:
    """Hours of operation at nominal load that leave ``soc_pct`` (%) by the fit: its inverse
    (the fit falls monotonically), 0 for a full battery."""
    if not soc_pct < 100.0:
        return 0.0
    return _hours_to(paper_soc_pct, soc_pct, _MAX_HOURS)


def _hours_to(soc_of: Callable[[float], float], soc_pct: float, max_h: float) -> float:
    """When (h, within ``[0, max_h]``) a falling state-of-charge curve ``soc_of`` reaches
    ``soc_pct``: bisection, to well under a second."""
    lo, hi = 0.0, max_h
    for _ in range(60):
        mid = (lo + hi) / 2
        if soc_of(mid) > soc_pct:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


def battery_use_pct(duration_s: float, soc_pct: float | None = None) -> float:
    """State of charge a run of ``duration_s`` uses (percentage points), by the whole fit at
    nominal load, from a battery now at ``soc_pct`` (``None``: full, the dearest case)."""
    t0 = 0.0 if soc_pct is None else hours_run(soc_pct)
    return paper_soc_pct(t0) - paper_soc_pct(t0 + max(0.0, duration_s) / 3600.0)


def endurance_left_s(endurance_s: float, soc_pct: float | None, cutoff_pct: float = 0.0) -> float:
    """Time left at cruise (s) from a battery now at ``soc_pct`` (%; None: full), for a vehicle
    whose full battery lasts ``endurance_s`` at cruise down to ``cutoff_pct``.

    The fit's shape (:func:`endurance_s`): its linear term set so that a full battery reaches
    the cut-off at ``endurance_s`` (for the twin, exactly the cruise load the figure was found
    at; for a setting's figure, the load it implies), less the time that shape takes to fall
    from 100 % to ``soc_pct``. The fit's fast initial term is spent first: half the charge
    left is less than half the endurance.
    """
    if soc_pct is None or soc_pct >= 100.0:
        return endurance_s
    if soc_pct <= cutoff_pct or endurance_s <= 0.0:
        return 0.0
    total_h = endurance_s / 3600.0
    fast_pct = SOC_FAST_PCT * -math.expm1(-total_h / SOC_FAST_TAU_H)
    linear_pct_per_h = max(0.0, (100.0 - cutoff_pct - fast_pct) / total_h)

    def soc(t_h: float) -> float:
        return 100.0 - linear_pct_per_h * t_h - SOC_FAST_PCT * -math.expm1(-t_h / SOC_FAST_TAU_H)

    return max(0.0, endurance_s - _hours_to(soc, soc_pct, total_h) * 3600.0)
