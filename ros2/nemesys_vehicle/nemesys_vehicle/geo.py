"""Latitude and longitude to metres about the datum, on the vehicle (standard library only).

The console converts with PROJ (``backend/chart/geo.py``: geodetic -> ECEF -> topocentric
about the datum, at the surface); a vehicle installs no PROJ, so this is the same pipeline
written out: WGS84 geodetic -> ECEF -> the local north/east plane about the datum. It is the
exact transform, not a small-angle approximation; the console-side test checks it against
PROJ to the millimetre. Heights are 0 (the sea surface): a 30 m geoid offset changes a 1 km
conversion by less than 5 mm.
"""

from __future__ import annotations

import math
from typing import Final

#: WGS84: semi-major axis (m) and flattening.
WGS84_A_M: Final = 6_378_137.0
WGS84_F: Final = 1.0 / 298.257223563
_E2: Final = WGS84_F * (2.0 - WGS84_F)


def check_lat_lon(lat_deg: float, lon_deg: float) -> None:
    """Raises ValueError naming the value unless latitude is in [-90, 90] and longitude in
    [-180, 180] degrees, both finite."""
    for name, value, bound in (("lat_deg", lat_deg, 90.0), ("lon_deg", lon_deg, 180.0)):
        if not (math.isfinite(value) and -bound <= value <= bound):
            raise ValueError(
                f"{name} must be finite, in [-{bound:g}, {bound:g}] deg, got {value!r}"
            )


def _ecef(lat_deg: float, lon_deg: float) -> tuple[float, float, float]:
    """Earth-centred, Earth-fixed metres of a point on the ellipsoid (height 0)."""
    phi, lam = math.radians(lat_deg), math.radians(lon_deg)
    sin_phi = math.sin(phi)
    n = WGS84_A_M / math.sqrt(1.0 - _E2 * sin_phi * sin_phi)
    return (
        n * math.cos(phi) * math.cos(lam),
        n * math.cos(phi) * math.sin(lam),
        n * (1.0 - _E2) * sin_phi,
    )


def geodetic_to_ned(
    datum_lat_deg: float, datum_lon_deg: float, lat_deg: float, lon_deg: float
) -> tuple[float, float]:
    """``(north_m, east_m)`` of a latitude and longitude (deg, WGS84) from the datum.

    Raises:
        ValueError: a latitude or longitude out of range or not finite (naming it).
    """
    check_lat_lon(datum_lat_deg, datum_lon_deg)
    check_lat_lon(lat_deg, lon_deg)
    x0, y0, z0 = _ecef(datum_lat_deg, datum_lon_deg)
    x, y, z = _ecef(lat_deg, lon_deg)
    dx, dy, dz = x - x0, y - y0, z - z0
    phi, lam = math.radians(datum_lat_deg), math.radians(datum_lon_deg)
    sin_phi, cos_phi = math.sin(phi), math.cos(phi)
    sin_lam, cos_lam = math.sin(lam), math.cos(lam)
    east = -sin_lam * dx + cos_lam * dy
    north = -sin_phi * cos_lam * dx - sin_phi * sin_lam * dy + cos_phi * dz
    return north + 0.0, east + 0.0
