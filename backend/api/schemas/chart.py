"""The chart's documents: the datum, the station (ME transmitter), the link's range, the
local tiles and the surface GPS; the preview's link reach."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

ReachState = Literal["in_range", "marginal", "out_of_range"]


class DatumDoc(BaseModel):
    """The latitude and longitude of the NED origin (deg, WGS84)."""

    lat_deg: float
    lon_deg: float


class StationDoc(BaseModel):
    """The ME transmitter: from the surface GPS's latest fix, else the ``station_lat_deg`` /
    ``station_lon_deg`` settings, else the datum (the NED origin)."""

    lat_deg: float | None = Field(description="null: no datum and no position of its own")
    lon_deg: float | None
    x_m: float | None = Field(description="north of the datum (m); null: not placed (no datum)")
    y_m: float | None = Field(description="east of the datum (m)")
    source: Literal["gps", "settings", "datum"]
    age_s: float | None = Field(description="age of the GPS fix (s); null for other sources")


class TilesDoc(BaseModel):
    """Local map tiles (a directory of z/x/y tiles or an MBTiles file)."""

    url: str = Field(description="the tile URL template, {z}/{x}/{y} (XYZ, rows from the north)")
    kind: Literal["directory", "mbtiles"]
    min_zoom: int | None
    max_zoom: int | None
    format: Literal["png", "jpg", "webp"] | None


class GpsDoc(BaseModel):
    """The surface GPS: its source, whether it has a fix, and what it has received."""

    configured: bool
    source: str = Field(description="udp://host:port or serial://device?baud=n")
    fix: bool
    quality: int | None = Field(description="GGA fix quality (1 GPS, 2 DGPS, 4 RTK...)")
    sentences: int = Field(description="NMEA sentences received")
    no_fix: int = Field(description="GGA/RMC sentences without a fix")
    errors: int = Field(description="sentences refused: checksum, unparsable, no position")
    last_error: str | None
    age_s: float | None = Field(description="seconds since the latest fix arrived")


class ChartDoc(BaseModel):
    """What the chart draws besides the vehicle: the datum, the transmitter and its range
    ring (``me_range_m``, marginal beyond ``marginal_fraction`` of it), the tiles, the GPS."""

    datum: DatumDoc | None = Field(description="null: no datum yet (positions in metres only)")
    station: StationDoc
    me_range_m: float
    marginal_fraction: float
    tiles: TilesDoc | None = Field(description="null: no local tiles (graticule only)")
    gps: GpsDoc | None = Field(description="null: no surface GPS configured")


class DatumIn(BaseModel):
    """Either ``{lat_deg, lon_deg}`` or ``{"source": "gps"}`` (the GPS's latest fix).
    Strict: ``false`` is not latitude 0, nor ``"10"`` a number."""

    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)

    lat_deg: float | None = Field(None, ge=-90, le=90)
    lon_deg: float | None = Field(None, ge=-180, le=180)
    source: Literal["gps"] | None = Field(None, description='"gps": the latest fix')


class ReachSegment(BaseModel):
    """Waypoints ``start`` to ``end`` (inclusive) of one reach class."""

    state: ReachState
    start: int
    end: int


class LinkReach(BaseModel):
    """The preview path's slant range from the transmitter: in range up to ``marginal_m``
    (75 % of the range), marginal up to ``range_m``, out of range beyond; ``state`` is the
    worst along the path; ``warning`` says so in words when the path leaves range."""

    range_m: float
    marginal_m: float
    station_x_m: float
    station_y_m: float
    max_distance_m: float
    state: ReachState
    segments: list[ReachSegment]
    warning: str | None
