"""A fleet survey's input: the area (one lawnmower box in NED) and the vehicles that share it,
their checks, and the area's own frame and lanes.

The area is given as a lawnmower is flown: ``origin`` is the corner where its first lane
starts, the lanes run along ``heading_deg`` for ``length_m``, and the area extends ``width_m``
to starboard of that heading (heading + 90 deg), which is where a lawnmower puts its next
lanes (``planner._plan``). Positions in the area's own frame are ``along_m`` (on the lane
axis from the origin corner) and ``across_m`` (to starboard of it).

The area is cut into ``ceil(width / lane spacing)`` lanes, centred across the width, so that
the lane-spacing-wide strips around them cover it. Bad input is a :class:`SurveyError`
naming the field at fault and what is allowed; nothing is clamped.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from codec import DICTIONARY, EncodeError, NumericScale
from vehicle_contract.fleet import ALL_VEHICLES, MAX_VEHICLES, NAME_PATTERN

#: The dictionary's lawnmower, whose fields the survey's blocks are sent as.
LAWNMOWER = DICTIONARY["lawnmower"]


def _largest_laps() -> int:
    scale = LAWNMOWER.field("laps").scale
    assert isinstance(scale, NumericScale)
    return int(scale.maximum)


#: Most laps one lawnmower flies (the count scale's last code): 2 lanes a lap.
MAX_LAPS = _largest_laps()
#: The area's fields as the lawnmower's parameters (what each is sent as).
AREA_PARAM = {
    "speed_mps": "speed",
    "depth_m": "depth",
    "length_m": "sweep_length",
    "lane_spacing_m": "lane_spacing",
}

Loc = tuple[str | int, ...]


class SurveyError(ValueError):
    """Input a survey cannot be made of. ``loc`` names the field at fault in the request
    (``("area", "length_m")``, ``("vehicles", 2, "x_m")``); the message says what is wrong and
    what is allowed."""

    def __init__(self, message: str, loc: Loc) -> None:
        super().__init__(message)
        self.loc = loc


@dataclass(frozen=True, slots=True)
class SurveyArea:
    """One lawnmower box (NED m, deg, m/s): see the module doc for its geometry."""

    origin_x_m: float
    origin_y_m: float
    heading_deg: float
    width_m: float
    length_m: float
    lane_spacing_m: float
    depth_m: float
    speed_mps: float


@dataclass(frozen=True, slots=True)
class SurveyVehicle:
    """A vehicle of the survey where it is believed to be (NED m; heading deg from north;
    ``z_m`` its depth, 0: at the surface)."""

    name: str
    x_m: float
    y_m: float
    heading_deg: float
    z_m: float = 0.0


@dataclass(frozen=True, slots=True)
class AreaFrame:
    """The area's own frame: ``along`` the lanes from the origin corner, ``across`` to
    starboard (m)."""

    origin_x_m: float
    origin_y_m: float
    heading_deg: float

    @property
    def axis(self) -> tuple[float, float]:
        """The lane axis as a unit vector (north, east)."""
        h = math.radians(self.heading_deg)
        return math.cos(h), math.sin(h)

    def to_local(self, x_m: float, y_m: float) -> tuple[float, float]:
        """NED ``(x, y)`` -> ``(along, across)`` (m)."""
        ux, uy = self.axis
        dx, dy = x_m - self.origin_x_m, y_m - self.origin_y_m
        return dx * ux + dy * uy, -dx * uy + dy * ux

    def to_ned(self, along_m: float, across_m: float) -> tuple[float, float]:
        """``(along, across)`` -> NED ``(x, y)`` (m)."""
        ux, uy = self.axis
        return (
            self.origin_x_m + along_m * ux - across_m * uy,
            self.origin_y_m + along_m * uy + across_m * ux,
        )


def frame_of(area: SurveyArea) -> AreaFrame:
    return AreaFrame(area.origin_x_m, area.origin_y_m, area.heading_deg % 360.0)


def lane_count(area: SurveyArea) -> int:
    """Lanes needed for the strips around them to cover the width: ``ceil(width / spacing)``
    (a width within a millimetre of whole lanes is whole lanes)."""
    return max(1, math.ceil(area.width_m / area.lane_spacing_m - 1e-3 / area.lane_spacing_m))


def area_lanes(area: SurveyArea) -> tuple[float, ...]:
    """The lanes' across offsets (m), centred across the width, ``lane_spacing_m`` apart."""
    n, s = lane_count(area), area.lane_spacing_m
    first = (area.width_m - (n - 1) * s) / 2.0
    return tuple(first + i * s for i in range(n))


@dataclass(frozen=True, slots=True)
class SentArea:
    """The area's values as every block's lawnmower sends them (snapped to the scales)."""

    speed_mps: float
    depth_m: float
    length_m: float
    lane_spacing_m: float


def check_area(area: SurveyArea) -> SentArea:
    """The area as lawnmower parameters: each within its 8-bit scale and not sent as 0.

    Raises:
        SurveyError: naming the area's field, its value as sent and the scale's range.
    """
    for name in ("origin_x_m", "origin_y_m", "heading_deg", "width_m"):
        value = getattr(area, name)
        if not math.isfinite(value) or (name == "width_m" and value <= 0.0):
            what = "a finite number above 0 m" if name == "width_m" else "a finite number"
            raise SurveyError(f"{name} {value!r}: allowed {what}", ("area", name))
    sent_values: dict[str, float] = {}
    for name, param in AREA_PARAM.items():
        value = getattr(area, name)
        field = LAWNMOWER.field(param)
        try:
            _, sent = field.snap(value)
        except EncodeError:
            allowed = field.scale.range_text(field.unit)
            raise SurveyError(
                f"{name} {value:g} {field.unit}: it is sent as the lawnmower's {param}, whose "
                f"8-bit scale allows {allowed}",
                ("area", name),
            ) from None
        if param != "depth" and isinstance(sent, int | float) and sent <= 0.0:
            scale = field.scale
            smallest = scale.values[1] if isinstance(scale, NumericScale) else 0.0
            raise SurveyError(
                f"{name} {value:g} is sent as 0 {field.unit} (the lawnmower's {param}); the "
                f"smallest it sends above 0 is {smallest:g} {field.unit}",
                ("area", name),
            )
        sent_values[name] = float(sent)
    return SentArea(**sent_values)


def check_vehicles(vehicles: Sequence[SurveyVehicle], lanes: int, area: SurveyArea) -> None:
    """1 to :data:`MAX_VEHICLES` vehicles with valid, unique names, and at least two lanes each
    (a lawnmower flies its lanes in out-and-back pairs), at most :data:`MAX_LAPS` pairs each.

    Raises:
        SurveyError: naming the fault and what is allowed.
    """
    n = len(vehicles)
    if n == 0:
        raise SurveyError(
            f"no vehicles: a survey is split among 1 to {MAX_VEHICLES} vehicles", ("vehicles",)
        )
    if n > MAX_VEHICLES:
        raise SurveyError(
            f"{n} vehicles: a survey is split among 1 to {MAX_VEHICLES} vehicles (one per frame "
            "address)",
            ("vehicles",),
        )
    seen: set[str] = set()
    for i, v in enumerate(vehicles):
        if not NAME_PATTERN.fullmatch(v.name) or v.name == ALL_VEHICLES:
            raise SurveyError(
                f"vehicle {v.name!r:.40}: a name is a lower-case letter, then up to 31 lower-case "
                f"letters, digits or underscores, and not {ALL_VEHICLES!r}",
                ("vehicles", i, "vehicle"),
            )
        if v.name in seen:
            raise SurveyError(
                f"vehicle {v.name} is given twice: each vehicle gets one block",
                ("vehicles", i, "vehicle"),
            )
        seen.add(v.name)
        for name in ("x_m", "y_m", "heading_deg", "z_m"):
            if not math.isfinite(getattr(v, name)):
                raise SurveyError(
                    f"vehicle {v.name}: {name} must be a finite number", ("vehicles", i, name)
                )
    where = f"width_m {area.width_m:g} at lane_spacing_m {area.lane_spacing_m:g}"
    if lanes < 2 * n:
        most = lanes // 2
        fewer = f" or use at most {most} vehicle{'s' if most != 1 else ''}" if most else ""
        raise SurveyError(
            f"the area has {lanes} lane{'s' if lanes != 1 else ''} ({where}); {n} "
            f"vehicle{'s' if n != 1 else ''} need at least {2 * n}: a lawnmower flies its lanes "
            f"in out-and-back pairs (laps >= 1). Widen the area, narrow the lane spacing{fewer}",
            ("vehicles",) if most else ("area", "width_m"),
        )
    if lanes > 2 * MAX_LAPS * n:
        raise SurveyError(
            f"the area has {lanes} lanes ({where}): {n} vehicle{'s' if n != 1 else ''} fly at "
            f"most {2 * MAX_LAPS * n} ({MAX_LAPS} laps of 2 lanes each, the laps scale's "
            "largest). Add vehicles, widen the lane spacing or narrow the area",
            ("area", "width_m"),
        )
