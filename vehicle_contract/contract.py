"""The vehicle contract: what the console and a NemeSys vehicle exchange, as the single source.

Every topic with its ROS 2 type, QoS, rate and ``frame_id``; the time base; the JSON Schemas
(draft 2020-12) of the acknowledgement and status messages; a version and the rule for
changing it. ``nemesys contract`` prints it, ``docs/vehicle.md`` is generated from it, the
simulator's bridge, the console's link, ``nemesys vehicle-check`` and the reference ROS 2 node
(``ros2/nemesys_vehicle``) all read it.

Versioning (semantic): a change a vehicle or console built for the old contract still works
with (a new optional field, a new optional topic) bumps the minor number; anything else (a
topic renamed or retyped, a required field added, removed or changed in meaning, a QoS a
peer of the old contract cannot match) bumps the major number. The patch number is for
wording. A vehicle and a console built for the same major number work together.
"""

from __future__ import annotations

import copy
import functools
from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING, Any, Final

from codec import RejectReason, describe_dictionary
from onboard.agent import INVALID_PLAN, LIMIT_VIOLATION
from onboard.guidance import Mode
from vehicle_contract.schema import command_schema, problems, vehicle_state_schema

if TYPE_CHECKING:
    from jsonschema import Draft202012Validator

#: The contract's version (see the module doc for the rule).
CONTRACT_VERSION: Final = "1.0.0"

#: Topic names.
FRAME_TOPIC: Final = "/nemesys/frame"
POSE_TOPIC: Final = "/nemesys/pose"
MISSION_TOPIC: Final = "/nemesys/mission"
STATUS_TOPIC: Final = "/nemesys/status"

#: ``header.frame_id`` of every pose: NED world frame (x north, y east, z down), metres.
POSE_FRAME_ID: Final = "map_ned"

#: The time base of every stamp and ``t_s``: ROS time (the vehicle's clock, epoch seconds on a
#: real robot, ``/clock`` in simulation). The console never compares it with its own clock:
#: ages are taken from arrival times.
TIME_BASE: Final = {
    "clock": "ROS time",
    "stamps": "builtin_interfaces/msg/Time {sec, nanosec} in header.stamp",
    "t_s": "the same clock, in seconds, in acknowledgement and status JSON",
    "ages": "the console measures ages from arrival times on its own clock, never from stamps",
}


class Direction(StrEnum):
    TO_VEHICLE = "console -> vehicle"
    TO_CONSOLE = "vehicle -> console"


class Reliability(StrEnum):
    RELIABLE = "reliable"
    BEST_EFFORT = "best_effort"


class Durability(StrEnum):
    VOLATILE = "volatile"
    TRANSIENT_LOCAL = "transient_local"


@dataclass(frozen=True)
class QoS:
    """A ROS 2 QoS profile (history KEEP_LAST of ``depth``)."""

    reliability: Reliability
    durability: Durability
    depth: int


@dataclass(frozen=True)
class Topic:
    """One topic of the contract. ``rate_hz`` None: one message per event (see ``rate``)."""

    name: str
    #: ROS 2 spelling (``pkg/msg/Name``); ``pkg/Name`` denotes the same type.
    type: str
    direction: Direction
    qos: QoS
    rate: str
    rate_hz: float | None
    frame_id: str | None
    #: A vehicle without it fails ``nemesys vehicle-check`` (the console degrades without it).
    required: bool
    description: str

    def as_json(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "type": self.type,
            "direction": str(self.direction),
            "qos": {
                "reliability": str(self.qos.reliability),
                "durability": str(self.qos.durability),
                "depth": self.qos.depth,
            },
            "rate": self.rate,
            "rate_hz": self.rate_hz,
            "frame_id": self.frame_id,
            "required": self.required,
            "description": self.description,
        }


TOPICS: Final = (
    Topic(
        FRAME_TOPIC,
        "std_msgs/msg/UInt8MultiArray",
        Direction.TO_VEHICLE,
        # transient local: a subscriber that matches a fresh publisher late still gets the frame
        QoS(Reliability.RELIABLE, Durability.TRANSIENT_LOCAL, 10),
        "one per frame sent",
        None,
        None,
        True,
        "one 100-bit frame packed in 13 bytes (docs/protocol.md), as the ME link carries it",
    ),
    Topic(
        POSE_TOPIC,
        "geometry_msgs/msg/PoseStamped",
        Direction.TO_CONSOLE,
        QoS(Reliability.BEST_EFFORT, Durability.VOLATILE, 1),
        ">= 10 Hz (the simulator: 20 Hz)",
        10.0,
        POSE_FRAME_ID,
        True,
        "the vehicle's pose, NED (x north, y east, z down, m), heading as a yaw quaternion",
    ),
    Topic(
        MISSION_TOPIC,
        "std_msgs/msg/String",
        Direction.TO_CONSOLE,
        QoS(Reliability.RELIABLE, Durability.VOLATILE, 50),
        "one per frame the onboard agent processed",
        None,
        None,
        True,
        "the onboard agent's acknowledgement, a JSON object (schema: ack)",
    ),
    Topic(
        STATUS_TOPIC,
        "std_msgs/msg/String",
        Direction.TO_CONSOLE,
        QoS(Reliability.RELIABLE, Durability.VOLATILE, 1),
        ">= 1 Hz (the simulator: 2 Hz)",
        1.0,
        None,
        True,
        "the vehicle's status, a JSON object (schema: status)",
    ),
)

#: Topic name -> its ROS 2 type.
TOPIC_TYPES: Final = {t.name: t.type for t in TOPICS}


def topic(name: str) -> Topic:
    """The contract's topic of that name.

    Raises:
        KeyError: not a contract topic.
    """
    for t in TOPICS:
        if t.name == name:
            return t
    raise KeyError(name)


# --- the JSON payloads ----------------------------------------------------------------------

#: The JSON Schema dialect of both schemas.
SCHEMA_DIALECT: Final = "https://json-schema.org/draft/2020-12/schema"

_NUMBER_OR_NULL: Final = {"type": ["number", "null"]}
_COUNT_OR_NULL: Final = {"type": ["integer", "null"], "minimum": 0}

#: The words of ``mode`` in the status (what guidance is doing).
MODES: Final = tuple(m.value for m in Mode)

#: Every ``reason`` a rejection may give: the codec's (the frame did not decode) and the
#: agent's (it decoded but is no flyable plan within the vehicle's limits).
REJECT_REASONS: Final = (*(r.value for r in RejectReason), INVALID_PLAN, LIMIT_VIOLATION)


def _command_or_null(description: str) -> dict[str, Any]:
    return {"anyOf": [{"$ref": "#/$defs/command"}, {"type": "null"}], "description": description}


#: The acknowledgement: one JSON object per frame the onboard agent processed, as the ``data``
#: of a ``std_msgs/String`` on ``/nemesys/mission``.
ACK_SCHEMA: Final[dict[str, Any]] = {
    "$schema": SCHEMA_DIALECT,
    "$id": "urn:nemesys:vehicle-contract:1:ack",
    "title": "NemeSys acknowledgement",
    "description": "the onboard agent's verdict on one received frame",
    "type": "object",
    "required": [
        "t_s",
        "outcome",
        "frame_hex",
        "reason",
        "detail",
        "command",
        "duplicate",
        "active",
        "from",
    ],
    "properties": {
        "seq": {"type": "integer", "minimum": 1, "description": "frames processed, this one"},
        "t_s": {**_NUMBER_OR_NULL, "description": "ROS time of the verdict (s)"},
        "outcome": {"enum": ["accepted", "rejected"], "description": "the verdict"},
        "frame_hex": {
            "type": ["string", "null"],
            "pattern": "^([0-9a-fA-F]{25}|[0-9a-fA-F]{26})$",
            "description": "the 100 bits received, 25 hex digits (or the 13 packed bytes); "
            "null when the message was not a frame",
        },
        "corrected_bits": {**_COUNT_OR_NULL, "description": "bits the BCH decoder corrected"},
        "sync_errors": {**_COUNT_OR_NULL, "description": "preamble and delimiter bits wrong"},
        "reason": {
            "enum": [*REJECT_REASONS, None],
            "description": "why it was rejected; null when accepted",
        },
        "detail": {"type": "string", "description": "the verdict in words"},
        "field": {"type": ["string", "null"], "description": "the parameter at fault"},
        "command": _command_or_null("the command decoded from the frame; null if none"),
        "duplicate": {
            "type": "boolean",
            "description": "accepted and already the active command: not replanned",
        },
        "decode_latency_ms": {
            **_NUMBER_OR_NULL,
            "minimum": 0,
            "description": "receipt to decoded and checked (ms)",
        },
        "replan_latency_ms": {
            **_NUMBER_OR_NULL,
            "minimum": 0,
            "description": "decoded to the new plan's first setpoint (ms)",
        },
        "waypoints": {**_COUNT_OR_NULL, "description": "waypoints of the new plan"},
        "active": _command_or_null("the command the vehicle runs after this frame; null: none"),
        "from": {
            "anyOf": [{"$ref": "#/$defs/vehicle_state"}, {"type": "null"}],
            "description": "the state the new plan was made from; null unless it replanned",
        },
        "channel_flipped_bits": {
            "type": "integer",
            "minimum": 0,
            "description": "the simulator only: bits its emulated channel flipped",
        },
    },
    "allOf": [
        {
            "if": {"properties": {"outcome": {"const": "accepted"}}, "required": ["outcome"]},
            "then": {
                "properties": {"reason": {"const": None}, "command": {"$ref": "#/$defs/command"}}
            },
        },
        {
            "if": {"properties": {"outcome": {"const": "rejected"}}, "required": ["outcome"]},
            "then": {
                "properties": {
                    "reason": {"enum": list(REJECT_REASONS)},
                    "duplicate": {"const": False},
                }
            },
        },
    ],
    "$defs": {"command": command_schema(), "vehicle_state": vehicle_state_schema()},
}

#: The status: one JSON object at >= 1 Hz, as the ``data`` of a ``std_msgs/String`` on
#: ``/nemesys/status``. A number the vehicle does not know is ``null``, never left out.
STATUS_SCHEMA: Final[dict[str, Any]] = {
    "$schema": SCHEMA_DIALECT,
    "$id": "urn:nemesys:vehicle-contract:1:status",
    "title": "NemeSys status",
    "description": "what the vehicle is doing; unknown numbers are null",
    "type": "object",
    "required": ["t_s", "depth_m", "heading_deg", "speed_mps", "battery_pct", "mode", "pattern"],
    "properties": {
        "t_s": {**_NUMBER_OR_NULL, "description": "ROS time (s)"},
        "x_m": {**_NUMBER_OR_NULL, "description": "north (m); the pose is the position's source"},
        "y_m": {**_NUMBER_OR_NULL, "description": "east (m); the pose is the position's source"},
        "depth_m": {**_NUMBER_OR_NULL, "description": "the depth sensor's reading (m, down)"},
        "heading_deg": {**_NUMBER_OR_NULL, "description": "degrees clockwise from north"},
        "speed_mps": {**_NUMBER_OR_NULL, "description": "speed through the water (m/s)"},
        "battery_pct": {
            **_NUMBER_OR_NULL,
            "minimum": 0,
            "maximum": 100,
            "description": "state of charge (%)",
        },
        "mode": {"enum": list(MODES), "description": "what guidance is doing"},
        "pattern": {
            "enum": [*(p["name"] for p in describe_dictionary()), None],
            "description": "the active command's pattern; null: none",
        },
        "active": _command_or_null(
            "the active command, as in an acknowledgement's 'active'; null: none. Optional "
            "(1.0), but without it vehicle-check cannot probe the acknowledgement path"
        ),
        "link": {
            "type": "object",
            "description": "the simulator only: its emulated ME channel",
            "properties": {
                "frames_in": {"type": "integer", "minimum": 0},
                "frames_lost": {"type": "integer", "minimum": 0},
                "accepted": {"type": "integer", "minimum": 0},
                "rejected": {"type": "integer", "minimum": 0},
                "last_frame_t_s": _NUMBER_OR_NULL,
                "distance_m": _NUMBER_OR_NULL,
                "range_m": _NUMBER_OR_NULL,
                "in_range": {"type": "boolean"},
                "ber": _NUMBER_OR_NULL,
            },
        },
    },
    "$defs": {"command": command_schema()},
}

#: The schemas by name.
SCHEMAS: Final = {"ack": ACK_SCHEMA, "status": STATUS_SCHEMA}


def required_fields(schema: dict[str, Any]) -> list[str]:
    """The top-level fields a message must hold."""
    return list(schema["required"])


@functools.cache
def _validator(name: str) -> Draft202012Validator:
    from jsonschema import Draft202012Validator  # on use: `nemesys contract` needs none of it

    schema = SCHEMAS[name]
    Draft202012Validator.check_schema(schema)
    return Draft202012Validator(schema)


def validate_ack(obj: object) -> list[str]:
    """Problems of an acknowledgement under :data:`ACK_SCHEMA`, one line each naming the field
    (empty: valid)."""
    return problems(_validator("ack"), obj)


def validate_status(obj: object) -> list[str]:
    """Problems of a status under :data:`STATUS_SCHEMA`, one line each naming the field
    (empty: valid)."""
    return problems(_validator("status"), obj)


# --- the contract as a whole ----------------------------------------------------------------

#: How the version changes (the module doc says the same).
VERSION_RULE: Final = (
    "semantic versioning. A change a vehicle or console built for the old contract still "
    "works with (a new optional field, a new optional topic) bumps the minor number; anything "
    "else (a topic renamed or retyped, a required field added, removed or changed in meaning, "
    "a QoS a peer of the old contract cannot match) bumps the major number; the patch number "
    "is for wording. A vehicle and a console built for the same major number work together."
)

#: The ROS 2 node that subscribes the frame topic on a NemeSys vehicle (the reference node in
#: ros2/nemesys_vehicle, and the simulator's graph, are named so).
VEHICLE_NODE: Final = "/nemesys_vehicle"

#: What a NemeSys vehicle must do, beyond publishing and subscribing the topics.
OBLIGATIONS: Final = (
    f"Subscribe to {FRAME_TOPIC} (RELIABLE, TRANSIENT_LOCAL) and run every message through "
    "the onboard agent: 13 bytes, 100 frame bits first bit most significant (docs/protocol.md); "
    "frame sync, BCH and CRC-4 decoding, the dictionary's checks, then a plan within the "
    "vehicle's limits.",
    f"Acknowledge every message on {FRAME_TOPIC} exactly once on {MISSION_TOPIC}: one JSON "
    "object (schema ack) as the data of a std_msgs/msg/String, accepted or rejected with the "
    "reason. A rejected frame changes nothing.",
    "A frame carrying the command the vehicle already runs is acknowledged accepted with "
    "duplicate true and is not replanned: the console repeats commands (Surface until "
    "acknowledged), and nemesys vehicle-check re-sends the active command to probe the "
    "acknowledgement path.",
    "The surface command (pattern 15) is executed whatever the limits, mode or battery; only a "
    "new command after it moves the vehicle again.",
    f"Publish the pose on {POSE_TOPIC} at 10 Hz or more: NED metres (x north, y east, z down) "
    f"in frame {POSE_FRAME_ID!r}, the heading as a yaw quaternion, header.stamp in ROS time.",
    f"Publish the status on {STATUS_TOPIC} at 1 Hz or more (schema status), with 'active' (the "
    "active command, or null): without it the acknowledgement path cannot be probed.",
    "A number the vehicle does not know is null (NaN and infinities become null through "
    "rosbridge); a required field is never left out.",
    "A reference ROS 2 node that does all of this, wrapping the simulator's own onboard agent, "
    "is ros2/nemesys_vehicle (its README says how to build and launch it).",
    "Run rosbridge_server with rosapi: the console lists the vehicle's topics through "
    "/rosapi/topics, and a one-shot sender asks /rosapi/subscribers whether the frame topic "
    "has its subscriber before publishing.",
)


def contract_json() -> dict[str, Any]:
    """The whole contract as JSON (what ``nemesys contract`` prints): a fresh copy."""
    return copy.deepcopy(
        {
            "version": CONTRACT_VERSION,
            "version_rule": VERSION_RULE,
            "topics": [t.as_json() for t in TOPICS],
            "time_base": TIME_BASE,
            "schemas": SCHEMAS,
            "obligations": list(OBLIGATIONS),
        }
    )
