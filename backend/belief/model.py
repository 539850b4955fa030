"""The belief's shapes: ``GET /api/vehicle`` -> ``belief`` and the ``belief`` message of
``/ws`` carry the same :class:`Belief`.

Units are in the names (m, deg, s); probabilities are in [0, 1]; times are the console's
wall clock (ages in seconds, ISO 8601 UTC stamps as the mission log writes them).
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

from backend.mission_log.records import Params

#: The name of the one vehicle a console drives today (a fleet keys its beliefs by name).
DEFAULT_VEHICLE = "nemesys"

Source = Literal["telemetry", "dead_reckoning", "assumed"]
Kind = Literal["command", "last_known", "unknown"]


class SentCommand(BaseModel):
    """The command whose first copy left the station most recently (wire order)."""

    id: int
    pattern: str
    params: Params


class BelievedCommand(BaseModel):
    """One candidate for what the vehicle runs now, with its probability and why."""

    kind: Kind = Field(
        description="command: one of this console's records; last_known: what the vehicle was "
        "last known to run (its echo, or nothing: holding); unknown: nothing is known"
    )
    id: int | None = Field(description="the record's id (null: not one of this console's)")
    pattern: str | None = Field(description="null: no command (holding), or unknown")
    params: Params | None
    p: float = Field(ge=0.0, le=1.0, description="probability that it is what the vehicle runs")
    reason: str = Field(description="where the probability comes from, in words")


class BelievedPosition(BaseModel):
    """Where the vehicle probably is (NED m from the datum; lat/lon through the datum).

    ``source``: ``telemetry`` (the last fix, while telemetry is fresh), ``dead_reckoning``
    (the last fix run forward under the believed command), ``assumed`` (no fix ever: a start
    was assumed, named in ``basis``)."""

    x_m: float
    y_m: float
    z_m: float = Field(description="depth (m, positive down)")
    heading_deg: float
    speed_mps: float
    lat_deg: float | None = Field(description="null without a datum")
    lon_deg: float | None
    sigma_m: float | None = Field(
        description="the horizontal uncertainty (m, one standard deviation of the modelled "
        "error); null: unknown (the start itself is assumed)"
    )
    source: Source
    age_s: float | None = Field(
        description="seconds (console clock) since the fix it rests on; null: no fix ever"
    )
    t_s: float = Field(description="the vehicle's mission clock it is estimated for (s)")
    basis: str = Field(description="what it rests on, in words (the fix, the command, the start)")


class SurfaceBelief(BaseModel):
    """The newest Surface of this vehicle, from its record's state only."""

    in_progress: bool = Field(description="its record is on its way (queued or transmitted)")
    id: int | None = Field(description="the Surface record (null: none sent)")
    state: str | None
    two_way: bool | None
    copies: int | None = Field(description="copies planned; null: until acknowledged")
    copies_sent: int | None
    p_delivered: float | None
    ber: float | None
    reason: str | None
    superseded_by: int | None
    changed_s: float | None = Field(description="seconds since its record last changed")


class Belief(BaseModel):
    """What the console believes one vehicle is doing, and how sure it is."""

    vehicle: str = Field(description="the vehicle's name (one per console today)")
    seq: int = Field(description="increases with every change (a page keeps the newest)")
    two_way: bool = Field(description="the link acknowledges (p is then 1 or 0)")
    last_sent: SentCommand | None
    command: BelievedCommand = Field(description="what the vehicle most probably runs now")
    runner_up: BelievedCommand | None = Field(description="the next most probable; null: none")
    position: BelievedPosition
    surface: SurfaceBelief


__all__ = [
    "DEFAULT_VEHICLE",
    "Belief",
    "BelievedCommand",
    "BelievedPosition",
    "Kind",
    "SentCommand",
    "Source",
    "SurfaceBelief",
]
