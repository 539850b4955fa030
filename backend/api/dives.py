"""A dive read back from the mission log: ``GET /api/series`` (the plots after a reload),
``GET /api/dives/{dive}/timeline`` (the replay's time slider) and
``GET /api/dives/{dive}/export.mcap`` (the dive for the robotics tools)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Annotated, Any, Final

from fastapi import APIRouter, HTTPException, Query
from fastapi.responses import StreamingResponse

from backend.api.deps import SQLITE_INT_MAX, ConsoleDep, IdPath, QueryVehicleDep
from backend.api.schemas import errors
from backend.api.schemas.dives import DiveSeries, DiveTimeline
from backend.bag.export import stream_mcap
from backend.chart.reach import track_lat_lon
from backend.console import Console
from backend.mission_log.series import DEFAULT_MAX_POINTS, dive_series
from backend.mission_log.timeline import dive_timeline, vehicle_events

router = APIRouter(prefix="/api", tags=["commands"])

#: MCAP has no registered media type: served as bytes (the file name says what it is).
MCAP_MEDIA_TYPE: Final = "application/octet-stream"

#: A dive's number as a query parameter: 1 and up (absent: the current dive).
DiveQ = Annotated[
    int | None,
    Query(ge=1, le=SQLITE_INT_MAX, description="the dive (1 and up); absent: the current one"),
]
#: Most samples returned: 2 to a day at 1 Hz; a longer dive is thinned evenly.
LimitQ = Annotated[int, Query(ge=2, le=86_400, description="most samples returned (2 to 86400)")]


@router.get(
    "/series",
    response_model=DiveSeries,
    response_model_exclude_unset=True,
    responses=errors((404, 422)),
)
def series(
    console: ConsoleDep,
    vehicle: QueryVehicleDep,
    dive: DiveQ = None,
    limit: LimitQ = DEFAULT_MAX_POINTS,
) -> DiveSeries:
    """The dive's status series (depth, commanded depth, battery, speed, heading, mode,
    navigation validity) a sample a second of the vehicle's clock, from its start: the plots
    load it, then append the live telemetry. Without ``dive``, the current dive (``dive: null``
    and no samples before one starts). With a fleet, of the ``vehicle`` named (required: 422
    naming the fleet's vehicles without it or for a name it has not); its ``vehicle`` says
    which."""
    log = console.log
    assert log is not None
    chosen = console.dive if dive is None else dive
    if chosen is None:
        doc = {"dive": None, "started_at": None, **dive_series([], limit)}
    else:
        row = log.dive(chosen)
        if row is None:
            raise HTTPException(404, f"no dive {chosen}")
        rows = log.track_rows(chosen, positioned=False, vehicle=vehicle)
        doc = {"dive": chosen, "started_at": row["started_at"], **dive_series(rows, limit)}
    if vehicle is not None:  # a fleet's (the single vehicle's answer is as it always was)
        doc["vehicle"] = vehicle
    return DiveSeries.model_validate(doc)


def timeline_of(console: Console, dive: int, vehicle: str | None = None) -> dict[str, Any]:
    """The dive's timeline document (404 when there is no such dive); of a fleet's
    ``vehicle``: its track, its commands, its events and those naming no vehicle."""
    log = console.log
    assert log is not None
    row = log.dive(dive)
    if row is None:
        raise HTTPException(404, f"no dive {dive}")
    commands = log.commands(dive=dive, vehicle=vehicle, limit=100_000, oldest_first=True)
    events = vehicle_events(log.events(dive), vehicle)
    rows = log.track_rows(dive, vehicle=vehicle)
    doc = dive_timeline(rows, commands, events, row["started_at"])
    track_lat_lon(doc["samples"], console.datum)
    named = {} if vehicle is None else {"vehicle": vehicle}  # a fleet's names its vehicle
    return {"dive": dive, **named, "started_at": row["started_at"], **doc}


@router.get(
    "/dives/{dive}/timeline",
    response_model=DiveTimeline,
    response_model_exclude_unset=True,
    responses=errors((404, 422)),
)
def timeline(dive: IdPath, console: ConsoleDep, vehicle: QueryVehicleDep) -> DiveTimeline:
    """The dive on its own clock, for the replay's time slider: every sample of the vehicle
    (position, mode, the command it was running), its commands and the link's events (copies
    sent, acknowledgements, rejections, timeouts, logged events), in time order. With a
    fleet, of the ``vehicle`` named (required: 422 naming the fleet's vehicles without it or
    for a name it has not): its samples and commands, its events and those naming no
    vehicle; its ``vehicle`` says which."""
    return DiveTimeline.model_validate(timeline_of(console, dive, vehicle))


@router.get(
    "/dives/{dive}/export.mcap",
    response_class=StreamingResponse,
    responses={
        **errors((404, 422)),
        200: {
            "description": "the dive as an MCAP file (ROS 2 profile, CDR, chunked and indexed), "
            "streamed as it is written (Content-Disposition: attachment)",
            "content": {MCAP_MEDIA_TYPE: {"schema": {"type": "string"}}},
        },
    },
)
def export_mcap(dive: IdPath, console: ConsoleDep) -> StreamingResponse:
    """The dive as MCAP for Foxglove, ``ros2 bag`` and PlotJuggler (docs/foxglove.md): the
    vehicle's odometry (ENU) and fix, its status, the frames sent, the command records, the
    acknowledgements (typed, and as the contract's JSON) and the log's events, on the console's
    clock. Streamed in constant memory from one snapshot of the log; a failure midway cuts the
    response short (an incomplete download, never a file that looks whole)."""
    log = console.log
    assert log is not None
    if not log.dive_exists(dive):
        raise HTTPException(404, f"no dive {dive}")
    datum = console.datum

    def body() -> Iterator[bytes]:
        with log.exporting() as db:
            yield from stream_mcap(db, dive, datum)

    return StreamingResponse(
        body(),
        media_type=MCAP_MEDIA_TYPE,
        headers={"Content-Disposition": f'attachment; filename="nemesys-dive-{dive}.mcap"'},
    )
