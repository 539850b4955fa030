"""The vehicle contract: what the console and a NemeSys vehicle exchange, as the single source.

Every topic with its ROS 2 type, QoS, rate and ``frame_id``; the time base; the JSON Schemas
(draft 2020-12) of the acknowledgement and status messages (:mod:`vehicle_contract.payloads`);
the reason codes and modes (:mod:`vehicle_contract.codes`); a version and the rule for
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
from dataclasses import dataclass
from typing import Any, Final

from codec.compat import StrEnum
from vehicle_contract.payloads import SCHEMAS

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
