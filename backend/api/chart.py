"""The chart: datum, station and range (GET /api/chart), setting the datum (PUT /api/datum,
operator), and local map tiles (GET /api/tiles/{z}/{x}/{y})."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Path, Response
from fastapi.exceptions import RequestValidationError

from backend.api.deps import ConsoleDep, OperatorDep
from backend.api.schemas import OPERATOR, errors
from backend.api.schemas.chart import ChartDoc, DatumDoc, DatumIn, GpsDoc, StationDoc, TilesDoc
from backend.chart.geo import Datum
from backend.chart.reach import MARGINAL_FRACTION
from backend.chart.tiles import MAX_ZOOM, MEDIA_TYPES
from backend.console import Console
from backend.messages import EventMessage
from backend.mission_log.records import log_event
from backend.mission_log.store import LogWriteError

router = APIRouter(prefix="/api", tags=["chart"])

TILE_URL = "/api/tiles/{z}/{x}/{y}"
#: The largest column or row index at the deepest zoom.
_INDEX_MAX = (1 << MAX_ZOOM) - 1


def chart_doc(console: Console) -> ChartDoc:
    datum, tiles, gps = console.datum, console.tiles, console.gps
    return ChartDoc(
        datum=None if datum is None else DatumDoc(lat_deg=datum.lat_deg, lon_deg=datum.lon_deg),
        station=StationDoc.model_validate(console.station().as_dict()),
        me_range_m=console.settings.me_range_m,
        marginal_fraction=MARGINAL_FRACTION,
        tiles=None
        if tiles is None
        else TilesDoc.model_validate(  # kind and format: checked against the documented names
            {
                "url": TILE_URL,
                "kind": tiles.kind,
                "min_zoom": tiles.min_zoom,
                "max_zoom": tiles.max_zoom,
                "format": tiles.format,
            }
        ),
        gps=None if gps is None else GpsDoc.model_validate(gps.doc()),
    )


@router.get("/chart", response_model=ChartDoc)
def chart(console: ConsoleDep) -> ChartDoc:
    """The datum (null: none yet), the ME transmitter (station) with its source, the link's
    range and where it turns marginal, the local tiles (null: none) and the surface GPS
    (null: none configured)."""
    return chart_doc(console)


def _invalid(field: str, msg: str, value: Any) -> RequestValidationError:
    return RequestValidationError(
        [{"loc": ("body", field), "msg": msg, "type": "value_error", "input": value}]
    )


@router.put(
    "/datum",
    response_model=ChartDoc,
    responses=errors(
        (*OPERATOR, 409, 413, 422),
        why={409: '{"source": "gps"} without a GPS fix (no GPS configured, or none yet)'},
    ),
)
def set_datum(body: DatumIn, console: ConsoleDep, _op: OperatorDep) -> ChartDoc:
    """Set the datum (the NED origin's lat/lon): ``{lat_deg, lon_deg}``, or
    ``{"source": "gps"}`` for the surface GPS's latest fix (409 without one). Every lat/lon
    shown from then on (pose, tracks, previews) is from the new datum; the change is logged
    as an event of the dive. Returns the chart document."""
    if body.source == "gps":
        if body.lat_deg is not None or body.lon_deg is not None:
            field = "lat_deg" if body.lat_deg is not None else "lon_deg"
            raise _invalid(field, 'give {lat_deg, lon_deg} or {"source": "gps"}, not both', None)
        fix = console.gps.fix if console.gps is not None else None
        if fix is None:
            why = "no surface GPS is configured (the gps setting)"
            if console.gps is not None:
                why = f"the surface GPS ({console.gps.source}) has no fix yet"
            raise HTTPException(409, f"cannot take the datum from the GPS: {why}")
        datum = Datum(fix.lat_deg, fix.lon_deg)
    else:
        for field in ("lat_deg", "lon_deg"):
            if getattr(body, field) is None:
                raise _invalid(
                    field, f'{field} is required (or give {{"source": "gps"}} alone)', None
                )
        assert body.lat_deg is not None and body.lon_deg is not None
        datum = Datum(body.lat_deg, body.lon_deg)
    old = console.datum
    console.datum = datum
    _log_datum(console, old, datum, body.source or "operator")
    return chart_doc(console)


def _log_datum(console: Console, old: Datum | None, new: Datum, source: str) -> None:
    if console.dives is None:
        return
    detail = f"datum set from the {source}: {new.lat_deg:.7f}, {new.lon_deg:.7f}"
    data = {
        "lat_deg": new.lat_deg,
        "lon_deg": new.lon_deg,
        "source": source,
        "previous": None if old is None else {"lat_deg": old.lat_deg, "lon_deg": old.lon_deg},
    }
    try:
        event = console.dives.event("datum", detail, data)  # starts a dive if none has
    except LogWriteError:
        return  # the datum is set; the log's own failure is reported by its health
    console.hub.publish(EventMessage(event=log_event(event)))


ZoomPath = Annotated[int, Path(ge=0, le=MAX_ZOOM, description="zoom level")]
IndexPath = Annotated[int, Path(ge=0, le=_INDEX_MAX, description="0 to 2^z - 1")]


@router.get(
    "/tiles/{z}/{x}/{y}",
    response_class=Response,
    responses={
        **errors((404, 422), why={404: "no such tile, or no local tiles configured"}),
        200: {
            "description": "the tile image",
            "content": {media: {"schema": {"type": "string"}} for media in MEDIA_TYPES.values()},
        },
    },
)
def tile(z: ZoomPath, x: IndexPath, y: IndexPath, console: ConsoleDep) -> Response:
    """A map tile (XYZ scheme: rows from the north, as Leaflet asks) from the local tiles
    (``tiles`` setting). ``x`` and ``y`` must be below 2^z (422 naming the one that is not);
    404 when there is no such tile or no tiles."""
    for name, value in (("x", x), ("y", y)):
        if value >= 1 << z:
            raise RequestValidationError(
                [
                    {
                        "loc": ("path", name),
                        "msg": f"{name} must be in [0, {(1 << z) - 1}] at zoom {z}",
                        "type": "value_error",
                        "input": value,
                    }
                ]
            )
    if console.tiles is None:
        raise HTTPException(404, "no local map tiles (the tiles setting)")
    found = console.tiles.get(z, x, y)
    if found is None:
        raise HTTPException(404, f"no tile {z}/{x}/{y}")
    data, media = found
    return Response(data, media_type=media, headers={"Cache-Control": "max-age=3600"})
