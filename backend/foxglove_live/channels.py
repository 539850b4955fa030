"""The live view's channels: their topics, schemas and what they carry (docs/foxglove.md,
"Live", lists the same; a test compares the two and what a client is advertised).

Foxglove's well-known schemas (protobuf, :mod:`foxglove.messages`) wherever one fits, so
Foxglove's panels draw them as they are: the 3D panel the poses, the track and the scene
updates, the Map panel the location fixes, the Log panel the log lines. The rest are JSON
with a JSON Schema generated from the console's own pydantic models (the shapes ``/ws`` and
the API carry), with their ``$ref``s inlined (a schema Foxglove reads field by field for the
Plot and Raw Messages panels).

With a fleet (``NEMESYS_VEHICLES``) each vehicle has its own channels of what is its alone
(:data:`PER_VEHICLE`, under ``/<name>``: ``/auv2/vehicle/pose``), the scene's shared channels
draw one entity per vehicle (``auv2/active``), and :data:`FRAMES` names each vehicle's frame.
Without one the channels are :data:`CHANNELS`, as they always were.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final

import foxglove
from foxglove.channels import (
    FrameTransformsChannel,
    LocationFixChannel,
    LogChannel,
    PoseInFrameChannel,
    PosesInFrameChannel,
    SceneUpdateChannel,
)
from pydantic import BaseModel

from backend.belief.model import Belief
from backend.commands.health import LinkHealth
from backend.messages import VehicleStatus
from backend.mission_log.records import CommandRecord

#: JSON channels' schema names are the model's, in this namespace.
SCHEMA_PREFIX: Final = "nemesys."


@dataclass(frozen=True)
class Spec:
    """One channel: its topic, the schema name it is advertised with, what it carries."""

    topic: str
    schema: str
    what: str


POSE = Spec("/vehicle/pose", "foxglove.PoseInFrame", "the vehicle's last pose (3D panel)")
TRACK = Spec(
    "/vehicle/track",
    "foxglove.PosesInFrame",
    "the dive's track, a pose a second of the vehicle's clock (thinned past 3600 poses)",
)
FIX = Spec(
    "/vehicle/fix",
    "foxglove.LocationFix",
    "the vehicle's latitude and longitude from the datum, altitude -depth (Map panel)",
)
STATUS = Spec(
    "/vehicle/status",
    SCHEMA_PREFIX + "VehicleStatus",
    "the vehicle's status: depth, speed, heading, battery, mode (Plot panel)",
)
ACTIVE = Spec(
    "/paths/active", "foxglove.SceneUpdate", "the path the vehicle flies, as mirrored (a line)"
)
PREVIEW = Spec(
    "/paths/preview",
    "foxglove.SceneUpdate",
    "the latest preview a page drew: the join and the pattern (a line)",
)
PREDICTION = Spec(
    "/paths/prediction",
    "foxglove.SceneUpdate",
    "the latest prediction a page asked for: the twin's track (a line)",
)
BELIEF_SCENE = Spec(
    "/belief/position",
    "foxglove.SceneUpdate",
    "the believed position and its one-sigma ring while it is dead-reckoned or assumed "
    "(deleted while telemetry is fresh)",
)
BELIEF_FIX = Spec(
    "/belief/fix",
    "foxglove.LocationFix",
    "the believed position's latitude and longitude, its sigma as the covariance",
)
BELIEF = Spec(
    "/belief",
    SCHEMA_PREFIX + "Belief",
    "what the console believes the vehicle does: command, probability, position, Surface",
)
STATION = Spec(
    "/station", "foxglove.SceneUpdate", "the ME transmitter and its range ring (me_range_m)"
)
STATION_FIX = Spec(
    "/station/fix", "foxglove.LocationFix", "the ME transmitter's latitude and longitude"
)
COMMANDS = Spec(
    "/commands",
    SCHEMA_PREFIX + "CommandRecord",
    "a command's record on every change of its state",
)
LINK = Spec("/link", SCHEMA_PREFIX + "LinkHealth", "the vehicle link's health, every second")
LOG = Spec(
    "/log",
    "foxglove.Log",
    "the console's log lines, the mission log's events and command state changes",
)

#: Every channel, in the order docs/foxglove.md lists them.
CHANNELS: Final = (
    POSE,
    TRACK,
    FIX,
    STATUS,
    ACTIVE,
    PREVIEW,
    PREDICTION,
    BELIEF_SCENE,
    BELIEF_FIX,
    BELIEF,
    STATION,
    STATION_FIX,
    COMMANDS,
    LINK,
    LOG,
)

#: The JSON channels' models.
MODELS: Final[Mapping[str, type[BaseModel]]] = {
    STATUS.topic: VehicleStatus,
    BELIEF.topic: Belief,
    COMMANDS.topic: CommandRecord,
    LINK.topic: LinkHealth,
}

#: With a fleet, each vehicle's own channels: these topics under ``/<name>``.
PER_VEHICLE: Final = (POSE, TRACK, FIX, STATUS, BELIEF_FIX, BELIEF, LINK)
#: With a fleet: each vehicle's frame, named by the vehicle, in the scene frame.
FRAMES = Spec(
    "/tf",
    "foxglove.FrameTransforms",
    "with a fleet: each vehicle's frame, its name, in map at its last pose (3D panel)",
)
#: A typed channel's class by its schema.
_TYPED: Final[Mapping[str, Any]] = {
    "foxglove.PoseInFrame": PoseInFrameChannel,
    "foxglove.PosesInFrame": PosesInFrameChannel,
    "foxglove.LocationFix": LocationFixChannel,
    "foxglove.SceneUpdate": SceneUpdateChannel,
    "foxglove.Log": LogChannel,
    "foxglove.FrameTransforms": FrameTransformsChannel,
}
_JSON_MODELS: Final = {SCHEMA_PREFIX + model.__name__: model for model in MODELS.values()}


def vehicle_topic(topic: str, vehicle: str | None) -> str:
    """``topic`` of vehicle ``vehicle``: a fleet's under ``/<name>``; None (the single
    vehicle): ``topic`` as it is."""
    return topic if vehicle is None else f"/{vehicle}{topic}"


def channel_specs(vehicles: Sequence[str] = ()) -> tuple[Spec, ...]:
    """The view's channels: :data:`CHANNELS` without a fleet; with one (``vehicles``: its
    names, in order) the shared ones, then each vehicle's own (:data:`PER_VEHICLE` under
    ``/<name>``), then :data:`FRAMES`."""
    if not vehicles:
        return CHANNELS
    shared = tuple(c for c in CHANNELS if c not in PER_VEHICLE)
    own = tuple(
        Spec(vehicle_topic(c.topic, name), c.schema, f"{name}: {c.what}")
        for name in vehicles
        for c in PER_VEHICLE
    )
    return (*shared, *own, FRAMES)


def json_schema(model: type[BaseModel], title: str) -> dict[str, Any]:
    """``model``'s JSON Schema as its JSON is sent (by alias), its ``$ref``s inlined, titled
    ``title`` (the schema name Foxglove shows).

    Raises:
        ValueError: the model refers to itself (a schema that cannot be inlined).
    """
    schema = model.model_json_schema(by_alias=True, mode="serialization")
    defs: dict[str, Any] = schema.pop("$defs", {})

    def inline(node: Any, seen: tuple[str, ...]) -> Any:
        if isinstance(node, list):
            return [inline(item, seen) for item in node]
        if not isinstance(node, dict):
            return node
        ref = node.get("$ref")
        if isinstance(ref, str) and ref.startswith("#/$defs/"):
            name = ref.removeprefix("#/$defs/")
            if name in seen:
                raise ValueError(f"{model.__name__}: {name} refers to itself")
            rest = {k: inline(v, seen) for k, v in node.items() if k != "$ref"}
            return {**inline(defs[name], (*seen, name)), **rest}
        return {key: inline(value, seen) for key, value in node.items()}

    out: dict[str, Any] = inline(schema, ())
    out["title"] = title
    return out


class Channels:
    """The live view's channels, in ``context`` (one per console: two consoles in one process
    do not share channels): :func:`channel_specs` of the fleet's ``vehicles`` (none: the
    single vehicle's)."""

    def __init__(self, context: foxglove.Context, vehicles: Sequence[str] = ()) -> None:
        self.specs = channel_specs(vehicles)
        #: The typed channels by topic.
        self.typed: dict[str, Any] = {}
        #: The JSON channels by topic (their messages: the model's JSON as ``/ws`` sends it).
        self.json: dict[str, foxglove.Channel] = {}
        for spec in self.specs:
            model = _JSON_MODELS.get(spec.schema)
            if model is None:
                self.typed[spec.topic] = _TYPED[spec.schema](spec.topic, context=context)
            else:
                schema = json_schema(model, spec.schema)
                self.json[spec.topic] = foxglove.Channel(spec.topic, schema=schema, context=context)
        self.log: LogChannel = self.typed[LOG.topic]

    def close(self) -> None:
        """Close every channel (their clients are told they are gone)."""
        for channel in (*self.typed.values(), *self.json.values()):
            channel.close()


__all__ = [
    "CHANNELS",
    "FRAMES",
    "MODELS",
    "PER_VEHICLE",
    "SCHEMA_PREFIX",
    "Channels",
    "Spec",
    "channel_specs",
    "json_schema",
    "vehicle_topic",
]
