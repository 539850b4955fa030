"""backend.chart.geo (PROJ's topocentric pipeline) against independent oracles: pymap3d's own
ECEF pipeline (pure Python, a separate implementation of the same transform), PROJ's
geodesics (pyproj.Geod, Karney's algorithm) and its azimuthal equidistant projection.

A NED point (x north, y east, at the surface) ``d`` metres from the datum lies, converted, at
a geodesic distance ``d`` and an initial azimuth ``atan2(y, x)`` from it: the tangent plane
and the ellipsoid part by ``d^3 / 3R^2`` (70 um at 2 km), far below the 0.1 m asked for."""

from __future__ import annotations

import math

import numpy as np
import pymap3d
import pytest
from pyproj import Geod, Transformer

from backend.chart.geo import (
    TRAINING_DATUM,
    Datum,
    dm,
    geodetic_to_ned,
    initial_datum,
    ned_to_geodetic,
)
from backend.settings import Settings
from tests.backend.conftest import clear_nemesys_env

GEOD = Geod(ellps="WGS84")
#: Datums at several latitudes: the training site, the equator, mid and high latitudes near
#: the poles (a point may pass over the pole), and across the antimeridian.
DATUMS = [
    (29.5316, -82.3031),
    (0.0, 0.0),
    (-45.0, 170.0),
    (60.0, 10.0),
    (78.2, 15.6),
    (89.9, 0.0),
    (89.99, 45.0),
    (-89.9, -120.0),
    (10.0, 179.99),
    (-30.0, -179.995),
]
#: NED offsets up to 2 km (m), every direction.
POINTS = [
    (2000.0, 0.0),
    (0.0, 2000.0),
    (-1414.0, 1414.0),
    (1500.0, -1300.0),
    (-2000.0, 5.0),
    (3.0, -1999.0),
    (700.0, 700.0),
    (0.5, 0.25),
]
TOLERANCE_M = 0.1


@pytest.mark.parametrize(("lat0", "lon0"), DATUMS)
def test_conversions_match_proj_geodesics_within_a_decimetre(lat0: float, lon0: float) -> None:
    datum = Datum(lat0, lon0)
    xs = np.array([p[0] for p in POINTS])
    ys = np.array([p[1] for p in POINTS])
    lats, lons = ned_to_geodetic(datum, xs, ys)  # one vectorised call
    assert lats.shape == lons.shape == xs.shape
    for (x, y), lat, lon in zip(POINTS, lats, lons, strict=True):
        assert -90 <= lat <= 90 and -180 <= lon <= 180
        # distance from the datum is the NED distance
        _az, _baz, distance = GEOD.inv(lon0, lat0, float(lon), float(lat))
        assert distance == pytest.approx(math.hypot(x, y), abs=TOLERANCE_M)
        # the point the geodesic at that azimuth and distance reaches is the converted one
        lon2, lat2, _ = GEOD.fwd(lon0, lat0, math.degrees(math.atan2(y, x)), math.hypot(x, y))
        miss = GEOD.inv(lon2, lat2, float(lon), float(lat))[2]
        assert miss < TOLERANCE_M, (x, y, miss)
        # and the scalar call agrees with the vectorised one
        one_lat, one_lon = ned_to_geodetic(datum, x, y)
        assert one_lat.shape == ()
        assert (float(one_lat), float(one_lon)) == pytest.approx((lat, lon), abs=1e-12)


@pytest.mark.parametrize(("lat0", "lon0"), [d for d in DATUMS if abs(d[0]) < 89])
def test_conversions_match_a_proj_azimuthal_equidistant_projection(
    lat0: float, lon0: float
) -> None:
    """A second PROJ route: aeqd about the datum maps the converted point back to (y, x)."""
    aeqd = Transformer.from_crs(
        "EPSG:4326", f"+proj=aeqd +lat_0={lat0} +lon_0={lon0} +ellps=WGS84", always_xy=True
    )
    for x, y in POINTS:
        lat, lon = ned_to_geodetic(Datum(lat0, lon0), x, y)
        east, north = aeqd.transform(float(lon), float(lat))
        assert math.hypot(east - y, north - x) < TOLERANCE_M, (x, y, east, north)


def test_the_antimeridian_is_crossed_not_unwrapped() -> None:
    datum = Datum(10.0, 179.99)
    lat, lon = ned_to_geodetic(datum, 0.0, 2000.0)  # 2 km east: past 180
    assert -180 < float(lon) < -179.97
    x, y = geodetic_to_ned(datum, float(lat), float(lon))
    assert (x, y) == pytest.approx((0.0, 2000.0), abs=0.01)


@pytest.mark.parametrize(("lat0", "lon0"), DATUMS)
def test_conversions_match_pymap3d_within_a_millimetre(lat0: float, lon0: float) -> None:
    """The same transform (NED about the datum, through ECEF) in another implementation."""
    datum = Datum(lat0, lon0)
    xs = np.array([p[0] for p in POINTS])
    ys = np.array([p[1] for p in POINTS])
    lat, lon = ned_to_geodetic(datum, xs, ys)
    for (x, y), la, lo in zip(POINTS, lat, lon, strict=True):
        n, e, _d = pymap3d.geodetic2ned(float(la), float(lo), 0.0, lat0, lon0, 0.0)
        # (la, lo) at the ellipsoid is below the tangent plane by d^2 / 2R: compare horizontally
        assert math.hypot(n - x, e - y) < 0.001, (x, y, n, e)
        back = geodetic_to_ned(datum, float(la), float(lo))
        assert back == pytest.approx((n, e), abs=0.001)


@pytest.mark.parametrize(("lat0", "lon0"), DATUMS)
def test_round_trip(lat0: float, lon0: float) -> None:
    datum = Datum(lat0, lon0)
    for x, y in POINTS:
        lat, lon = ned_to_geodetic(datum, x, y)
        back = geodetic_to_ned(datum, float(lat), float(lon))
        assert back == pytest.approx((x, y), abs=0.001)
    assert geodetic_to_ned(datum, lat0, lon0) == pytest.approx((0.0, 0.0), abs=1e-6)


def test_dm_formats_degrees_and_decimal_minutes() -> None:
    assert dm(29.5316, lat=True) == "29°31.896'N"
    assert dm(-82.3031, lat=False) == "082°18.186'W"
    assert dm(-33.5, lat=True) == "33°30.000'S"
    assert dm(5.25, lat=False) == "005°15.000'E"
    assert dm(0.0, lat=True) == "00°00.000'N"
    assert dm(0.0, lat=False) == "000°00.000'E"
    assert dm(-179.999, lat=False) == "179°59.940'W"
    # 59.9996' rounds to 60.000': carried into the degrees, never "59°60.000'"
    assert dm(10 + 59.9996 / 60, lat=True) == "11°00.000'N"
    assert dm(-(9 + 59.9996 / 60), lat=False) == "010°00.000'W"
    assert dm(10 + 59.9994 / 60, lat=True) == "10°59.999'N"
    assert dm(90.0, lat=True) == "90°00.000'N"


@pytest.mark.parametrize(
    ("lat", "lon", "field"),
    [
        (90.5, 0.0, "lat_deg"),
        (-91.0, 0.0, "lat_deg"),
        (math.nan, 0.0, "lat_deg"),
        (0.0, 180.01, "lon_deg"),
        (0.0, -math.inf, "lon_deg"),
        (True, 0.0, "lat_deg"),
        (0.0, "10", "lon_deg"),
    ],
)
def test_datum_refuses_bad_values_naming_the_field(lat: object, lon: object, field: str) -> None:
    with pytest.raises(ValueError, match=field) as caught:
        Datum(lat, lon)  # type: ignore[arg-type]
    assert "deg" in str(caught.value)


def test_datum_bounds_are_inclusive() -> None:
    assert Datum(90, -180).lat_deg == 90.0
    assert Datum(-90.0, 180.0).lon_deg == 180.0


def test_initial_datum(monkeypatch: pytest.MonkeyPatch) -> None:
    clear_nemesys_env(monkeypatch)
    assert initial_datum(Settings(token="t" * 20)) == TRAINING_DATUM
    assert initial_datum(Settings(token="t" * 20, target="loop://")) is None
    set_ = Settings(token="t" * 20, target="loop://", datum_lat_deg=1.5, datum_lon_deg=-2.5)
    assert initial_datum(set_) == Datum(1.5, -2.5)
