"""The vehicle contract: what the console and a NemeSys vehicle exchange, as the single source.

Every topic with its ROS 2 type, QoS, rate and ``frame_id`` (its name under a vehicle
namespace: :mod:`vehicle_contract.names`, the one place topic names are built); the time base
and the acknowledgement deadline; the conventions (heading, depth, body frame, datum); the JSON
Schemas (draft 2020-12) of the acknowledgement, status and datum messages
(:mod:`vehicle_contract.payloads`); the reason codes and modes (:mod:`vehicle_contract.codes`);
a version and the rule for changing it. ``nemesys contract`` prints it,
``docs/vehicle.md`` is generated from it, the simulator's bridge, the console's link,
``nemesys vehicle-check`` and the reference ROS 2 node (``ros2/nemesys_vehicle``) all read it.

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
from vehicle_contract import codes
from vehicle_contract.payloads import SCHEMAS

#: The contract's version (see the module doc for the rule). 2.0: a new reject reason
#: (``no_navigation``) and mode (``nav_fault``) a 1.x peer does not know; the datum topic,
#: the acknowledgement deadline and ``late``, ``nav_valid``, ``recent_acks``, vehicle
#: namespaces. 2.1: a fleet on one link: a vehicle's address (optional: without one, a vehicle
#: and a console work as in 2.0, with the same frames), the addressed frame on the frame topic,
#: the ``other_vehicle`` reason and the ``address`` fields, all only where an address is set.
CONTRACT_VERSION: Final = "2.1.0"

#: A vehicle acknowledges a frame within this long of receiving it (s); one made later says
#: ``late: true``. (The numbers the onboard path needs live in :mod:`vehicle_contract.codes`.)
ACK_DEADLINE_S: Final = codes.ACK_DEADLINE_S
#: The status carries the acknowledgements of this long (s), at most this many.
RECENT_ACKS_S: Final = codes.RECENT_ACKS_S
RECENT_ACKS_MAX: Final = codes.RECENT_ACKS_MAX

#: Topic names, without a vehicle namespace (:func:`vehicle_contract.names.topic_name` puts
#: them under one).
FRAME_TOPIC: Final = "/nemesys/frame"
POSE_TOPIC: Final = "/nemesys/pose"
MISSION_TOPIC: Final = "/nemesys/mission"
STATUS_TOPIC: Final = "/nemesys/status"
DATUM_TOPIC: Final = "/nemesys/datum"

#: ``header.frame_id`` of every pose: NED world frame (x north, y east, z down), metres, about
#: the datum (:data:`DATUM_TOPIC`).
POSE_FRAME_ID: Final = "map_ned"

#: The longest time between two datum messages (s): the datum is latched (transient local)
#: and also sent again this often, for a subscriber that matched too late for the latched copy.
DATUM_REPEAT_S: Final = 5.0

#: The time base of every stamp and ``t_s``: ROS time (the vehicle's clock, epoch seconds on a
#: real robot, ``/clock`` in simulation). The console never compares it with its own clock:
#: ages are taken from arrival times.
TIME_BASE: Final = {
    "clock": "ROS time",
    "stamps": "builtin_interfaces/msg/Time {sec, nanosec} in header.stamp",
    "t_s": "the same clock, in seconds, in acknowledgement, status and datum JSON",
    "pose stamp": "when the navigation solution the pose carries was made (or reached the "
    "vehicle's node), never the time it was sent: a pose is not re-stamped to look fresh, "
    "and none is sent from stale navigation",
    "ack t_s": "when the verdict was made; the status's t_s: when the status was made",
    "ack deadline": f"an acknowledgement is published within {ACK_DEADLINE_S:g} s of the "
    "frame's reception; one made later says late: true",
    "ages": "the console measures ages from arrival times on its own clock, never from stamps",
}

#: What the numbers mean: positions, heading, depth, the body, the datum.
CONVENTIONS: Final = {
    "position": f"{POSE_FRAME_ID}: metres north (x), east (y) and down (z) of the datum, a "
    "local tangent plane at the water surface",
    "datum": f"the latitude and longitude (WGS84) of {POSE_FRAME_ID}'s origin, published on "
    f"{DATUM_TOPIC}; the console compares it with its own and names a mismatch",
    "heading": "degrees clockwise from true (geographic) north, in [0, 360); a navigation "
    "referenced to magnetic north is corrected by the local declination before publishing",
    "depth": "metres below the water surface, positive down (the pose's z, the status's "
    "depth_m): 0 at the surface, not a height above the sea floor",
    "body frame": f"FRD (x forward, y starboard, z down); the pose's orientation is the body's "
    f"attitude in {POSE_FRAME_ID} as a quaternion whose yaw is the heading (a vehicle may send "
    "yaw only: roll and pitch 0)",
    "namespace": "several vehicles share one ROS graph by namespace: every topic under "
    "/<namespace>/nemesys/... (the console: its vehicle_namespace setting); no namespace: the "
    "names as listed",
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
        "one 100-bit frame packed in 13 bytes (docs/protocol.md), as the ME link carries it; "
        "to a vehicle with an address, a 108-bit addressed frame in 14 bytes",
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
    Topic(
        DATUM_TOPIC,
        "std_msgs/msg/String",
        Direction.TO_CONSOLE,
        # transient local: a console that subscribes later still gets it
        QoS(Reliability.RELIABLE, Durability.TRANSIENT_LOCAL, 1),
        f"when set, then at least every {DATUM_REPEAT_S:g} s",
        1.0 / DATUM_REPEAT_S,
        None,
        False,
        f"the latitude and longitude of {POSE_FRAME_ID}'s origin, a JSON object (schema: datum); "
        "a vehicle without it has its positions taken as about the console's datum",
    ),
)

#: Topic name -> its ROS 2 type.
TOPIC_TYPES: Final = {t.name: t.type for t in TOPICS}


def topic(name: str) -> Topic:
    """The contract's topic of that name (without a namespace:
    :func:`vehicle_contract.names.contract_topic_of`).

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
#: ros2/nemesys_vehicle, and the simulator's graph, are named so; under a namespace it is
#: /<namespace>/nemesys_vehicle). The console and vehicle-check never look for this name: they
#: find the vehicle's nodes by the topics they publish and subscribe.
VEHICLE_NODE: Final = "/nemesys_vehicle"

#: What a NemeSys vehicle must do, beyond publishing and subscribing the topics.
OBLIGATIONS: Final = (
    f"Subscribe to {FRAME_TOPIC} (RELIABLE, TRANSIENT_LOCAL) and run every message through "
    "the onboard agent: 13 bytes, 100 frame bits first bit most significant (docs/protocol.md); "
    "frame sync, BCH and CRC-4 decoding, the dictionary's checks, then a plan within the "
    "vehicle's limits. (A vehicle that takes frames only from its own ME receiver: below.)",
    f"Acknowledge every frame exactly once on {MISSION_TOPIC}, within {ACK_DEADLINE_S:g} s of "
    "receiving it: one JSON object (schema ack) as the data of a std_msgs/msg/String, accepted "
    "or rejected with the reason. A rejected frame changes nothing. No frame is dropped or "
    "held without an acknowledgement: one the vehicle cannot act on now is rejected with the "
    "reason (no_navigation when it has no navigation to plan from), never kept for later. An "
    "acknowledgement made after the deadline says late: true (the console may have given up "
    "on it). nemesys vehicle-check probes this path before a dive with a deliberately "
    "malformed frame (right preamble and delimiter, its codeword beyond correction), on a "
    "fresh vehicle too: it must come back rejected, reason uncorrectable, within the deadline "
    "(round trip), the active command unchanged.",
    "A frame carrying the command the vehicle already runs is acknowledged accepted with "
    "duplicate true and is not replanned: the console repeats commands (Surface until "
    "acknowledged), and while a command runs nemesys vehicle-check re-sends it once to "
    "check this rule.",
    "The surface command (pattern 15) is executed whatever the limits, mode or battery, and "
    "with stale navigation (from the last known position); only a new command after it moves "
    "the vehicle again. Before the vehicle has had any navigation it is rejected "
    "(no_navigation) like every other command: there is nothing to plan it from.",
    "Navigation health: when the navigation solution is older than the vehicle's limit (the "
    "reference node's nav_timeout_s), stop publishing the pose, say nav_valid false (with "
    "nav_age_s) and mode nav_fault in the status, with null position, depth, heading and "
    "speed, and hold or surface from the last known position (the vehicle's setting, in its "
    "documentation). Until a new command is accepted with navigation valid again the mode "
    "stays nav_fault; a command needing a plan is rejected with no_navigation meanwhile.",
    f"Publish the pose on {POSE_TOPIC} at 10 Hz or more while navigation is valid: NED metres "
    f"(x north, y east, z down) in frame {POSE_FRAME_ID!r} about the datum, the heading from "
    "true north as a yaw quaternion, header.stamp the navigation solution's time (ROS time).",
    f"Publish the status on {STATUS_TOPIC} at 1 Hz or more (schema status), with 'active' (the "
    "active command, or null; without it vehicle-check cannot check the duplicate rule), "
    f"nav_valid, and recent_acks: the acknowledgements of the last {RECENT_ACKS_S:g} s (at "
    f"most {RECENT_ACKS_MAX}, oldest first) exactly as published, so a console that "
    "reconnects takes those it missed from the next status (it knows one by t_s and seq).",
    f"Publish the datum on {DATUM_TOPIC} (schema datum; RELIABLE, TRANSIENT_LOCAL, depth 1) "
    f"once it is known and again at least every {DATUM_REPEAT_S:g} s: the latitude and "
    f"longitude of {POSE_FRAME_ID}'s origin (set on the vehicle, or its first GPS fix at the "
    "surface). Every position is about it; the console names a datum that differs from its "
    "own.",
    "A number the vehicle does not know is null (NaN and infinities become null through "
    "rosbridge); a required field is never left out.",
    "A fleet on one ME link (docs/protocol.md, Addressing): each vehicle has an address, "
    f"1 to {codes.MAX_ADDRESS} (the reference node's vehicle_address parameter; "
    f"{codes.BROADCAST_ADDRESS} addresses all vehicles), and takes the 108-bit addressed frames "
    f"(14 bytes on {FRAME_TOPIC}) addressed to it or to all, and of the 100-bit frames only "
    "surface (Surface from a single-vehicle console reaches every vehicle). Any other frame "
    "that decodes is acknowledged rejected with reason other_vehicle and changes nothing: "
    "one addressed to another vehicle, or a 100-bit frame other than surface (it names no "
    "vehicle). Its acknowledgements then carry the address the frame named (address; null "
    "when none) and its status its own address (address). A vehicle without an address takes "
    "the 100-bit frames only, exactly as before, and never says address.",
    "Several vehicles in one ROS graph: each puts every contract topic under its namespace, "
    "/<namespace>/nemesys/... (the reference node's vehicle_namespace parameter, the console's "
    "vehicle_namespace setting); without one the names are as listed.",
    "A vehicle that takes frames only from its own ME receiver (no subscriber on "
    f"{FRAME_TOPIC}) says frame_input receiver in its status, acknowledges on {MISSION_TOPIC} "
    "every frame its receiver synchronises on, decoded or not (a false sync in noise shows as "
    "a rejection), with the same JSON and deadline, and publishes status, pose and datum the "
    "same. nemesys vehicle-check probes it through the modem path (--modem tcp://HOST:PORT "
    "or serial:///dev/...): the malformed frame goes out over the ME modem and its rejection "
    "comes back over rosbridge; without --modem the probe's row fails saying so. The console "
    "drives it the same way: frames over the modem, telemetry and acknowledgements over "
    "rosbridge (NEMESYS_TELEMETRY).",
    "A reference ROS 2 node that does all of this, wrapping the simulator's own onboard agent, "
    "is ros2/nemesys_vehicle (its README says how to build and launch it).",
    "Run rosbridge_server with rosapi: the console and vehicle-check read the graph through "
    "/rosapi/topics (the types), /rosapi/publishers and /rosapi/subscribers (the nodes): the "
    "onboard agent runs when a node other than rosbridge's own publishes the mission and "
    "status topics, and frames reach it when one subscribes to the frame topic (rosbridge "
    "subscribes and publishes for its clients, so a topic can exist without the vehicle); a "
    "one-shot sender asks /rosapi/subscribers whether the frame topic has its subscriber "
    "before publishing.",
)


def contract_json() -> dict[str, Any]:
    """The whole contract as JSON (what ``nemesys contract`` prints): a fresh copy."""
    return copy.deepcopy(
        {
            "version": CONTRACT_VERSION,
            "version_rule": VERSION_RULE,
            "topics": [t.as_json() for t in TOPICS],
            "time_base": TIME_BASE,
            "conventions": CONVENTIONS,
            "ack_deadline_s": ACK_DEADLINE_S,
            "schemas": SCHEMAS,
            "obligations": list(OBLIGATIONS),
        }
    )
