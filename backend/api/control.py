"""Who is in control of each vehicle: ``GET /api/control`` and ``POST /api/control``
(:mod:`backend.control`: the rules, the heartbeat, the send gate)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, HTTPException
from pydantic import Field

from backend.api.deps import ConsoleDep, OperatorDep
from backend.api.models import Strict
from backend.api.schemas import OPERATOR, errors
from backend.control.desk import ControlDesk, UnknownVehicle
from backend.control.model import ControlAction, ControlResult, ControlView
from backend.mission_log.control import ControlRefused

router = APIRouter(prefix="/api", tags=["control"])


class ControlIn(Strict):
    """An action on a vehicle's control."""

    action: ControlAction = Field(
        description="request (granted at once if nobody is in control, else it waits for "
        "the owner's answer), grant or refuse (the owner answers the waiting request), "
        "release (the owner), takeover (only where the owner allows it)"
    )
    vehicle: Annotated[str, Field(min_length=1, max_length=64)] | None = Field(
        default=None, description='the vehicle ("nemesys" without a fleet; omitted: that one)'
    )
    takeover_allowed: bool | None = Field(
        default=None,
        description="whether another console may take over without asking: set by the "
        "console that has or gets control with this action (omitted: unchanged, or no)",
    )


def _desk(console: ConsoleDep) -> ControlDesk:
    if console.control is None:
        raise HTTPException(503, "the console is starting")
    return console.control.desk


@router.get("/control", response_model=list[ControlView], responses=errors((503,)))
def control_list(console: ConsoleDep) -> list[ControlView]:
    """Who is in control of each vehicle (``{vehicle, console, operator, epoch,
    takeover_allowed, since}``, and a request waiting for the owner's answer). On a SQLite
    log the one console is in control (``implicit``)."""
    return _desk(console).views()


@router.post(
    "/control",
    response_model=ControlResult,
    responses=errors(
        (*OPERATOR, 409, 413, 422, 503),
        why={
            409: "the rules do not allow it: only the console in control grants, refuses or "
            "releases; a takeover only where the owner allows it; no request to answer",
            422: "invalid input, or a vehicle this console does not have",
        },
    ),
)
def control_act(body: ControlIn, console: ConsoleDep, _op: OperatorDep) -> ControlResult:
    """Request, grant, refuse, release or take over control of a vehicle, as this console
    and its operator. Every change is logged as an event and shown on every console's pages
    (``control`` and ``event`` on ``/ws``); the owner's pages show a waiting request."""
    desk = _desk(console)
    try:
        return desk.act(body.action, body.vehicle, body.takeover_allowed)
    except UnknownVehicle as err:
        detail = [{"loc": ["body", "vehicle"], "msg": str(err), "type": "value_error"}]
        raise HTTPException(422, detail) from None
    except ControlRefused as err:
        raise HTTPException(409, str(err)) from None
