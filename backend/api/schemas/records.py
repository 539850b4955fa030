"""The mission log's records, dives, and the vehicle as the console knows it."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from backend.api.schemas.common import CommandJson, Params, VehicleStateOut
from backend.commands.health import LinkHealth
from backend.commands.lifecycle import State


def lenient(description: str) -> Any:
    """A field of something the vehicle sent: the documented shape when it fits, else any
    JSON object (a vehicle outside the contract must not make the log unreadable)."""
    return Field(union_mode="left_to_right", description=description)


class Ack(BaseModel):
    """The vehicle's acknowledgement of a frame, as it sent it (the vehicle contract's ack
    schema: ``nemesys contract``). Fields it left out stay out; extra fields are kept (the
    simulator adds ``channel_flipped_bits``)."""

    model_config = ConfigDict(extra="allow")

    seq: int | None = None
    t_s: float | None = Field(None, description="the vehicle's ROS time of the verdict (s)")
    outcome: Literal["accepted", "rejected"] | None = None
    frame_hex: str | None = None
    corrected_bits: int | None = None
    sync_errors: int | None = None
    reason: str | None = Field(None, description="why it was rejected; null when accepted")
    detail: str | None = None
    field: str | None = None
    command: CommandJson | None = None
    duplicate: bool | None = None
    decode_latency_ms: float | None = None
    replan_latency_ms: float | None = None
    waypoints: int | None = None
    active: CommandJson | None = None
    from_: VehicleStateOut | None = Field(
        None, alias="from", description="the state the new plan was made from"
    )


class OverriddenViolation(BaseModel):
    check: str
    param: str
    message: str


class Overrides(BaseModel):
    """Who overrode which limit violations to send a command."""

    by: str = Field(description="the operator")
    violations: list[OverriddenViolation]


class CommandRecord(BaseModel):
    """A command of the mission log (docs/api.md: "Command record")."""

    id: int
    dive: int
    created_at: str = Field(description="ISO 8601, UTC")
    updated_at: str = Field(description="ISO 8601, UTC")
    operator: str
    target: str
    kind: Literal["command", "surface", "script"]
    pattern: str
    pattern_id: int
    params: Params = Field(description="the values sent (snapped to the codec's steps)")
    requested: Params = Field(description="the values asked for")
    bits: str
    hex: str
    state: State
    attempts: int = Field(description="frames handed to the link, failed ones included")
    sent_at: str | None
    acked_at: str | None
    ack: Annotated[
        Ack | dict[str, Any] | None, lenient("the vehicle's acknowledgement; null: none yet")
    ]
    reason: str | None
    copies: int | None = Field(description="copies planned; null: a Surface until acknowledged")
    copies_sent: int
    p_delivered: float = Field(description="probability that at least one copy decodes")
    ber: float | None = Field(description="the bit-error rate the copies were chosen from")
    two_way: bool | None = Field(description="an acknowledgement was expected")
    superseded_by: int | None
    origin: Literal["api", "ws", "surface", "retry", "script", "scenario", "cli"] | None = Field(
        None, description="the path it came by (null: a record from before paths were logged)"
    )
    retry_of: int | None = Field(None, description="the command this one retries")
    overrides: Overrides | None = Field(
        None, description="the limit violations the operator overrode to send it, and who"
    )
    first_sent_at: str | None = Field(
        None, description="when its first copy left (ISO 8601, UTC): the log's wire order"
    )


class DiveSummary(BaseModel):
    id: int
    started_at: str = Field(description="ISO 8601, UTC")
    target: str
    commands: int
    track_points: int


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
    track_points: int
    commands: int


class Pose(BaseModel):
    """The vehicle's last pose (NED); a number it did not send (null, NaN) is null;
    ``lat_deg``/``lon_deg`` from the datum (null without one, or without x/y)."""

    t_s: float | None
    x_m: float | None
    y_m: float | None
    z_m: float | None
    heading_deg: float | None
    roll_deg: float | None
    lat_deg: float | None
    lon_deg: float | None


class VehicleStatus(BaseModel):
    """The vehicle's last status as it sent it (the vehicle contract's status schema:
    ``mode``, ``pattern``, ``active``, the simulator's ``link``, ...); the numbers the
    console reads are a finite number or null."""

    model_config = ConfigDict(extra="allow")

    t_s: float | None
    depth_m: float | None
    heading_deg: float | None
    speed_mps: float | None
    battery_pct: float | None
    x_m: float | None
    y_m: float | None


class LastSent(BaseModel):
    """The last command that left the station."""

    id: int
    pattern: str
    pattern_id: int
    params: Params


class ActivePath(BaseModel):
    """The path the vehicle flies, as the station mirrors it from what it sent and what the
    vehicle acknowledged (NED m; lat/lon deg, null without a datum)."""

    pattern: str
    x_m: list[float]
    y_m: list[float]
    z_m: list[float]
    lat_deg: list[float] | None
    lon_deg: list[float] | None


class VehicleView(BaseModel):
    """Pose, status, the vehicle's echoed active command vs the last sent, link health."""

    pose: Pose | None
    status: VehicleStatus | None
    active: Annotated[
        CommandJson | dict[str, Any] | None,
        lenient("the vehicle's echo of its active command (its last acknowledgement's)"),
    ]
    last_sent: LastSent | None
    active_path: ActivePath | None = Field(
        description="the path the vehicle flies, as mirrored; null when none is known"
    )
    echo_mismatch: bool
    age_s: float | None = Field(description="seconds since the vehicle was last heard from")
    link: LinkHealth
