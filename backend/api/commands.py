"""Sending, Surface, the command log and its exports, dives and replay, vehicle status."""

from __future__ import annotations

import csv
import io
from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Query, Response, status
from fastapi.responses import JSONResponse
from pydantic import BaseModel, Field

from backend.api.deps import (
    ConsoleDep,
    IdField,
    IdPath,
    OperatorDep,
    QueryVehicleDep,
    ServiceDep,
    filter_vehicle,
)
from backend.api.models import LinkIn, RetryIn, SendIn, SurfaceIn
from backend.api.schemas import (
    OPERATOR,
    Ack,
    CommandRecord,
    DiveDetail,
    DiveSummary,
    ErrorDetail,
    LimitViolationError,
    ReplayResult,
    ValidationErrorResponse,
    VehicleView,
    errors,
)
from backend.api.schemas.records import TrackPoint
from backend.api.view import ViewHeader
from backend.chart.reach import track_lat_lon
from backend.commands.health import LinkHealth, LinkTestResult
from backend.commands.link_settings import test_link
from backend.commands.service import SendRequest
from backend.commands.vehicles import ALL_VEHICLES
from backend.fleet.models import FleetSurface
from backend.mission_log.export import csv_rows
from backend.mission_log.records import command_record
from backend.mission_log.store import STATES

router = APIRouter(prefix="/api", tags=["commands"])


@router.post(
    "/commands",
    status_code=status.HTTP_202_ACCEPTED,
    response_model=CommandRecord,
    response_model_exclude_unset=True,
    responses=errors(
        (*OPERATOR, 409, 413, 422, 429, 503, 504),
        models={
            409: LimitViolationError | ErrorDetail,
            422: ValidationErrorResponse | LimitViolationError,
        },
        why={
            409: "limits an operator may override, without override: true; or another "
            "console (named) is in control of the vehicle",
            422: "invalid input, or limits no operator can override (the depth rating)",
        },
    ),
)
async def send(body: SendIn, service: ServiceDep, _op: OperatorDep) -> CommandRecord:
    """Queue a command for transmission (logged first), through the command service's checks.
    422: limits that cannot be overridden or bad values, or (with a fleet) no ``vehicle`` or
    one the fleet has not (naming its vehicles); 409: overridable limits without
    ``override`` (an override is recorded in the log with who gave it), or this console is
    not in control of the vehicle (consoles sharing a log: ``/api/control``); 429: rate
    limit; 503: the mission log cannot be written or its database is out of reach. A console
    without a transmitter (target relay) answers with the record the console holding it
    made, or that console's refusal (its status and reason); 504: none took it in time."""
    request = SendRequest(
        body.pattern,
        body.params,
        "api",
        override=body.override,
        copies=body.copies,
        vehicle=body.vehicle,
    )
    return (await service.send(request)).record


@router.post(
    "/surface",
    status_code=status.HTTP_202_ACCEPTED,
    response_model=CommandRecord | FleetSurface,
    response_model_exclude_unset=True,
    responses=errors((*OPERATOR, 413, 422, 503, 504)),
)
async def surface(
    service: ServiceDep, _op: OperatorDep, body: SurfaceIn | None = None
) -> CommandRecord | FleetSurface:
    """Abort: send surface now and again every ``surface_repeat_s``: until acknowledged on a
    two-way link, a bounded number of times on a one-way link. It replaces any command still
    being repeated (to that vehicle); pressed while another Surface is on its way, it joins
    that one. With a fleet, ``vehicle`` names one vehicle, or ``"all"``: one frame to address
    0 that every vehicle accepts, one record per vehicle, replacing every vehicle's commands
    (422 without it, naming the vehicles)."""
    vehicle = body.vehicle if body is not None else None
    outcome = await service.surface("surface", vehicle=vehicle)
    if vehicle == ALL_VEHICLES:
        return FleetSurface(vehicle=vehicle, commands=list(outcome.records))
    return outcome.record


@router.post(
    "/commands/{command_id}/retry",
    status_code=status.HTTP_202_ACCEPTED,
    response_model=CommandRecord,
    response_model_exclude_unset=True,
    responses=errors(
        (*OPERATOR, 404, 409, 413, 422, 429, 503, 504),
        models={
            409: LimitViolationError | ErrorDetail,
            422: ValidationErrorResponse | LimitViolationError,
        },
        why={
            409: "the command is not in a retryable state, or overridable limits without "
            "override: true",
            422: "invalid input, or limits no operator can override",
        },
    ),
)
async def retry(
    command_id: IdPath, service: ServiceDep, _op: OperatorDep, body: RetryIn | None = None
) -> CommandRecord:
    """A new command with the values of an interrupted, timed-out, failed, rejected or
    superseded one (a new record, created now, ``retry_of`` naming it), checked as any send
    from where the vehicle is now; it replaces any command still being repeated (to that
    vehicle). With a fleet, ``vehicle`` names the vehicle it goes to (422 without it)."""
    override = body.override if body else False
    copies = body.copies if body else None
    vehicle = body.vehicle if body else None
    return (
        await service.retry(command_id, override=override, copies=copies, vehicle=vehicle)
    ).record


StateQ = Annotated[str | None, Query(pattern="^(" + "|".join(STATES) + ")$")]


class LogFilter(BaseModel):
    """Filters of the mission log (all optional): query parameters."""

    state: StateQ = None
    pattern: Annotated[str | None, Field(max_length=32)] = None
    target: Annotated[str | None, Field(max_length=200)] = None
    dive: IdField | None = None
    vehicle: Annotated[
        str | None, Field(max_length=32, description="a fleet's vehicle's records only")
    ] = None
    since: Annotated[str | None, Field(max_length=40, description="ISO time, UTC")] = None
    until: Annotated[str | None, Field(max_length=40, description="ISO time, UTC")] = None


FilterQ = Annotated[LogFilter, Query()]


def _rows(console: ConsoleDep, filters: LogFilter, limit: int) -> list[dict[str, Any]]:
    """The log's rows as written (the exports hand them on as they are)."""
    assert console.log is not None
    vehicle = filter_vehicle(console, filters.vehicle, ("query", "vehicle"))
    return console.log.commands(**{**filters.model_dump(), "vehicle": vehicle}, limit=limit)


@router.get(
    "/commands",
    response_model=list[CommandRecord],
    response_model_exclude_unset=True,
    responses=errors((422,)),
)
def commands(
    console: ConsoleDep, filters: FilterQ, limit: Annotated[int, Query(ge=1, le=1000)] = 200
) -> list[CommandRecord]:
    """The mission log, newest first."""
    return [command_record(row) for row in _rows(console, filters, limit)]


@router.get(
    "/commands/{command_id}",
    response_model=CommandRecord,
    response_model_exclude_unset=True,
    responses=errors((404, 422)),
)
def command(command_id: IdPath, console: ConsoleDep) -> CommandRecord:
    assert console.log is not None
    row = console.log.command(command_id)
    if row is None:
        raise HTTPException(404, f"no command {command_id}")
    return command_record(row)


ExportLimitQ = Annotated[int, Query(ge=1, le=100_000)]


# the exports return their documents as built (up to 100 000 records, not re-validated)
@router.get(
    "/log.json",
    response_model=list[CommandRecord],
    responses={
        **errors((422,)),
        200: {"description": "the log as a JSON file (Content-Disposition: attachment)"},
    },
)
def log_json(console: ConsoleDep, filters: FilterQ, limit: ExportLimitQ = 100_000) -> JSONResponse:
    """The log as a JSON file (newest first)."""
    return JSONResponse(
        _rows(console, filters, limit),
        headers={"Content-Disposition": 'attachment; filename="nemesys-log.json"'},
    )


@router.get(
    "/log.csv",
    response_class=Response,
    responses={
        **errors((422,)),
        200: {
            "description": "the log as a CSV file: a header row, then one row per record",
            "content": {"text/csv": {"schema": {"type": "string"}}},
        },
    },
)
def log_csv(console: ConsoleDep, filters: FilterQ, limit: ExportLimitQ = 100_000) -> Response:
    """The log as a CSV file (oldest first), with the acknowledgement's figures as columns
    (with a fleet, each record's ``vehicle`` after ``target``)."""
    buf = io.StringIO()
    rows = reversed(_rows(console, filters, limit))
    csv.writer(buf).writerows(csv_rows(rows, fleet=console.fleet.configured))
    return Response(
        buf.getvalue(),
        media_type="text/csv",
        headers={"Content-Disposition": 'attachment; filename="nemesys-log.csv"'},
    )


@router.get("/dives", response_model=list[DiveSummary])
def dives(console: ConsoleDep) -> list[DiveSummary]:
    assert console.log is not None
    return [DiveSummary.model_validate(row) for row in console.log.dives()]


def _dive(console: ConsoleDep, dive: int, vehicle: str | None = None) -> DiveDetail:
    assert console.log is not None
    if not console.log.dive_exists(dive):
        raise HTTPException(404, f"no dive {dive}")
    track = track_lat_lon(console.log.track(dive, vehicle), console.datum)
    rows = console.log.commands(dive=dive, vehicle=vehicle, limit=100_000, oldest_first=True)
    return DiveDetail(
        dive=dive,
        track=[TrackPoint.model_validate(point) for point in track],
        commands=[command_record(row) for row in rows],
    )


@router.get(
    "/dives/{dive}",
    response_model=DiveDetail,
    response_model_exclude_unset=True,
    responses=errors((404, 422)),
)
def dive(
    dive: IdPath,
    console: ConsoleDep,
    vehicle: Annotated[
        str | None, Query(max_length=32, description="a fleet's vehicle's track and commands")
    ] = None,
) -> DiveDetail:
    """A dive's track (1 Hz) and its commands, for replay (of a fleet's ``vehicle``: its
    track points and records only)."""
    return _dive(console, dive, filter_vehicle(console, vehicle, ("query", "vehicle")))


@router.post(
    "/dives/{dive}/replay",
    response_model=ReplayResult,
    response_model_exclude_unset=True,
    responses=errors((*OPERATOR, 404, 422)),
)
def replay(
    dive: IdPath,
    console: ConsoleDep,
    _op: OperatorDep,
    vehicle: QueryVehicleDep,
    x_nemesys_view: ViewHeader = None,
) -> ReplayResult:
    """Draw a dive's track and its acknowledged commands in the caller's own 3D view
    (``X-Nemesys-View``; without it, in none). ``DELETE /api/replay`` clears it. With a
    fleet, of the ``vehicle`` named (required: 422 naming the fleet's vehicles): its track
    and its commands only."""
    doc = _dive(console, dive, vehicle)
    if console.viewer is not None:
        track = [(p.t_s, p.x_m, p.y_m, p.z_m, p.heading_deg) for p in doc.track]
        marks = []
        for c in doc.commands:
            origin = c.ack.from_ if isinstance(c.ack, Ack) else None
            if c.state == "acknowledged" and origin:
                marks.append((origin.t_s, origin.x_m, origin.y_m, origin.z_m, f"#{c.id}"))
        console.viewer.show_replay(x_nemesys_view, track, marks)
    named = {} if vehicle is None else {"vehicle": vehicle}  # a fleet's names its vehicle
    return ReplayResult.model_validate(
        {"dive": dive, **named, "track_points": len(doc.track), "commands": len(doc.commands)}
    )


@router.get("/vehicle", response_model=VehicleView, response_model_exclude_unset=True)
def vehicle(console: ConsoleDep) -> VehicleView:
    """Pose, status, the vehicle's echoed active command vs the last sent, link state (with a
    fleet: its first vehicle's; each one's is ``/api/vehicles/{name}``)."""
    return console.vehicle()


@router.put(
    "/link",
    response_model=LinkHealth,
    responses=errors(
        (*OPERATOR, 409, 413, 422, 503),
        why={
            409: 'link_ber or copies_from "estimate_upper" in training (the emulated '
            "channel's BER is used)"
        },
    ),
)
def set_link(body: LinkIn, console: ConsoleDep, operator: OperatorDep) -> LinkHealth:
    """What the station assumes of its link: ``link_ber`` (a real link's bit-error rate,
    [0, 0.5)), ``delivery_target`` ((0, 1)) and ``copies_from`` (``assumed``, or
    ``estimate_upper``: the upper end of the acknowledgements' BER estimate; a change is
    logged, naming the operator). 409 for ``link_ber`` or ``estimate_upper`` in training, where
    the emulated channel's BER is used. Later commands' copies follow; returns the link's
    health."""
    try:
        return console.set_link(operator, body.link_ber, body.delivery_target, body.copies_from)
    except ValueError as err:
        raise HTTPException(409, str(err)) from None


@router.post("/link/test", response_model=LinkTestResult, responses=errors(OPERATOR))
async def link_test(console: ConsoleDep, _op: OperatorDep) -> LinkTestResult:
    """Test the vehicle link now without sending a frame: an ME modem's port or TCP gateway is
    opened if it is not open and checked (the gateway still there, nothing of an earlier frame
    waiting, writable); a rosbridge link says whether it is connected; the hybrid link checks
    both. Returns each check and the link's health after them."""
    return await test_link(console)
