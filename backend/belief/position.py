"""Where the vehicle probably is: the last fix while telemetry is fresh, else the fix run
forward under the candidate commands, else a start that is assumed (and says so).

**Fresh** (:data:`FRESH_TELEMETRY_S`): the fix is at most 3 s old on the vehicle's clock
(the training simulator's clock; else the console's age of it): the link health's
telemetry turns stale at the same 3 s. The vehicle publishes its pose at 10-20 Hz; a fix
that old means the telemetry stopped, not that one message was late.

Run forward (:mod:`backend.belief.reckoning`): the last known state's motion (the plan the
vehicle flies, as the console mirrors it from its acknowledgement; holding; or, when its plan
is not known, anywhere within its top speed) up to when a candidate command's first copy left,
then that command planned from there (:func:`planner.plan`, the vehicle's own replan, joining
from the last known plan); every candidate with ``p`` of at least :data:`MIN_P` is run, the
most probable gives the position, and the others' distance from it adds to the uncertainty
(:func:`backend.belief.reckoning.spread_m`). With no fix ever, the same runs start from the
assumed start: the position is then ``assumed``, its uncertainty unknown (null).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final

from backend.belief.commands import Candidate, same_command
from backend.belief.model import BelievedPosition
from backend.belief.reckoning import (
    FIX_SIGMA_M,
    Current,
    Reckoned,
    off_path_m,
    plan_time_at,
    run_along,
    sigma_m,
    spread_m,
)
from backend.chart.geo import Datum
from backend.chart.reach import point_lat_lon
from codec import ADDRESSED_FRAME_BITS, decode_addressed_frame, decode_frame
from onboard.agent import command_json
from onboard.guidance import GuidanceConfig
from planner import Plan, PlanError, VehicleState, plan

__all__ = ["FRESH_TELEMETRY_S", "MIN_P", "Fix", "Start", "believe_position"]

#: A fix at most this old on the vehicle's clock (s) is fresh: the position is the fix.
FRESH_TELEMETRY_S: Final = 3.0
#: How far a holding vehicle drifts before it approaches its hold point again (m): the
#: guidance's capture radius.
HOLD_DRIFT_M: Final = GuidanceConfig().capture_m
#: Candidates less probable than this are not run (their share of the spread is below 1 %
#: of their distance).
MIN_P: Final = 1e-4


@dataclass(frozen=True, slots=True)
class Fix:
    """The vehicle's last reported state, when it arrived (console clock, epoch s) and what
    reported it (``pose``, or the state an ``acknowledgement`` planned from)."""

    state: VehicleState
    at_s: float
    what: str


@dataclass(frozen=True, slots=True)
class Start:
    """The start assumed when no fix ever came, and what it is in words."""

    state: VehicleState
    what: str


@functools.lru_cache(maxsize=64)
def _planned(bits: str, state: VehicleState, base: Plan | None) -> Plan:
    """A record's command (decoded from its bits, as the vehicle decodes it: a fleet's frame
    is addressed) planned from ``state`` while running ``base``."""
    if len(bits) == ADDRESSED_FRAME_BITS:
        return plan(decode_addressed_frame(bits).command, state, base)
    return plan(decode_frame(bits).command, state, base)


class _Base:
    """The last known state's motion from the fix (or the assumed start), by vehicle time."""

    def __init__(
        self,
        origin: VehicleState,
        known: Candidate | None,
        mirror: Plan | None,
        current: Current,
        unknown_speed_mps: float,
    ) -> None:
        self.origin = origin
        self.current = current  # what carries the vehicle along a plan
        self.own_current = current  # what adds to the base's own uncertainty
        self.plan: Plan | None = None
        self.tau0 = 0.0
        self.off_m = 0.0
        self.unknown_speed_mps = 0.0
        belief = known.belief if known is not None else None
        echoed = None if belief is None else {"pattern": belief.pattern, "params": belief.params}
        if mirror is not None and same_command(echoed, command_json(mirror.command)):
            self.plan = mirror
            self.tau0 = plan_time_at(mirror, origin)
            self.off_m = off_path_m(mirror, origin, self.tau0)
            self.words = f"along {mirror.pattern} (the plan it acknowledged)"
        elif belief is not None and belief.kind == "last_known" and belief.pattern is None:
            # it keeps station: the current does not carry it off, but it lets it drift to its
            # capture radius before it approaches its hold point again
            self.own_current = Current(0.0, 0.0, 0.0, "held against")
            self.off_m = HOLD_DRIFT_M
            self.words = "holding (as last reported)"
        else:
            self.unknown_speed_mps = unknown_speed_mps
            self.words = f"its plan unknown: anywhere within {unknown_speed_mps:.2f} m/s"

    def at(self, elapsed_s: float) -> tuple[VehicleState, Reckoned | None]:
        if self.plan is None:
            o = self.origin
            return VehicleState(o.x_m, o.y_m, o.z_m, o.heading_deg, 0.0, o.t_s + elapsed_s), None
        run = run_along(self.plan, self.tau0, elapsed_s, self.current, self.origin.t_s)
        return run.state, run


def _run(
    c: Candidate, base: _Base, total: float, now_s: float, scale: float
) -> tuple[VehicleState, float, str]:
    """Where candidate ``c`` has the vehicle now, ``total`` vehicle seconds after the fix (0:
    no fix): (state, uncertainty m, in words)."""
    record = c.record
    if c.last_known or c.sent_s is None or record is None:
        state, run = base.at(total)
        sigma = sigma_m(
            total,
            run,
            off_path=base.off_m,
            current=base.own_current,
            unknown_speed_mps=base.unknown_speed_mps,
        )
        return state, sigma, base.words
    since = max(0.0, (now_s - c.sent_s) * scale)  # vehicle seconds since its first copy left
    start = max(0.0, total - since)
    state0, run0 = base.at(start)
    try:
        planned = _planned(str(record["bits"]), state0, base.plan)
    except (PlanError, ValueError) as err:  # sent, so planned before: a bookkeeping oddity
        return state0, sigma_m(total, run0, unknown_speed_mps=base.unknown_speed_mps), str(err)
    run = run_along(planned, 0.0, since, base.current, state0.t_s)
    both = Reckoned(
        run.state,
        run.tau_s,
        run.distance_m + (run0.distance_m if run0 else 0.0),
        run.turned_rad + (run0.turned_rad if run0 else 0.0),
    )
    sigma = sigma_m(
        max(total, since),
        both,
        off_path=base.off_m,
        current=base.current,
        unknown_speed_mps=base.unknown_speed_mps * start / max(total, 1e-9),
    )
    words = f"{planned.pattern} (command {record['id']}) since its first copy left"
    return run.state, sigma, words


def believe_position(
    candidates: Sequence[Candidate],
    *,
    fix: Fix | None,
    start: Start,
    mirror: Plan | None,
    now_s: float,
    time_scale: float,
    current: Current,
    datum: Datum | None,
    top_speed_mps: float,
    vehicle_now_s: float | None = None,
) -> BelievedPosition:
    """The believed position (see the module's doc); ``candidates`` most probable first.

    ``now_s``: the console's clock (epoch s); ``vehicle_now_s``: the vehicle's mission clock
    now when the console knows it (the training simulator's), else it is the fix's advanced
    by the console's clock times ``time_scale``."""
    age_s = None if fix is None else max(0.0, now_s - fix.at_s)
    total = 0.0  # vehicle seconds since the fix
    if fix is not None and age_s is not None:
        total = age_s * time_scale
        if vehicle_now_s is not None:
            total = max(0.0, vehicle_now_s - fix.state.t_s)
    if fix is not None and age_s is not None and total <= FRESH_TELEMETRY_S:
        s = fix.state
        return _position(
            s,
            FIX_SIGMA_M + s.speed_mps * total,
            "telemetry",
            age_s,
            datum,
            f"the last fix ({fix.what}), {age_s:.1f} s ago",
        )
    known = next((c for c in candidates if c.last_known), None)
    origin = fix.state if fix is not None else start.state
    base = _Base(origin, known, mirror, current, top_speed_mps)
    runs = [
        (c.belief.p, *_run(c, base, total, now_s, time_scale))
        for c in candidates
        if c is candidates[0] or c.belief.p >= MIN_P
    ]
    _p, state, sigma, words = runs[0]
    spread = spread_m([(p, s.x_m, s.y_m) for p, s, _, _ in runs[1:]], state.x_m, state.y_m)
    top = candidates[0]
    if fix is None:
        basis = f"{start.what}, no fix ever"
        if not top.last_known:  # the start, then the believed command from there
            basis += f"; then {words} (p {top.belief.p:.4g})"
        return _position(state, None, "assumed", None, datum, basis)
    basis = f"the last fix ({fix.what}) {age_s:.1f} s ago, then {words}"
    if not top.last_known:
        basis += f" (p {top.belief.p:.4g})"
    overall = (sigma * sigma + spread * spread) ** 0.5
    return _position(state, overall, "dead_reckoning", age_s, datum, basis)


def _position(
    s: VehicleState,
    sigma: float | None,
    source: Any,
    age_s: float | None,
    datum: Datum | None,
    basis: str,
) -> BelievedPosition:
    lat, lon = point_lat_lon(datum, s.x_m, s.y_m)
    doc: Mapping[str, Any] = {
        "x_m": s.x_m,
        "y_m": s.y_m,
        "z_m": s.z_m,
        "heading_deg": s.heading_deg,
        "speed_mps": s.speed_mps,
        "lat_deg": lat,
        "lon_deg": lon,
        "sigma_m": sigma,
        "source": source,
        "age_s": age_s,
        "t_s": s.t_s,
        "basis": basis,
    }
    return BelievedPosition.model_validate(doc)
