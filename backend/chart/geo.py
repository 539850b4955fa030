"""The geo reference: where the NED origin is on the Earth, and the one edge to latitude/longitude.

All logic works in NED metres (``x`` north, ``y`` east, ``z`` down) from the mission origin.
The chart, the operator's lat/lon readouts and the API's ``lat_deg``/``lon_deg`` fields are
the only places that need the Earth; they all go through :func:`ned_to_geodetic`, and the
surface GPS comes back in through :func:`geodetic_to_ned`. Both are WGS84, through pyproj.

Why pyproj (PROJ): the conversion sits on the preview's hot path (bench: p50 <= 5 ms at 20
clients). PROJ's topocentric pipeline (geodetic <-> ECEF <-> local east/north/up about the
datum, exact, no small-angle approximation) runs in C: a cached transformer per datum
converts a preview's path in ~0.02 ms. pymap3d, pure Python, did the same in ~0.2-0.3 ms
(numpy overhead of its iterative ECEF inversion), a quarter of the whole preview's work; it
is kept as the tests' independent oracle (its own ECEF pipeline), with PROJ's geodesics.

The datum's height is the sea surface (0 m above the ellipsoid is close enough at these
ranges: a 30 m geoid offset changes a 1 km horizontal conversion by < 5 mm).
"""

from __future__ import annotations

import math
import threading
from typing import Final, Protocol

import numpy as np
import numpy.typing as npt
from pyproj import Transformer

from codec._record import Record, init

__all__ = [
    "TRAINING_DATUM",
    "Datum",
    "DatumSettings",
    "dm",
    "geodetic_to_ned",
    "initial_datum",
    "ned_to_geodetic",
]

FloatArray = npt.NDArray[np.float64]

_THREAD = threading.local()


def _local(lat_deg: float, lon_deg: float) -> Transformer:
    """PROJ's pipeline from geodetic (lon, lat deg, h m) to local east/north/up metres about
    the datum (the surface, h 0); ``transform(..., direction="INVERSE")`` goes back. One per
    thread and datum (a PROJ context is not shared between threads: the previews run in the
    server's thread pool)."""
    cache: dict[tuple[float, float], Transformer] = _THREAD.__dict__.setdefault("local", {})
    found = cache.get((lat_deg, lon_deg))
    if found is None:
        if len(cache) >= 8:
            cache.clear()
        found = cache[lat_deg, lon_deg] = _pipeline(lat_deg, lon_deg)
    return found


def _pipeline(lat_deg: float, lon_deg: float) -> Transformer:
    return Transformer.from_pipeline(
        "+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad "
        "+step +proj=cart +ellps=WGS84 "
        f"+step +proj=topocentric +ellps=WGS84 +lat_0={lat_deg!r} +lon_0={lon_deg!r} +h_0=0"
    )


class Datum(Record):
    """The latitude and longitude of the NED origin (deg, WGS84).

    Raises:
        ValueError: naming the field, when latitude is outside [-90, 90] or longitude outside
            [-180, 180] or either is not a finite number.
    """

    __slots__ = ("lat_deg", "lon_deg")
    lat_deg: float
    lon_deg: float

    def __init__(self, lat_deg: float, lon_deg: float) -> None:
        init(self, "lat_deg", _check("lat_deg", lat_deg, 90.0))
        init(self, "lon_deg", _check("lon_deg", lon_deg, 180.0))


def _check(name: str, value: float, bound: float) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ValueError(f"{name} must be finite, in [-{bound:g}, {bound:g}] deg, got {value!r}")
    if not -bound <= value <= bound:
        raise ValueError(f"{name} must be in [-{bound:g}, {bound:g}] deg, got {value!r}")
    return float(value)


#: Training mode's default site: Lake Wauburg, University of Florida (the paper's authors'
#: university), 29.5316 N, 82.3031 W, open water about 400 m across. A documented stand-in,
#: not the paper's trial site (the paper does not give one).
TRAINING_DATUM: Final = Datum(29.5316, -82.3031)


class DatumSettings(Protocol):
    """What :func:`initial_datum` reads of the console's settings (``backend.settings.Settings``;
    not imported here: the settings check their ``gps`` with the GPS parser, which imports this
    module)."""

    @property
    def datum_lat_deg(self) -> float | None: ...

    @property
    def datum_lon_deg(self) -> float | None: ...

    @property
    def training(self) -> bool: ...


def initial_datum(settings: DatumSettings) -> Datum | None:
    """The datum at start: the settings' when given, training's site in training, else None
    (a surface GPS may set it later)."""
    if settings.datum_lat_deg is not None and settings.datum_lon_deg is not None:
        return Datum(settings.datum_lat_deg, settings.datum_lon_deg)
    return TRAINING_DATUM if settings.training else None


def ned_to_geodetic(
    datum: Datum, x_m: npt.ArrayLike, y_m: npt.ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """NED metres (north, east, at the surface) to latitude and longitude (deg, WGS84).

    Args:
        datum: the origin's latitude and longitude.
        x_m: north (m), a scalar or an array.
        y_m: east (m), same shape.

    Returns:
        ``(lat_deg, lon_deg)``, float64 arrays of the same shape (0-d for scalars).
    """
    x = np.asarray(x_m, dtype=np.float64)
    y = np.asarray(y_m, dtype=np.float64)
    lon, lat, _h = _local(datum.lat_deg, datum.lon_deg).transform(
        y, x, np.zeros_like(x), direction="INVERSE"
    )
    return np.asarray(lat, dtype=np.float64), np.asarray(lon, dtype=np.float64)


def geodetic_to_ned(datum: Datum, lat_deg: float, lon_deg: float) -> tuple[float, float]:
    """A latitude and longitude (deg) to NED metres ``(x_m north, y_m east)`` from ``datum``."""
    e, n, _u = _local(datum.lat_deg, datum.lon_deg).transform(lon_deg, lat_deg, 0.0)
    return float(n), float(e)


def dm(value_deg: float, *, lat: bool) -> str:
    """Degrees and decimal minutes, as on a chart: ``29°31.896'N``, ``082°18.186'W``."""
    hemi = ("N" if value_deg >= 0 else "S") if lat else ("E" if value_deg >= 0 else "W")
    a = abs(value_deg)
    deg = int(a)
    minutes = (a - deg) * 60.0
    if round(minutes, 3) >= 60.0:
        deg, minutes = deg + 1, 0.0
    width = 2 if lat else 3
    return f"{deg:0{width}d}°{minutes:06.3f}'{hemi}"
