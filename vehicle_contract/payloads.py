"""The vehicle contract's JSON payloads (:mod:`vehicle_contract.contract`): the JSON Schemas
(draft 2020-12) of the acknowledgement, the status and the datum, each the ``data`` of a
``std_msgs/String``, and their validators (one line per problem, naming the field).

The reason codes and the modes they list are :mod:`vehicle_contract.codes`; the command and
vehicle-state schemas they embed, and the wording of problems, :mod:`vehicle_contract.schema`.
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING, Any, Final

from codec import describe_dictionary
from vehicle_contract.codes import (
    ACK_DEADLINE_S,
    BROADCAST_ADDRESS,
    MAX_ADDRESS,
    MODES,
    RECENT_ACKS_MAX,
    RECENT_ACKS_S,
    REJECT_REASONS,
)
from vehicle_contract.schema import command_schema, problems, vehicle_state_schema

if TYPE_CHECKING:
    from jsonschema import Draft202012Validator

#: The JSON Schema dialect of both schemas.
SCHEMA_DIALECT: Final = "https://json-schema.org/draft/2020-12/schema"

_NUMBER_OR_NULL: Final = {"type": ["number", "null"]}
_COUNT_OR_NULL: Final = {"type": ["integer", "null"], "minimum": 0}


def _command_or_null(description: str) -> dict[str, Any]:
    return {"anyOf": [{"$ref": "#/$defs/command"}, {"type": "null"}], "description": description}


#: The acknowledgement: one JSON object per frame the onboard agent processed, as the ``data``
#: of a ``std_msgs/String`` on ``/nemesys/mission``.
ACK_SCHEMA: Final[dict[str, Any]] = {
    "$schema": SCHEMA_DIALECT,
    "$id": "urn:nemesys:vehicle-contract:2:ack",
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
            "pattern": "^([0-9a-fA-F]{25}|[0-9a-fA-F]{26}|[0-9a-fA-F]{27}|[0-9a-fA-F]{28})$",
            "description": "the 100 bits received, 25 hex digits (or the 13 packed bytes); a "
            "fleet's addressed frame: 108 bits, 27 hex digits (or its 14 packed bytes); null "
            "when the message was not a frame",
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
        "late": {
            "type": "boolean",
            "description": f"made more than the contract's deadline ({ACK_DEADLINE_S:g} s) "
            "after the frame was received; absent: not late",
        },
        "channel_flipped_bits": {
            "type": "integer",
            "minimum": 0,
            "description": "the simulator only: bits its emulated channel flipped",
        },
        "address": {
            "type": ["integer", "null"],
            "minimum": BROADCAST_ADDRESS,
            "maximum": MAX_ADDRESS,
            "description": "a vehicle with an address only (2.1): the address the frame "
            f"carried ({BROADCAST_ADDRESS}: all vehicles); null: an unaddressed frame, or none "
            "decoded; with reason other_vehicle, the vehicle it was for",
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
    "$id": "urn:nemesys:vehicle-contract:2:status",
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
        "mode": {
            "enum": list(MODES),
            "description": "what guidance is doing: running while it flies the command (a "
            "finite path's last depth change included); holding once a finite command is done, "
            "at its end and its depth (a hover: its time up and at its depth); nav_fault: "
            "navigation went stale",
        },
        "pattern": {
            "enum": [*(p["name"] for p in describe_dictionary()), None],
            "description": "the active command's pattern; null: none",
        },
        "active": _command_or_null(
            "the active command, as in an acknowledgement's 'active'; null: none. Optional "
            "(1.0); without it vehicle-check cannot check the duplicate rule (the "
            "acknowledgement path is probed with a malformed frame all the same)"
        ),
        "nav_valid": {
            "type": "boolean",
            "description": "the navigation is fresh (absent: a 1.x vehicle, taken as true); "
            "false: the pose is not sent and the position fields are null",
        },
        "nav_age_s": {
            **_NUMBER_OR_NULL,
            "minimum": 0,
            "description": "age of the latest navigation solution (s); null: none yet",
        },
        "frame_input": {
            "enum": ["topic", "receiver"],
            "description": "where the vehicle takes frames from: the frame topic, or only its "
            "own ME receiver (no frame subscriber); absent: the topic",
        },
        "address": {
            "type": ["integer", "null"],
            "minimum": 1,
            "maximum": MAX_ADDRESS,
            "description": "the vehicle's own address on a link it shares with a fleet (2.1; "
            "docs/protocol.md, Addressing); absent or null: none, it takes single-vehicle "
            "frames only",
        },
        "recent_acks": {
            "type": "array",
            "maxItems": RECENT_ACKS_MAX,
            "items": {"$ref": "#/$defs/ack"},
            "description": f"the acknowledgements of the last {RECENT_ACKS_S:g} s, oldest "
            "first, as published: what a reconnecting console missed",
        },
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
    "$defs": {
        "command": command_schema(),
        "vehicle_state": vehicle_state_schema(),
        # the acknowledgement as an item of recent_acks (its own $defs are the ones above)
        "ack": {k: v for k, v in ACK_SCHEMA.items() if k not in ("$schema", "$id", "$defs")},
    },
}

#: The datum: one JSON object, the ``data`` of a ``std_msgs/String`` on ``/nemesys/datum``.
DATUM_SCHEMA: Final[dict[str, Any]] = {
    "$schema": SCHEMA_DIALECT,
    "$id": "urn:nemesys:vehicle-contract:2:datum",
    "title": "NemeSys datum",
    "description": "where map_ned's origin is on the Earth (WGS84, at the water surface)",
    "type": "object",
    "required": ["t_s", "lat_deg", "lon_deg", "source"],
    "properties": {
        "t_s": {**_NUMBER_OR_NULL, "description": "ROS time the datum was set (s)"},
        "lat_deg": {
            "type": "number",
            "minimum": -90,
            "maximum": 90,
            "description": "latitude of the origin (deg, north positive)",
        },
        "lon_deg": {
            "type": "number",
            "minimum": -180,
            "maximum": 180,
            "description": "longitude of the origin (deg, east positive)",
        },
        "source": {
            "enum": ["parameters", "navsatfix"],
            "description": "set on the vehicle, or its first GPS fix at the surface",
        },
        "odometry_origin": {
            "anyOf": [
                {
                    "type": "object",
                    "required": ["north_m", "east_m"],
                    "properties": {"north_m": {"type": "number"}, "east_m": {"type": "number"}},
                },
                {"type": "null"},
            ],
            "description": "where the vehicle's own navigation frame has its origin, in "
            "map_ned (m); null: not known yet",
        },
    },
}

#: The schemas by name.
SCHEMAS: Final = {"ack": ACK_SCHEMA, "status": STATUS_SCHEMA, "datum": DATUM_SCHEMA}


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


def validate_datum(obj: object) -> list[str]:
    """Problems of a datum under :data:`DATUM_SCHEMA`, one line each naming the field
    (empty: valid)."""
    return problems(_validator("datum"), obj)


def validate_status(obj: object) -> list[str]:
    """Problems of a status under :data:`STATUS_SCHEMA`, one line each naming the field
    (empty: valid)."""
    return problems(_validator("status"), obj)
