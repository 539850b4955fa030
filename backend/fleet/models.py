"""The fleet's views as models: ``GET /api/vehicles`` and ``/api/vehicles/{name}`` (each vehicle
as ``/api/vehicle`` shows the one, with its name and address) and ``GET /api/transmitter`` (the
one transmitter: every copy still to go out, and how long until they are)."""

from __future__ import annotations

from pydantic import BaseModel, Field

from backend.messages import VehicleView
from backend.mission_log.records import CommandRecord

__all__ = ["FleetSurface", "FleetVehicleView", "QueuedDelivery", "TransmitterView"]


class FleetVehicleView(VehicleView):
    """One vehicle of the console: as ``/api/vehicle`` (pose, status, its echoed and last sent
    command, its link health and belief), with its name, its address and the airtime its
    queued copies need. Without a fleet, the one vehicle ``nemesys`` (address null)."""

    name: str = Field(description="its name: its ROS namespace in a fleet; nemesys alone")
    address: int | None = Field(
        description="the address its frames carry (1-15); null: the single vehicle's "
        "unaddressed frames"
    )
    airtime_budget_s: float = Field(
        description="seconds until every copy queued for it (a Surface to all included) has "
        "left the one transmitter, as scheduled now (0: none queued)"
    )
    repeating: bool = Field(
        description="a Surface to it repeats until it acknowledges (not in airtime_budget_s)"
    )


class QueuedDelivery(BaseModel):
    """A command whose copies are still going out (one frame for all its records)."""

    commands: list[int] = Field(description="its records (a Surface to all: one per vehicle)")
    vehicles: list[str] = Field(description="the vehicles those records are for")
    pattern: str
    copies_left: int | None = Field(description="copies still to leave; null: until acknowledged")
    next_copy_in_s: float = Field(description="until its next copy may leave (s; 0: now)")
    surface: bool = Field(description="a Surface: its copies go first among those due")
    frame_airtime_s: float = Field(description="one copy's time on the link (s)")


class TransmitterView(BaseModel):
    """The one transmitter every vehicle's frames leave by (``GET /api/transmitter``)."""

    target: str
    connected: bool
    problems: list[str] = Field(
        description="why frames may not leave now: the connection's problem (empty: none)"
    )
    addressed: bool = Field(description="frames carry an address (a fleet is configured)")
    airtime_budget_s: float = Field(
        description="seconds until every queued bounded copy, of every vehicle, has left (a "
        "frame at a time, each command's copies spaced, a Surface first; 0: none queued)"
    )
    repeating_until_acknowledged: list[str] = Field(
        description="vehicles a Surface repeats to until they acknowledge (no end to count)"
    )
    queued: list[QueuedDelivery]


class FleetSurface(BaseModel):
    """``POST /api/surface {"vehicle": "all"}``: one frame to every vehicle (address 0), one
    record per vehicle (each ends as that vehicle's acknowledgement, or its copies, say)."""

    vehicle: str = Field(description='"all"')
    commands: list[CommandRecord] = Field(description="the records written, one per vehicle")
