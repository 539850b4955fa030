"""Dead reckoning: the vehicle run forward from its last fix along the plan it flies (pure).

The vehicle's guidance follows the plan's path at the plan's speed through the water
(line-of-sight path following, :mod:`onboard.guidance`), so the twin used here is the planner's
own plan (:func:`planner.plan`, the one the vehicle replans with), not a clock: the fix is
placed on the path (:func:`plan_time_at`: the time along the plan of the nearest point), and
the vehicle advances along the path from there (:func:`run_along`). A water current changes
its speed over ground: the part along the path adds to it, the part across it is crabbed
against (``sqrt(v^2 - c_across^2)``). Integrated in steps of :data:`STEP_S`: 0.4 ms for a
minute without telemetry, 2.6 ms for ten (at most :data:`MAX_STEPS` steps); the simulated
twin costs 0.8-1.7 ms per simulated second on this machine, 50-100 ms for the same minute
and growing with the time without telemetry, and the belief is pushed every second while
dead-reckoning (``nemesys bench dead_reckoning`` measures both).

The uncertainty (:func:`sigma_m`, one standard deviation of the horizontal error) grows from
the fix's own (:data:`FIX_SIGMA_M`, and how far the vehicle was off the path) with the
distance run (:data:`MODEL_ERROR_FRACTION`: turns, speed) and with time (the current's
uncertainty: the estimate's drift in training, :data:`CURRENT_SIGMA_MPS` otherwise), in
quadrature; when the command itself is uncertain, :func:`spread_m` adds the spread of the
candidates' positions.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Final

from codec._record import Record, init
from planner import Plan, VehicleState

__all__ = [
    "CURRENT_MODEL_FRACTION",
    "CURRENT_SIGMA_MPS",
    "FIX_SIGMA_M",
    "MODEL_ERROR_FRACTION",
    "SHARP_TURN_DEG",
    "STEP_S",
    "TURN_ERROR_M_PER_RAD",
    "UNKNOWN_CURRENT",
    "Current",
    "Reckoned",
    "off_path_m",
    "plan_time_at",
    "run_along",
    "sigma_m",
    "spread_m",
]

#: The navigation uncertainty of a reported fix (m, one standard deviation): assumed, the
#: vehicle does not report one.
FIX_SIGMA_M: Final = 0.25
#: The twin's model error per metre run along the plan (speed, smooth turns): 3 %, twice what
#: the simulator showed over 60 s of circle (bench/dead_reckoning.py).
MODEL_ERROR_FRACTION: Final = 0.03
#: The model error per radian of sharp turn (a corner of the path, more than
#: :data:`SHARP_TURN_DEG` in one step): guidance cuts corners by about (2 - pi/2) / (pi/2) of
#: its 1.5 m lookahead per radian, and the vehicle is then ahead of the plan (m/rad).
TURN_ERROR_M_PER_RAD: Final = 0.5
SHARP_TURN_DEG: Final = 20.0
#: Guidance starts a corner this far before it (its lookahead, m): the corners that near
#: ahead of the reckoned point count as taken.
CORNER_LEAD_M: Final = 1.5
#: The model error per metre the known current carries the vehicle: all of it (the crab
#: against it and the turns in it are not flown as modelled; half was not enough for the
#: lawnmower in bench/dead_reckoning.py).
CURRENT_MODEL_FRACTION: Final = 1.0
#: The water current's uncertainty when nothing estimates it (m/s): assumed.
CURRENT_SIGMA_MPS: Final = 0.05
#: Integration step along the plan (vehicle seconds); longer runs take longer steps so that a
#: run never takes more than :data:`MAX_STEPS`.
STEP_S: Final = 1.0
MAX_STEPS: Final = 600


class Current(Record):
    """The water current as estimated (NED m/s over ground) and its uncertainty (m/s)."""

    __slots__ = ("east_mps", "north_mps", "sigma_mps", "what")
    north_mps: float
    east_mps: float
    sigma_mps: float
    what: str

    def __init__(self, north_mps: float, east_mps: float, sigma_mps: float, what: str) -> None:
        init(self, "north_mps", float(north_mps))
        init(self, "east_mps", float(east_mps))
        init(self, "sigma_mps", float(sigma_mps))
        init(self, "what", what)


#: No estimate: no current, with the assumed uncertainty.
UNKNOWN_CURRENT: Final = Current(0.0, 0.0, CURRENT_SIGMA_MPS, "no current estimate")


class Reckoned(Record):
    """Where the run along a plan ends: the state there, the time along the plan reached,
    the distance run over ground (m) and the sharp turns taken on the way (rad)."""

    __slots__ = ("distance_m", "state", "tau_s", "turned_rad")
    state: VehicleState
    tau_s: float
    distance_m: float
    turned_rad: float

    def __init__(
        self, state: VehicleState, tau_s: float, distance_m: float, turned_rad: float = 0.0
    ) -> None:
        init(self, "state", state)
        init(self, "tau_s", tau_s)
        init(self, "distance_m", distance_m)
        init(self, "turned_rad", turned_rad)


def plan_time_at(plan: Plan, state: VehicleState) -> float:
    """The time along ``plan`` (s after it took effect) of the path point nearest the vehicle
    (among passes of the same place, the one nearest its clock), and how far off it was (m)
    is :func:`off_path_m`."""
    path = plan.path
    if len(path) == 1:
        return 0.0
    index = path.locate(state.x_m, state.y_m, state.z_m, state.segment, state.t_s - plan.t0_s)
    i = min(int(index), len(path) - 2)
    f = index - i
    return path.times[i] + f * (path.times[i + 1] - path.times[i])


def off_path_m(plan: Plan, state: VehicleState, tau_s: float) -> float:
    """Horizontal distance (m) from the vehicle to the plan's point at ``tau_s``."""
    sp = plan.path.sample(tau_s)
    return math.hypot(sp.x_m - state.x_m, sp.y_m - state.y_m)


def run_along(
    plan: Plan, tau_s: float, elapsed_s: float, current: Current, t_s: float = 0.0
) -> Reckoned:
    """The vehicle ``elapsed_s`` (vehicle seconds) further along ``plan`` from ``tau_s``.

    ``t_s``: its mission clock at ``tau_s`` (the result's state is stamped ``t_s +
    elapsed_s``). Past the end of a finite plan it holds the last point; a repeating plan
    wraps into its lap (:meth:`planner.Path.sample`).
    """
    elapsed = max(0.0, elapsed_s)
    steps = max(1, min(MAX_STEPS, math.ceil(elapsed / STEP_S)))
    h = elapsed / steps
    tau, distance, turned = tau_s, 0.0, 0.0
    cn, ce = current.north_mps, current.east_mps
    last: float | None = None
    sharp = math.radians(SHARP_TURN_DEG)
    for _ in range(steps if elapsed > 0 else 0):
        sp = plan.path.sample(tau)
        v = sp.speed_mps
        if v <= 1e-9:  # holding (a hover, the end of a finite plan): the plan's clock runs
            tau += h
            continue
        course = math.radians(sp.course_deg)
        if last is not None:
            turn = abs(math.remainder(course - last, math.tau))
            turned += turn if turn > sharp else 0.0
        last = course
        along = cn * math.cos(course) + ce * math.sin(course)
        across = -cn * math.sin(course) + ce * math.cos(course)
        ground = max(0.0, math.sqrt(max(0.0, v * v - across * across)) + along)
        tau += h * ground / v
        distance += h * ground
    sp = plan.path.sample(tau)
    state = VehicleState(sp.x_m, sp.y_m, sp.z_m, sp.course_deg, sp.speed_mps, t_s + elapsed)
    return Reckoned(state, tau, distance, turned + _corners_ahead(plan, tau, last))


def _corners_ahead(plan: Plan, tau_s: float, course: float | None) -> float:
    """Sharp turns (rad) within :data:`CORNER_LEAD_M` of path ahead of ``tau_s``."""
    sharp, turned, ahead, tau = math.radians(SHARP_TURN_DEG), 0.0, 0.0, tau_s
    for _ in range(100):
        sp = plan.path.sample(tau)
        if sp.speed_mps <= 1e-9 or ahead >= CORNER_LEAD_M:
            break
        now = math.radians(sp.course_deg)
        if course is not None:
            turn = abs(math.remainder(now - course, math.tau))
            turned += turn if turn > sharp else 0.0
        course = now
        step = min(STEP_S, (CORNER_LEAD_M - ahead) / sp.speed_mps + 1e-6)
        tau += step
        ahead += step * sp.speed_mps
    return turned


def sigma_m(
    elapsed_s: float,
    run: Reckoned | None = None,
    *,
    off_path: float = 0.0,
    current: Current = UNKNOWN_CURRENT,
    unknown_speed_mps: float = 0.0,
) -> float:
    """The horizontal uncertainty (m) after ``elapsed_s`` vehicle seconds of ``run`` (None:
    no run, the vehicle held): the fix's own, how far off the path the vehicle was at the fix,
    the model's error (distance, sharp turns, the known current) and the current's
    uncertainty over the time, in quadrature; ``unknown_speed_mps``: the plan is not known,
    the vehicle may have gone anywhere at up to this speed (added in full)."""
    t = max(0.0, elapsed_s)
    distance = run.distance_m if run is not None else 0.0
    turned = run.turned_rad if run is not None else 0.0
    drift = math.hypot(current.north_mps, current.east_mps)
    terms = (
        FIX_SIGMA_M,
        MODEL_ERROR_FRACTION * distance,
        TURN_ERROR_M_PER_RAD * turned,
        CURRENT_MODEL_FRACTION * drift * t,
        current.sigma_mps * t,
    )
    # the offset from the path and an unknown plan's reach add in full: the vehicle's error
    # is at most the offset plus the error along the path (the triangle inequality)
    return math.sqrt(sum(x * x for x in terms)) + off_path + unknown_speed_mps * t


def spread_m(candidates: Sequence[tuple[float, float, float]], x_m: float, y_m: float) -> float:
    """The root of the probability-weighted mean squared distance (m) from ``(x_m, y_m)`` of
    the candidates' positions ``(p, x_m, y_m)``: what the command's own uncertainty adds."""
    total = sum(p * ((x - x_m) ** 2 + (y - y_m) ** 2) for p, x, y in candidates)
    return math.sqrt(max(0.0, total))
