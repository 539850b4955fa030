"""A page's own 3D view: the ``X-Nemesys-View`` header, and clearing what it shows.

A page makes a random view id when it loads, opens the 3D view with it (the websocket URL
``ws://host:port/view/<id>``) and sends it as ``X-Nemesys-View`` on every API call: previews,
script previews and replays are then drawn in that page's view only. A call without the
header (an API user) draws nothing in any view. Clearing needs no token: it only changes the
caller's own view, nothing on the vehicle.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Header

from backend.api.deps import ConsoleDep
from backend.api.schemas import errors
from backend.api.schemas.view import ViewCleared
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
