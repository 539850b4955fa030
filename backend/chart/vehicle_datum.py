"""The vehicle's datum against the console's own.

A geo-referenced vehicle publishes the latitude and longitude of its ``map_ned`` origin on the
contract's datum topic (``/nemesys/datum``, schema ``datum``); every pose it sends is about that
point. The console draws poses, tracks, previews and the fence about its own datum
(:mod:`backend.chart.geo`). When the two differ every position on the chart is off by the
distance between them, so :class:`DatumWatch` names it: a link health problem while it lasts,
and a mission log event each time it begins. A console with no datum yet takes the vehicle's.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Final

from backend.chart.geo import Datum, dm, geodetic_to_ned
from vehicle_contract.messages import number

#: Datums closer than this are the same (m): about a GPS fix's own scatter.
DATUM_TOLERANCE_M: Final = 2.0

#: A mission log event: (kind, detail, data).
Event = tuple[str, str, dict[str, Any]]


def datum_of(msg: Mapping[str, Any]) -> Datum | None:
    """The datum a datum message gives (None: no latitude and longitude in range)."""
    lat, lon = number(msg.get("lat_deg")), number(msg.get("lon_deg"))
    if lat is None or lon is None:
        return None
    try:
        return Datum(lat, lon)
    except ValueError:
        return None


def _where(datum: Datum) -> str:
    return f"{dm(datum.lat_deg, lat=True)} {dm(datum.lon_deg, lat=False)}"


def offset_m(ours: Datum, theirs: Datum) -> float:
    """How far the vehicle's datum is from the console's (m, along the surface)."""
    north_m, east_m = geodetic_to_ned(ours, theirs.lat_deg, theirs.lon_deg)
    return math.hypot(north_m, east_m)


class DatumWatch:
    """The vehicle's latest datum, and whether it differs from the console's."""

    def __init__(self) -> None:
        #: The vehicle's datum (None: it sent none, or nothing usable).
        self.vehicle: Datum | None = None
        #: Where the vehicle took it from (the message's ``source``).
        self.source: str | None = None
        self._flagged = False  # a mismatch is logged once each time it begins

    def problem(self, ours: Datum | None) -> str | None:
        """The mismatch in words (a link health problem), None when there is none."""
        theirs = self.vehicle
        if theirs is None or ours is None:
            return None
        off_m = offset_m(ours, theirs)
        if off_m <= DATUM_TOLERANCE_M:
            return None
        return (
            f"the vehicle's datum ({_where(theirs)}, from its {self.source}) is {off_m:.0f} m "
            f"from the console's ({_where(ours)}): its positions are drawn {off_m:.0f} m off; "
            "set one datum to the other (PUT /api/datum, or the vehicle's datum parameters)"
        )

    def on_message(self, msg: Mapping[str, Any], ours: Datum | None) -> Event | None:
        """Take a datum message; the event to log, if any: ``datum`` when the console has no
        datum yet (the caller adopts :attr:`vehicle`), ``datum_mismatch`` when one begins."""
        theirs = datum_of(msg)
        if theirs is None:
            return None
        self.vehicle = theirs
        self.source = str(msg.get("source") or "settings")
        data: dict[str, Any] = {
            "lat_deg": theirs.lat_deg,
            "lon_deg": theirs.lon_deg,
            "source": "vehicle",
            "vehicle_source": self.source,
            "previous": None,
        }
        if ours is None:
            return "datum", f"datum set from the vehicle: {_where(theirs)}", data
        problem = self.problem(ours)
        if problem is None or self._flagged:
            self._flagged = problem is not None
            return None
        self._flagged = True
        data["console"] = {"lat_deg": ours.lat_deg, "lon_deg": ours.lon_deg}
        data["offset_m"] = offset_m(ours, theirs)
        return "datum_mismatch", problem, data
