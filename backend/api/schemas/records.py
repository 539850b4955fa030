"""The mission log's records, dives, and the vehicle as the console knows it.

The records themselves are the mission log's (:mod:`backend.mission_log.records`) and the
vehicle's shapes the ``/ws`` news's (:mod:`backend.messages`): the service and the console
hand them to the routers typed; they are named here with the responses built from them.
"""

from __future__ import annotations

from pydantic import BaseModel, Field

from backend.messages import ActivePath, LastSent, Pose, VehicleStatus, VehicleView
from backend.mission_log.records import (
    Ack,
    CommandRecord,
    DiveSummary,
    OverriddenViolation,
    Overrides,
)


class TrackPoint(BaseModel):
    """A track point (NED m); ``lat_deg``/``lon_deg`` from the current datum (null: none)."""

    t_s: float
    x_m: float
    y_m: float
    z_m: float
    heading_deg: float
    lat_deg: float | None
    lon_deg: float | None


class DiveDetail(BaseModel):
    """A dive's track (1 Hz) and its commands, oldest first."""

    dive: int
    track: list[TrackPoint]
    commands: list[CommandRecord]


class ReplayResult(BaseModel):
    dive: int
    vehicle: str | None = Field(
        None, description="the fleet's vehicle replayed (absent without a fleet)"
    )
    track_points: int
    commands: int


__all__ = [
    "Ack",
    "ActivePath",
    "CommandRecord",
    "DiveDetail",
    "DiveSummary",
    "LastSent",
    "OverriddenViolation",
    "Overrides",
    "Pose",
    "ReplayResult",
    "TrackPoint",
    "VehicleStatus",
    "VehicleView",
]
