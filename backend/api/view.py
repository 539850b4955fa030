"""A page's own 3D view: the ``X-Nemesys-View`` header, clearing what it shows, and the
replay's slider marker.

A page makes a random view id when it loads, opens the 3D view with it (the websocket URL
``ws://host:port/view/<id>``) and sends it as ``X-Nemesys-View`` on every API call: previews,
script previews and replays are then drawn in that page's view only. A call without the
header (an API user) draws nothing in any view. Clearing needs no token: it only changes the
caller's own view, nothing on the vehicle.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Header, HTTPException
from fastapi.exceptions import RequestValidationError

from backend.api.deps import ConsoleDep, required_vehicle
from backend.api.models import ReplayAtIn
from backend.api.schemas import errors
from backend.api.schemas.dives import ReplayAt, TimelineSample
from backend.api.schemas.view import ViewCleared
from backend.chart.reach import track_lat_lon
from backend.mission_log.timeline import vehicle_at, vehicle_events
from backend.viewer.ids import VIEW_ID_PATTERN

#: The caller's view id (8-64 of ``A-Z a-z 0-9 _ -``), or None.
ViewHeader = Annotated[
    str | None,
    Header(
        pattern=VIEW_ID_PATTERN,
        description="the calling page's 3D view (8-64 of A-Z a-z 0-9 _ -): what the call "
        "draws goes to that view only; absent: drawn in no view",
    ),
]

router = APIRouter(prefix="/api", tags=["view"])


@router.delete("/replay", response_model=ViewCleared, responses=errors((422,)))
def clear_replay(console: ConsoleDep, x_nemesys_view: ViewHeader = None) -> ViewCleared:
    """Remove the replayed dive from the caller's own 3D view (``X-Nemesys-View``)."""
    cleared = False
    if x_nemesys_view is not None and console.viewer is not None:
        cleared = console.viewer.clear_replay(x_nemesys_view)
    return ViewCleared(view=x_nemesys_view, cleared=cleared)


@router.put(
    "/replay/at",
    response_model=ReplayAt,
    response_model_exclude_unset=True,
    responses=errors((404, 413, 422)),
)
def replay_at(body: ReplayAtIn, console: ConsoleDep, x_nemesys_view: ViewHeader = None) -> ReplayAt:
    """The replayed vehicle at ``t_s`` of dive ``dive`` (s on the dive's clock, within its
    timeline's ``from_t_s`` .. ``duration_s``: 422 naming them otherwise): where it was and
    the command it was running, drawn as a marker in the caller's own 3D view
    (``X-Nemesys-View``; without it, in none). No token: it changes only the caller's view.
    With a fleet, of the ``vehicle`` named (required: 422 naming the fleet's vehicles), on
    its own timeline (``GET /api/dives/{dive}/timeline?vehicle=``)."""
    log = console.log
    assert log is not None
    vehicle = required_vehicle(console, body.vehicle, ("body", "vehicle"))
    row = log.dive(body.dive)
    if row is None:
        raise HTTPException(404, f"no dive {body.dive}")
    commands = log.commands(dive=body.dive, vehicle=vehicle, limit=100_000, oldest_first=True)
    events = vehicle_events(log.events(body.dive), vehicle)
    rows = log.track_rows(body.dive, vehicle=vehicle)
    (lo, hi), pos = vehicle_at(rows, commands, events, row["started_at"], body.t_s)
    if not lo <= body.t_s <= hi:
        whose = "" if vehicle is None else f" of {vehicle}"
        msg = f"t_s must be within {lo:g} to {hi:g} s (dive {body.dive}'s timeline{whose})"
        raise RequestValidationError(
            [{"loc": ("body", "t_s"), "msg": msg, "type": "value_error", "input": body.t_s}]
        )
    named = {} if vehicle is None else {"vehicle": vehicle}  # a fleet's names its vehicle
    if pos is None:
        return ReplayAt.model_validate(
            {"dive": body.dive, **named, "t_s": body.t_s, "position": None, "drawn": False}
        )
    track_lat_lon([pos], console.datum)
    drawn = x_nemesys_view is not None and console.viewer is not None
    if console.viewer is not None and x_nemesys_view is not None:
        console.viewer.show_replay_at(
            x_nemesys_view, pos["x_m"], pos["y_m"], pos["z_m"], pos["heading_deg"]
        )
    position = TimelineSample.model_validate(pos)
    return ReplayAt.model_validate(
        {"dive": body.dive, **named, "t_s": body.t_s, "position": position, "drawn": drawn}
    )
