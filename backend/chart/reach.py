"""The ME link's reach along a path, and the lat/lon fields documents carry beside x/y.

Link reach (after Cockpit's ``missionPathSignal``, for an ME link): every waypoint's slant
range from the transmitter (at the surface, the station's NED position) to the waypoint
(depth included, as the simulator's channel measures it) is classed ``in_range`` (up to
75 % of ``me_range_m``), ``marginal`` (75 to 100 %) or ``out_of_range``; runs of one class
are segments of waypoint indices. Between two waypoints the range is largest at one of
them (the distance to a point is convex along a straight leg), so the worst class over the
waypoints is the worst along the path. A path that leaves range gets a warning in words:
a command sent while the vehicle is out there would not reach it. The send checks
(:mod:`backend.commands.checks`) make it an overridable violation from the same distances: the
operator may mean it (a Surface still works once it is back).

Lat/lon: every conversion goes through :mod:`backend.chart.geo`, a whole path in one call.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Final, Literal

import numpy as np
import numpy.typing as npt

from backend.chart.geo import Datum, ned_to_geodetic
from backend.chart.gps import Station

TYPE_CHECKING = False
if TYPE_CHECKING:
    from planner import Plan

#: Beyond this fraction of the range the link is marginal (Cockpit's 75 %).
MARGINAL_FRACTION: Final = 0.75
#: Farthest NED offset given a lat/lon (m): a local frame 10,000 km wide is no frame at all,
#: and a vehicle reporting 1e30 m must not make NaN of the page's numbers.
MAX_LOCAL_M: Final = 1e7

ReachState = Literal["in_range", "marginal", "out_of_range"]
_STATES: Final[tuple[ReachState, ...]] = ("in_range", "marginal", "out_of_range")


def lat_lon(
    datum: Datum | None, xs: Sequence[float], ys: Sequence[float]
) -> tuple[list[float] | None, list[float] | None]:
    """Latitudes and longitudes (deg) of NED points, in one conversion; (None, None) without
    a datum, or when a point is too far to be one (:data:`MAX_LOCAL_M`)."""
    if datum is None:
        return None, None
    x = np.asarray(xs, dtype=np.float64)
    y = np.asarray(ys, dtype=np.float64)
    if x.size and not (np.abs(x).max() <= MAX_LOCAL_M and np.abs(y).max() <= MAX_LOCAL_M):
        return None, None
    lat, lon = ned_to_geodetic(datum, x, y)
    if not (np.isfinite(lat).all() and np.isfinite(lon).all()):
        return None, None
    return lat.tolist(), lon.tolist()


def point_lat_lon(
    datum: Datum | None, x_m: float | None, y_m: float | None
) -> tuple[float | None, float | None]:
    """One point's latitude and longitude (deg); None without a datum or a position."""
    if datum is None or x_m is None or y_m is None:
        return None, None
    if not (abs(x_m) <= MAX_LOCAL_M and abs(y_m) <= MAX_LOCAL_M):
        return None, None  # a vehicle reporting nonsense (1e30 m) is no place on the Earth
    lat, lon = ned_to_geodetic(datum, x_m, y_m)
    if not (np.isfinite(lat) and np.isfinite(lon)):
        return None, None
    return float(lat), float(lon)


def with_lat_lon(point: dict[str, Any], datum: Datum | None) -> dict[str, Any]:
    """``point`` (a pose, a track point: ``x_m``, ``y_m``) with ``lat_deg`` and ``lon_deg``."""
    lat, lon = point_lat_lon(datum, point.get("x_m"), point.get("y_m"))
    point["lat_deg"], point["lon_deg"] = lat, lon
    return point


def track_lat_lon(track: list[dict[str, Any]], datum: Datum | None) -> list[dict[str, Any]]:
    """Track points (``x_m``, ``y_m``) with ``lat_deg``/``lon_deg``, in one conversion."""
    lats, lons = lat_lon(datum, [p["x_m"] for p in track], [p["y_m"] for p in track])
    for i, p in enumerate(track):
        p["lat_deg"] = None if lats is None else lats[i]
        p["lon_deg"] = None if lons is None else lons[i]
    return track


def distances_m(
    xs: Sequence[float], ys: Sequence[float], zs: Sequence[float], station: Station
) -> npt.NDArray[np.float64] | None:
    """Every waypoint's slant range from the transmitter (m); None when the station's NED
    position is not known (its lat/lon is, but there is no datum to place it) or a distance is
    not finite (a vehicle reporting 1e200 m)."""
    if station.x_m is None or station.y_m is None:
        return None
    dx = np.asarray(xs, dtype=np.float64) - station.x_m
    dy = np.asarray(ys, dtype=np.float64) - station.y_m
    dz = np.asarray(zs, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        distance = np.sqrt(dx * dx + dy * dy + dz * dz)
    return distance if np.isfinite(distance).all() else None


def out_of_range_message(farthest_m: float, range_m: float) -> str:
    """The sentence for a path that leaves the ME range (the chart's warning, the check's
    violation: one wording)."""
    return (
        f"the path goes {farthest_m:,.0f} m from the transmitter, beyond the ME link's "
        f"{range_m:,.0f} m range: the next retask could not reach the vehicle there"
    )


def link_reach(
    xs: Sequence[float],
    ys: Sequence[float],
    zs: Sequence[float],
    station: Station,
    range_m: float,
) -> dict[str, Any] | None:
    """The path's reach from the transmitter; None when the station's NED position is not
    known (its lat/lon is, but there is no datum to place it) or a distance is not finite."""
    distance = distances_m(xs, ys, zs, station)
    if distance is None:
        return None
    marginal_m = MARGINAL_FRACTION * range_m
    classes = (distance > marginal_m).astype(np.int8) + (distance > range_m).astype(np.int8)
    segments: list[dict[str, Any]] = []
    if classes.size:
        cuts = np.flatnonzero(np.diff(classes)) + 1
        starts = np.concatenate(([0], cuts))
        ends = np.concatenate((cuts - 1, [classes.size - 1]))
        segments = [
            {"state": _STATES[int(classes[s])], "start": int(s), "end": int(e)}
            for s, e in zip(starts, ends, strict=True)
        ]
    worst = int(classes.max()) if classes.size else 0
    farthest = float(distance.max()) if distance.size else 0.0
    warning = out_of_range_message(farthest, range_m) if worst == 2 else None
    return {
        "range_m": range_m,
        "marginal_m": marginal_m,
        "station_x_m": station.x_m,
        "station_y_m": station.y_m,
        "max_distance_m": farthest,
        "state": _STATES[worst],
        "segments": segments,
        "warning": warning,
    }


def add_geo(doc: dict[str, Any], datum: Datum | None, station: Station, range_m: float) -> None:
    """A preview document's path gets ``lat_deg``/``lon_deg``, the document ``link_reach``."""
    path = doc["path"]
    path["lat_deg"], path["lon_deg"] = lat_lon(datum, path["x_m"], path["y_m"])
    doc["link_reach"] = link_reach(path["x_m"], path["y_m"], path["z_m"], station, range_m)


def active_path_doc(active: Plan, datum: Datum | None) -> dict[str, Any]:
    """The path the vehicle flies, for the chart: pattern, NED columns (m) and lat/lon (deg)."""
    p = active.path
    lat, lon = lat_lon(datum, p.xs, p.ys)
    return {
        "pattern": active.pattern,
        "x_m": list(p.xs),
        "y_m": list(p.ys),
        "z_m": list(p.zs),
        "lat_deg": lat,
        "lon_deg": lon,
    }
