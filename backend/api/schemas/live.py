"""Every message of the live websocket ``/ws``, as models: ``docs/live.md`` is written from
them (``scripts/gen_live_doc.py``).

Server -> client: the news every page gets (:mod:`backend.messages`: ``telemetry`` (a fleet's
vehicles' in one ``fleet_telemetry``), ``command``, ``vehicle``, ``active_path``, ``link``,
``event``, ``belief``, ``control``) and the answers to a page's own control messages
(``auth_ok``, ``auth_refused``, ``queued``, ``error``).
Client -> server: ``auth``, then ``surface`` or ``send``. Each message is a JSON object whose
``type`` names it: the unions below are discriminated by it.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, get_args

from pydantic import BaseModel, Field, TypeAdapter

from backend.api.models import SendIn, VehicleIn
from backend.api.schemas.common import LimitViolation
from backend.messages import (
    ActivePathMessage,
    BeliefMessage,
    CommandMessage,
    ControlMessage,
    EventMessage,
    FleetTelemetryMessage,
    LinkMessage,
    Message,
    TelemetryMessage,
    VehicleMessage,
)
from backend.mission_log.records import CommandRecord

# --- answers to the page's control messages (server -> that page) --------------------------


class AuthOk(Message):
    """The token was right: this connection may send control messages."""

    type: Literal["auth_ok"] = "auth_ok"


class AuthRefused(Message):
    """The token was wrong (or not text). The page goes read-only at once, saying what to do
    (e.g. the console restarted with ``--new-token``); the connection stays open."""

    type: Literal["auth_refused"] = "auth_refused"
    detail: str = Field(description="why, in words")


class Queued(Message):
    """A ``surface`` or ``send`` went through the command service: its record as written
    (queued, or a Surface joined); a fleet's Surface to all: every vehicle's record."""

    type: Literal["queued"] = "queued"
    command: CommandRecord = Field(description="the record as written (to all: the first)")
    commands: list[CommandRecord] | None = Field(
        default=None, description='a Surface to "all": the records, one per vehicle'
    )


class ErrorReply(Message):
    """A control message refused; nothing was transmitted. ``field``, ``status`` and
    ``violations`` are present only where they apply."""

    type: Literal["error"] = "error"
    detail: str = Field(description="what was wrong, in words")
    field: str | None = Field(
        default=None, description="the field at fault (null: a value the codec refused without one)"
    )
    status: int | None = Field(
        default=None,
        description="the HTTP status REST answers the same refusal with (422, 409, 429, 503, 504)",
    )
    violations: list[LimitViolation] | None = Field(
        default=None, description="the limits the command breaks (a refusal by the checks)"
    )


# --- the page's control messages (client -> server) -----------------------------------------


class AuthMessage(BaseModel):
    """The operator's token; answered ``auth_ok`` or ``auth_refused``. A page sends it on
    every (re)connection."""

    type: Literal["auth"]
    token: str = Field(description="the operator token (``nemesys console`` prints it)")


class SurfaceMessage(BaseModel):
    """Surface now (as the Surface button): never refused by the checks. With a fleet,
    ``vehicle`` names one vehicle or ``"all"`` (required)."""

    type: Literal["surface"]
    vehicle: VehicleIn = None


class SendMessage(SendIn):
    """A command, checked as ``POST /api/commands`` checks it (the same fields and rules:
    ``override`` accepts the soft violations, ``copies`` 1-20 or omitted, ``vehicle`` with a
    fleet; no other field)."""

    type: Literal["send"]


# --- the unions -----------------------------------------------------------------------------

#: The models of each direction, plain unions (each used once below, with its discriminator).
_Client = AuthMessage | SurfaceMessage | SendMessage
_Server = (
    TelemetryMessage
    | FleetTelemetryMessage
    | CommandMessage
    | VehicleMessage
    | ActivePathMessage
    | LinkMessage
    | EventMessage
    | BeliefMessage
    | ControlMessage
    | AuthOk
    | AuthRefused
    | Queued
    | ErrorReply
)
#: What a page may send.
ClientMessage = Annotated[_Client, Field(discriminator="type")]
#: What the console sends a page: the news, and the answers to its own messages.
ServerMessage = Annotated[_Server, Field(discriminator="type")]
#: Every message of ``/ws``, either way.
LiveMessage = Annotated[_Server | _Client, Field(discriminator="type")]

#: Parses a page's message (after the size, nesting and number checks of the handler).
CLIENT_MESSAGE: TypeAdapter[_Client] = TypeAdapter(ClientMessage)


def message_models(union: Any) -> tuple[type[BaseModel], ...]:
    """The models of a discriminated union of messages, in its order."""
    members: tuple[type[BaseModel], ...] = get_args(get_args(union)[0])
    return members


def type_of(model: type[BaseModel]) -> str:
    """A message model's ``type`` (the one value its ``Literal`` takes)."""
    value: str = get_args(model.model_fields["type"].annotation)[0]
    return value


def message_types(union: Any) -> tuple[str, ...]:
    """The ``type`` of every member of a discriminated union, in its order."""
    return tuple(type_of(m) for m in message_models(union))


#: The ``type`` of each message a page may send.
CLIENT_TYPES = message_types(ClientMessage)

__all__ = [
    "CLIENT_MESSAGE",
    "CLIENT_TYPES",
    "AuthMessage",
    "AuthOk",
    "AuthRefused",
    "ClientMessage",
    "ErrorReply",
    "LiveMessage",
    "Queued",
    "SendMessage",
    "ServerMessage",
    "SurfaceMessage",
    "message_models",
    "message_types",
    "type_of",
]
