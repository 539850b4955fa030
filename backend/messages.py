"""What the console tells every page: the news messages of ``/ws`` and the vehicle as the
console knows it (``GET /api/vehicle``, the same shapes).

Each message is a model whose ``type`` names it (:class:`Message`); the place that publishes
builds it and the telemetry hub serialises it once (:func:`message_json`) for every page.
The control protocol (the page's own messages, and the answers to them) and the union of
every ``/ws`` message, documented in ``docs/live.md``, are in
:mod:`backend.api.schemas.live`.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, TypeVar

from pydantic import BaseModel, ConfigDict, Field

from backend.belief.model import Belief
from backend.commands.health import LinkHealth
from backend.control.model import ControlView
from backend.mission_log.records import CommandJson, CommandRecord, LogEvent, Params, lenient


def _type_required(schema: dict[str, Any]) -> None:
    """A message's ``type`` is always sent (its default is the only value it takes)."""
    required = schema.setdefault("required", [])
    if "type" not in required:
        required.insert(0, "type")


class Message(BaseModel):
    """A ``/ws`` message: ``type`` (a constant per class) says which. It is always serialised,
    whatever else is left out as unset (an acknowledgement's fields the vehicle did not send,
    an error's ``field`` that does not apply)."""

    model_config = ConfigDict(json_schema_extra=_type_required)

    def model_post_init(self, context: Any, /) -> None:
        self.model_fields_set.add("type")


M = TypeVar("M", bound=Message)


def for_vehicle(message: M, vehicle: str | None) -> M:
    """``message`` naming the fleet's ``vehicle`` it concerns (None: no fleet, the message as
    it always was: no ``vehicle`` key at all)."""
    if vehicle is not None:
        message.vehicle = vehicle  # type: ignore[attr-defined]  # the messages that have one
    return message


def message_json(message: BaseModel) -> str:
    """A message as its JSON text: the fields set (so a record's JSON is its row's), by alias
    (an acknowledgement's ``from``); a non-finite number is ``null``."""
    return message.model_dump_json(by_alias=True, exclude_unset=True)


def _vehicle_field() -> Any:
    """The vehicle a message concerns, named where a fleet is configured (``NEMESYS_VEHICLES``);
    absent without one (the single vehicle's messages are as they always were)."""
    return Field(
        default=None,
        description="the fleet's vehicle it concerns (absent without a fleet: the one vehicle)",
    )


# --- the vehicle as the console knows it ----------------------------------------------------


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


#: The vehicle's echo of its active command: the documented shape when it fits, else as sent.
ActiveEcho = Annotated[
    CommandJson | dict[str, Any] | None,
    lenient("the vehicle's echo of its active command (its last acknowledgement's)"),
]


class VehicleView(BaseModel):
    """Pose, status, the vehicle's echoed active command vs the last sent, link health."""

    pose: Pose | None
    status: VehicleStatus | None
    active: ActiveEcho
    last_sent: LastSent | None
    active_path: ActivePath | None = Field(
        description="the path the vehicle flies, as mirrored; null when none is known"
    )
    echo_mismatch: bool
    age_s: float | None = Field(description="seconds since the vehicle was last heard from")
    link: LinkHealth
    belief: Belief | None = Field(
        None, description="what the console believes the vehicle does (null: starting)"
    )


# --- the news: server -> every page ---------------------------------------------------------


class TelemetryMessage(Message):
    """The latest pose and status (latest value wins, at most ``telemetry_hz`` a second); as
    in ``/api/vehicle``."""

    type: Literal["telemetry"] = "telemetry"
    pose: Pose | None = Field(description="the last pose (null: none yet)")
    status: VehicleStatus | None = Field(description="the last status (null: none yet)")
    age_s: float | None = Field(description="seconds since the vehicle was last heard from")
    dive: int | None = Field(
        default=None,
        description="the dive the console records them in (null: none yet); a page's plots "
        "start again when it changes",
    )
    relayed_via: str | None = Field(
        default=None,
        description="a console without a transmitter (target relay): the console whose track "
        "points in the shared mission log these were read from (at most one a second; "
        "``age_s`` since that console heard them); absent: heard over this console's own link",
    )
    vehicle: str | None = _vehicle_field()


class FleetTelemetryMessage(Message):
    """A fleet's telemetry (``NEMESYS_VEHICLES``): every vehicle whose pose or status changed
    since this page last got it, in one message (at most ``telemetry_hz`` a second), each as
    a ``telemetry`` message naming its vehicle. One message a period, not one per vehicle,
    so the pages' cost does not grow with the fleet."""

    type: Literal["fleet_telemetry"] = "fleet_telemetry"
    telemetry: list[TelemetryMessage] = Field(
        description="each changed vehicle's latest telemetry, in the fleet's order"
    )


class CommandMessage(Message):
    """A command's record, on every change of its state (in order)."""

    type: Literal["command"] = "command"
    command: CommandRecord = Field(description="the record as written (its new state)")


class VehicleMessage(Message):
    """The vehicle's echoed active command, when an acknowledgement arrives."""

    type: Literal["vehicle"] = "vehicle"
    active: ActiveEcho
    echo_mismatch: bool = Field(description="it differs from the last command it accepted")
    vehicle: str | None = _vehicle_field()


class ActivePathMessage(Message):
    """The mirrored path the vehicle flies, when it changes (null: none); every page's chart
    draws it."""

    type: Literal["active_path"] = "active_path"
    active_path: ActivePath | None = Field(description="null: no path is known")
    vehicle: str | None = _vehicle_field()


class LinkMessage(Message):
    """The vehicle link's health (as in ``/api/vehicle``), every second while a page listens."""

    type: Literal["link"] = "link"
    link: LinkHealth = Field(description="what the station knows of its link to the vehicle")
    vehicle: str | None = _vehicle_field()


class EventMessage(Message):
    """An event the mission log kept (an echo mismatch, a new datum, a script run the
    operator's command stopped)."""

    type: Literal["event"] = "event"
    event: LogEvent = Field(description="the event as the mission log wrote it")


class BeliefMessage(Message):
    """What the console believes the vehicle does (as in ``/api/vehicle``): on every change
    of a command's state, an acknowledgement or a status, with a new position at most every
    0.5 s, and at least every second while the position is dead-reckoned or assumed."""

    type: Literal["belief"] = "belief"
    belief: Belief = Field(description="the last sent, the believed command, position, Surface")


class ControlMessage(Message):
    """Who is in control of a vehicle, at every change (a request, a grant or refusal, a
    release, a takeover, a timeout), made by this console or another sharing the mission
    log; the owner's page shows a waiting ``request`` with its grant and refuse."""

    type: Literal["control"] = "control"
    control: ControlView = Field(description="the vehicle's control after the change")


#: What the hub publishes to every page.
News = Annotated[
    TelemetryMessage
    | FleetTelemetryMessage
    | CommandMessage
    | VehicleMessage
    | ActivePathMessage
    | LinkMessage
    | EventMessage
    | BeliefMessage
    | ControlMessage,
    Field(discriminator="type"),
]

__all__ = [
    "ActiveEcho",
    "ActivePath",
    "ActivePathMessage",
    "BeliefMessage",
    "CommandMessage",
    "ControlMessage",
    "EventMessage",
    "FleetTelemetryMessage",
    "LastSent",
    "LinkMessage",
    "Message",
    "News",
    "Pose",
    "TelemetryMessage",
    "VehicleMessage",
    "VehicleStatus",
    "VehicleView",
    "for_vehicle",
    "message_json",
]
