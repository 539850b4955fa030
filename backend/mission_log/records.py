"""The mission log's records as typed values: what the command service, the routers and the
``/ws`` messages hand on (the store itself keeps rows as dicts, field by field).

A command's row becomes a :class:`CommandRecord` in one place, :func:`command_record`; an
event's in :func:`log_event`. Validating a row keeps exactly the fields it holds (an
acknowledgement's fields the vehicle left out stay out when serialised with
``exclude_unset``), so the JSON is the row's.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, JsonValue, WithJsonSchema

from backend.commands.lifecycle import State

#: A number as the source gave it: an integer stays an integer (``3``), a float a float.
Number = Annotated[int | float, WithJsonSchema({"type": "number"})]
#: A parameter's value: a number, or a choice's name (``"cw"``).
ParamValue = Annotated[
    int | float | str, WithJsonSchema({"anyOf": [{"type": "number"}, {"type": "string"}]})
]
#: Parameters by name (units as in ``/api/dictionary``).
Params = dict[str, ParamValue]
#: The path a command came by: one of this console's, or ``relay:<console>`` (a command another
#: console without a transmitter checked and handed over: :mod:`backend.relay`).
PathOrigin = Literal["api", "ws", "surface", "retry", "script", "scenario", "cli"]
RelayOrigin = Annotated[str, Field(pattern=r"^relay:[A-Za-z0-9][A-Za-z0-9._-]{0,63}$")]


def lenient(description: str) -> Any:
    """A field of something the vehicle sent: the documented shape when it fits, else any
    JSON object (a vehicle outside the contract must not make the log unreadable)."""
    return Field(union_mode="left_to_right", description=description)


class CommandJson(BaseModel):
    """A command: its pattern (name and ID) and its parameters as sent (snapped)."""

    pattern: str
    pattern_id: int
    params: Params


class VehicleStateOut(BaseModel):
    """The vehicle as the planner saw it (NED m, deg, m/s, mission clock s); ``segment``:
    the active path's segment guidance tracked, when known."""

    x_m: float
    y_m: float
    z_m: float
    heading_deg: float
    speed_mps: float
    t_s: float
    segment: int | None


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
    origin: PathOrigin | RelayOrigin | None = Field(
        None,
        description="the path it came by; relay:<console>: checked by that console (one without "
        "a transmitter) and sent by this record's console (null: a record from before paths "
        "were logged)",
    )
    retry_of: int | None = Field(None, description="the command this one retries")
    overrides: Overrides | None = Field(
        None, description="the limit violations the operator overrode to send it, and who"
    )
    first_sent_at: str | None = Field(
        None, description="when its first copy left (ISO 8601, UTC): the log's wire order"
    )
    console: str | None = Field(
        None,
        description="the console that wrote it (consoles sharing a log; null: a record from "
        "before consoles were named)",
    )
    vehicle: str | None = Field(
        None,
        description="the fleet's vehicle it is for (NEMESYS_VEHICLES); absent without a fleet",
    )


def command_record(row: Mapping[str, Any]) -> CommandRecord:
    """A command's row (:meth:`backend.mission_log.store.MissionLog.command`) as its record:
    the one place a row becomes typed."""
    return CommandRecord.model_validate(row)


class LogEvent(BaseModel):
    """Something the vehicle or the operator did that the mission log keeps beside the
    commands: an echo mismatch (another station retasked the vehicle?), a new datum, the
    operator's choice of the BER the copies follow, a mission script run stopped by the
    operator's command."""

    id: int
    dive: int
    at: str = Field(description="ISO 8601, UTC")
    kind: str = Field(
        description="echo_mismatch, datum, copies_from, script_stopped, control (who is in "
        "control), relay (a relayed command refused by the console holding the transmitter)"
    )
    detail: str = Field(description="what happened, in words")
    data: dict[str, JsonValue] | None = Field(description="the kind's figures (null: none)")
    vehicle: str | None = Field(
        None,
        description="the fleet's vehicle it concerns; absent without a fleet, or for them all",
    )


def log_event(row: Mapping[str, Any]) -> LogEvent:
    """An event's row (:meth:`backend.mission_log.store.MissionLog.add_event`) as its record."""
    return LogEvent.model_validate(row)


class DiveSummary(BaseModel):
    id: int
    started_at: str = Field(description="ISO 8601, UTC")
    target: str
    commands: int
    track_points: int


__all__ = [
    "Ack",
    "CommandJson",
    "CommandRecord",
    "DiveSummary",
    "LogEvent",
    "Number",
    "OverriddenViolation",
    "Overrides",
    "ParamValue",
    "Params",
    "VehicleStateOut",
    "command_record",
    "lenient",
    "log_event",
]
