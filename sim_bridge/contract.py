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
wording. The console accepts any vehicle with the same major number.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import Any, Final

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
