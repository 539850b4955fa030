"""Sending, Surface, the command log and its exports, dives and replay, vehicle status."""

from __future__ import annotations

import csv
import io
from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Query, Response, status
from fastapi.responses import JSONResponse
from pydantic import BaseModel, Field

from backend.api.deps import ConsoleDep, OperatorDep
from backend.api.models import LinkIn, RetryIn, SendIn
from backend.commands import CommandManager, NotRetryable
from backend.health import LinkHealth
from backend.store import STATES, csv_rows

router = APIRouter(prefix="/api", tags=["commands"])


def _manager(console: ConsoleDep) -> CommandManager:
    if console.commands is None:
        raise HTTPException(503, "the console is starting")
    return console.commands


@router.post("/commands", status_code=status.HTTP_202_ACCEPTED)
async def send(body: SendIn, console: ConsoleDep, _op: OperatorDep) -> dict[str, Any]:
    """Queue a command for transmission (logged first). 422: limits that cannot be
    overridden or bad values; 409: overridable limits without ``override``; 429: rate limit."""
    enc, doc = console.prepare(body.pattern, dict(body.params))
    hard = [v for v in doc["violations"] if not v["overridable"]]
    soft = [v for v in doc["violations"] if v["overridable"]]
    if hard:
        raise HTTPException(422, {"message": "limit violation", "violations": hard})
    if soft and not body.override:
        raise HTTPException(
            409,
            {
                "message": "limit violation: send with override to accept it",
                "violations": soft,
            },
        )
    return await _manager(console).submit(enc, copies=body.copies)


@router.post("/surface", status_code=status.HTTP_202_ACCEPTED)
async def surface(console: ConsoleDep, _op: OperatorDep) -> dict[str, Any]:
    """Abort: send surface now and again every ``surface_repeat_s``: until acknowledged on a
    two-way link, a bounded number of times on a one-way link. It replaces any command still
    being repeated; pressed while another Surface is on its way, it joins that one."""
    return await _manager(console).surface()


@router.post("/commands/{command_id}/retry", status_code=status.HTTP_202_ACCEPTED)
async def retry(
    command_id: int, console: ConsoleDep, _op: OperatorDep, body: RetryIn | None = None
) -> dict[str, Any]:
    """A new attempt of an interrupted, timed-out, failed, rejected or superseded command
    (the same record); it replaces any command still being repeated."""
    try:
        return await _manager(console).retry(command_id, body.copies if body else None)
    except KeyError:
        raise HTTPException(404, f"no command {command_id}") from None
    except NotRetryable as err:
        raise HTTPException(409, str(err)) from None


StateQ = Annotated[str | None, Query(pattern="^(" + "|".join(STATES) + ")$")]


class LogFilter(BaseModel):
    """Filters of the mission log (all optional): query parameters."""

    state: StateQ = None
    pattern: Annotated[str | None, Field(max_length=32)] = None
    target: Annotated[str | None, Field(max_length=200)] = None
    dive: Annotated[int | None, Field(ge=1)] = None
    since: Annotated[str | None, Field(max_length=40, description="ISO time, UTC")] = None
    until: Annotated[str | None, Field(max_length=40, description="ISO time, UTC")] = None


FilterQ = Annotated[LogFilter, Query()]


def _rows(console: ConsoleDep, filters: LogFilter, limit: int) -> list[dict[str, Any]]:
    assert console.log is not None
    return console.log.commands(**filters.model_dump(), limit=limit)


@router.get("/commands")
def commands(
    console: ConsoleDep, filters: FilterQ, limit: Annotated[int, Query(ge=1, le=1000)] = 200
) -> list[dict[str, Any]]:
    """The mission log, newest first."""
    return _rows(console, filters, limit)


@router.get("/commands/{command_id}")
def command(command_id: int, console: ConsoleDep) -> dict[str, Any]:
    assert console.log is not None
    record = console.log.command(command_id)
    if record is None:
        raise HTTPException(404, f"no command {command_id}")
    return record


ExportLimitQ = Annotated[int, Query(ge=1, le=100_000)]


@router.get("/log.json")
def log_json(console: ConsoleDep, filters: FilterQ, limit: ExportLimitQ = 100_000) -> JSONResponse:
    """The log as a JSON file (newest first)."""
    return JSONResponse(
        _rows(console, filters, limit),
        headers={"Content-Disposition": 'attachment; filename="nemesys-log.json"'},
    )


@router.get("/log.csv")
def log_csv(console: ConsoleDep, filters: FilterQ, limit: ExportLimitQ = 100_000) -> Response:
    """The log as a CSV file (oldest first), with the acknowledgement's figures as columns."""
    buf = io.StringIO()
    csv.writer(buf).writerows(csv_rows(reversed(_rows(console, filters, limit))))
    return Response(
        buf.getvalue(),
        media_type="text/csv",
        headers={"Content-Disposition": 'attachment; filename="nemesys-log.csv"'},
    )


@router.get("/dives")
def dives(console: ConsoleDep) -> list[dict[str, Any]]:
    assert console.log is not None
    return console.log.dives()


def _dive(console: ConsoleDep, dive: int) -> dict[str, Any]:
    assert console.log is not None
    if not console.log.dive_exists(dive):
        raise HTTPException(404, f"no dive {dive}")
    return {
        "dive": dive,
        "track": console.log.track(dive),
        "commands": console.log.commands(dive=dive, limit=100_000, oldest_first=True),
    }


@router.get("/dives/{dive}")
def dive(dive: int, console: ConsoleDep) -> dict[str, Any]:
    """A dive's track (1 Hz) and its commands, for replay."""
    return _dive(console, dive)


@router.post("/dives/{dive}/replay")
def replay(dive: int, console: ConsoleDep, _op: OperatorDep) -> dict[str, Any]:
    """Draw a dive's track and its acknowledged commands in the 3D view."""
    doc = _dive(console, dive)
    if console.viewer is not None:
        track = [(p["t_s"], p["x_m"], p["y_m"], p["z_m"], p["heading_deg"]) for p in doc["track"]]
        marks = []
        for c in doc["commands"]:
            ack = c.get("ack") or {}
            origin = ack.get("from")
            if c["state"] == "acknowledged" and origin:
                marks.append(
                    (origin["t_s"], origin["x_m"], origin["y_m"], origin["z_m"], c["pattern"])
                )
        console.viewer.show_replay(track, marks)
    return {"dive": dive, "track_points": len(doc["track"]), "commands": len(doc["commands"])}


@router.get("/vehicle")
def vehicle(console: ConsoleDep) -> dict[str, Any]:
    """Pose, status, the vehicle's echoed active command vs the last sent, link state."""
    return console.vehicle()


@router.put("/link")
def set_link(body: LinkIn, console: ConsoleDep, _op: OperatorDep) -> LinkHealth:
    """What the station assumes of its link: ``link_ber`` (a real link's bit-error rate,
    [0, 0.5); 409 in training, where the emulated channel's is used) and ``delivery_target``
    ((0, 1)). Later commands' copies follow; returns the link's health."""
    try:
        return console.set_link(body.link_ber, body.delivery_target)
    except ValueError as err:
        raise HTTPException(409, str(err)) from None
