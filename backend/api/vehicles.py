"""Every vehicle of the console, and the one transmitter their frames share (issue 23).

Without a fleet the list holds the one vehicle, ``nemesys`` (address null), and
``/api/vehicle`` is unchanged; with one (``NEMESYS_VEHICLES``), each vehicle in the order
configured. Read-only, no token needed.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, HTTPException, Path

from backend.api.deps import ConsoleDep
from backend.api.schemas import errors
from backend.commands.vehicles import UnknownVehicle
from backend.fleet import views
from backend.fleet.models import FleetVehicleView, TransmitterView

router = APIRouter(prefix="/api", tags=["vehicles"])

#: A vehicle's name in a path: as the fleet setting allows it (an unknown one is a 404).
NamePath = Annotated[str, Path(min_length=1, max_length=32, description="the vehicle's name")]


@router.get("/vehicles", response_model=list[FleetVehicleView], response_model_exclude_unset=True)
def vehicles(console: ConsoleDep) -> list[FleetVehicleView]:
    """Every vehicle (``name``, ``address``), each as ``/api/vehicle`` shows one: pose,
    status, its echoed and last sent command, its link health and belief, and the airtime
    its queued copies need."""
    return views.vehicle_list(console)


@router.get(
    "/vehicles/{name}",
    response_model=FleetVehicleView,
    response_model_exclude_unset=True,
    responses=errors((404, 422)),
)
def vehicle(name: NamePath, console: ConsoleDep) -> FleetVehicleView:
    """One vehicle, as ``/api/vehicle`` shows the single one (404 naming the vehicles the
    console has)."""
    try:
        return views.fleet_vehicle(console, name)
    except UnknownVehicle as err:
        raise HTTPException(404, str(err)) from None


@router.get("/transmitter", response_model=TransmitterView)
def transmitter(console: ConsoleDep) -> TransmitterView:
    """The one transmitter every vehicle's frames leave by: every command whose copies are
    still going out, and the airtime budget (seconds until every vehicle's queued copies are
    out: a frame at a time, each command's copies spaced, a Surface first)."""
    return views.transmitter(console)
