"""Operational limits: what a plan may not do, and the violations that stop a send.

Checks, each reported as a :class:`Violation` naming the parameter, its value and the limit:

* the vehicle's depth rating (:data:`RATED_DEPTH_M`, 100 m): never overridable;
* a configurable maximum depth (at most the rating) and maximum speed;
* the tightest circle the vehicle can hold at the commanded speed (radius >= the turn
  radius :func:`planner.turn_radius_m` gives at that speed);
* an optional geofence, a circle or a polygon fixed in the NED frame (the mission origin is
  ``(0, 0)``), which every waypoint of the plan, join included, must stay inside;
* the vehicle's top speed through the water (:func:`planner._checks.top_speed`,
  overridable): a command faster than the vehicle can fly is flown at top speed, slower
  than planned. The console checks it from its vehicle profile; it is not one of the
  onboard :class:`Limits`, so an operator's override reaches the vehicle.

:func:`planner.check` raises :class:`planner.LimitError` unless every violation is
overridable and the operator overrides explicitly. The geofences (:mod:`planner._fence`) and
the console's checks (:mod:`planner._checks`) are modules of their own: the vehicle validates
every plan but loads neither unless it is given a geofence (``nemesys bench reconfig``).
"""

from __future__ import annotations

from codec._record import Record, init
from planner._build import turn_radius_m
from planner._errors import Violation, finite_positive

TYPE_CHECKING = False
if TYPE_CHECKING:
    from planner._fence import CircleFence, PolygonFence
    from planner._plan import Plan

__all__ = [
    "DEFAULT_MAX_SPEED_MPS",
    "RATED_DEPTH_M",
    "Limits",
    "Violation",
    "finite_positive",
    "validate",
]

#: Depth rating of the NemeSys hull (m); no override can exceed it.
RATED_DEPTH_M = 100.0
#: Default maximum speed (m/s); an assumption, the paper gives no cruise speed.
DEFAULT_MAX_SPEED_MPS = 1.0

_DEPTH_PARAMS = ("depth", "start_depth", "end_depth")
_ROUND_PARAMS = {"circle": "radius", "helix": "radius"}


class Limits(Record):
    """Operational limits a plan is checked against.

    Attributes:
        max_depth_m: deepest allowed depth (m), at most :data:`RATED_DEPTH_M`.
        max_speed_mps: fastest allowed cruise speed (m/s).
        geofence: optional :class:`CircleFence` or :class:`PolygonFence`.
    """

    __slots__ = ("geofence", "max_depth_m", "max_speed_mps")
    max_depth_m: float
    max_speed_mps: float
    geofence: CircleFence | PolygonFence | None

    def __init__(
        self,
        max_depth_m: float = RATED_DEPTH_M,
        max_speed_mps: float = DEFAULT_MAX_SPEED_MPS,
        geofence: CircleFence | PolygonFence | None = None,
    ) -> None:
        finite_positive("max_depth_m", max_depth_m)
        if max_depth_m > RATED_DEPTH_M:
            raise ValueError(
                f"max_depth_m {max_depth_m:g} m exceeds the vehicle's {RATED_DEPTH_M:g} m rating"
            )
        init(self, "max_depth_m", float(max_depth_m))
        init(self, "max_speed_mps", finite_positive("max_speed_mps", max_speed_mps))
        init(self, "geofence", geofence)


def validate(plan: Plan, limits: Limits) -> tuple[Violation, ...]:
    """Every limit ``plan`` breaks (empty if none)."""
    out: list[Violation] = []
    params = plan.command.params
    for name in _DEPTH_PARAMS:
        value = params.get(name)
        if not isinstance(value, float | int):
            continue
        if value > RATED_DEPTH_M:
            out.append(
                Violation(
                    name,
                    value,
                    RATED_DEPTH_M,
                    "m",
                    f"{name} {value:g} m is deeper than the vehicle's {RATED_DEPTH_M:g} m "
                    "rating (cannot be overridden)",
                    overridable=False,
                )
            )
        elif value > limits.max_depth_m:
            out.append(
                Violation(
                    name,
                    value,
                    limits.max_depth_m,
                    "m",
                    f"{name} {value:g} m is deeper than the maximum depth {limits.max_depth_m:g} m",
                )
            )
    speed = params.get("speed")
    if isinstance(speed, float | int):
        if speed > limits.max_speed_mps:
            out.append(
                Violation(
                    "speed",
                    speed,
                    limits.max_speed_mps,
                    "m/s",
                    f"speed {speed:g} m/s is faster than the maximum speed "
                    f"{limits.max_speed_mps:g} m/s",
                )
            )
        key = _ROUND_PARAMS.get(plan.pattern)
        radius = params.get(key) if key else None
        if key and isinstance(radius, float | int) and 0 < radius < turn_radius_m(speed):
            tight = turn_radius_m(speed)
            out.append(
                Violation(
                    key,
                    radius,
                    tight,
                    "m",
                    f"{key} {radius:g} m is tighter than the {tight:.2f} m the vehicle can turn "
                    f"at {speed:g} m/s: slow down or widen it",
                )
            )
    if limits.geofence is not None:
        from planner._fence import fence_violations  # only a vehicle given a geofence

        out.extend(fence_violations(plan, limits.geofence))
    return tuple(out)
