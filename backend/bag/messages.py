"""The mission log's rows as ROS 2 messages (plain dicts in the types' field names, which
``mcap_ros2`` encodes and :func:`backend.bag.write.rosbags_message` turns into rosbags'
classes): one function per message, and the topics a dive export writes them on.

Frames: the pose leaves the contract's ``map_ned`` for ROS's ENU ``map`` through the one
function :func:`vehicle_contract.frames.ned_to_enu` (REP-103: x east, y north, z up, the yaw
from east counter-clockwise; the body FLU, so the speed is ``twist.linear.x``). The typed
status keeps the contract's NED numbers, as its JSON form does. A number the log does not hold
is NaN (a count: -1; an optional command: an empty sequence), ROS having no null.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from typing import Any, Final, NamedTuple

from backend.bag.msgdefs import type_name
from codec import ADDRESSED_FRAME_BITS, DICTIONARY, AddressedFrame, Frame
from vehicle_contract.contract import POSE_FRAME_ID
from vehicle_contract.frames import NedPose, ned_to_enu
from vehicle_contract.messages import number, quaternion_from_roll_yaw

Msg = dict[str, Any]

#: The ROS world frame of the exported odometry (REP-105's fixed frame, ENU) and its body.
MAP_FRAME: Final = "map"
BODY_FRAME: Final = "base_link"
NAN: Final = math.nan


class Topic(NamedTuple):
    """A topic of a dive export: its name, its ROS 2 type and what one message is."""

    name: str
    type: str
    what: str


ODOM = Topic(
    "/nemesys/odom",
    "nav_msgs/msg/Odometry",
    "the vehicle's pose (ENU map frame, REP-103) and speed, one per track point with a position",
)
FIX = Topic(
    "/nemesys/fix",
    "sensor_msgs/msg/NavSatFix",
    "the same position as latitude/longitude about the datum (altitude: minus the depth); "
    "only with a datum",
)
STATUS = Topic(
    "/nemesys/typed/status",
    type_name("Status"),
    "the vehicle's status at each track point (1 Hz), those without a position included",
)
FRAME = Topic(
    "/nemesys/frame",
    "std_msgs/msg/UInt8MultiArray",
    "a command's 13 frame bytes as the contract's frame topic carries them, when its first "
    "copy left",
)
COMMANDS = Topic(
    "/nemesys/console/commands",
    type_name("CommandRecord"),
    "every command record of the dive, when the console wrote it, with how it ended",
)
ACK = Topic(
    "/nemesys/typed/ack",
    type_name("Ack"),
    "each acknowledgement the console logged, when it arrived",
)
MISSION = Topic(
    "/nemesys/mission",
    "std_msgs/msg/String",
    "the same acknowledgements as the vehicle sent them: the contract's JSON form",
)
EVENTS = Topic(
    "/nemesys/console/events",
    "std_msgs/msg/String",
    "the log's events (a datum set, an echo mismatch) as JSON {kind, detail, data}",
)
#: Every topic of a dive export, in the order they are declared.
TOPICS: Final = (ODOM, FIX, STATUS, FRAME, COMMANDS, ACK, MISSION, EVENTS)


def vehicle_topic(topic: Topic, vehicle: str | None) -> Topic:
    """``topic`` of a fleet's ``vehicle``: under ``/<name>`` (``/auv2/nemesys/odom``), the
    naming of the live Foxglove view's (:func:`backend.foxglove_live.channels.vehicle_topic`);
    None (a single vehicle's, or a row naming no vehicle): ``topic`` as it is."""
    if vehicle is None:
        return topic
    return topic._replace(name=f"/{vehicle}{topic.name}", what=f"{vehicle}: {topic.what}")


def body_frame(vehicle: str | None) -> str:
    """The body frame of a fleet's ``vehicle``'s odometry, ``<name>/base_link`` (each vehicle
    its own frame, as ROS names a robot's among several); :data:`BODY_FRAME` without one."""
    return BODY_FRAME if vehicle is None else f"{vehicle}/{BODY_FRAME}"


def stamp(t_s: float) -> Msg:
    """``builtin_interfaces/Time`` of ``t_s`` seconds (rounded to the nanosecond)."""
    ns = round(t_s * 1e9)
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def header(t_s: float, frame_id: str = "") -> Msg:
    return {"stamp": stamp(t_s), "frame_id": frame_id}


def _float(value: Any) -> float:
    got = number(value)
    return NAN if got is None else got


def _count(value: Any) -> int:
    got = number(value)
    return int(got) if got is not None and got == int(got) and got >= 0 else -1


def _text(value: Any) -> str:
    return value if isinstance(value, str) else ""


def command(obj: Any) -> Msg | None:
    """``nemesys_msgs/Command`` of a command object (pattern, pattern_id, params); None when
    ``obj`` is none (its ``pattern_id`` from the dictionary when it does not say)."""
    if not isinstance(obj, Mapping) or not isinstance(obj.get("pattern"), str):
        return None
    pattern = obj["pattern"]
    pattern_id = obj.get("pattern_id")
    if not isinstance(pattern_id, int):
        pattern_id = DICTIONARY[pattern].id if pattern in DICTIONARY else 0
    given = obj.get("params")
    params: Mapping[str, Any] = given if isinstance(given, Mapping) else {}
    return {
        "pattern": pattern,
        "pattern_id": pattern_id,
        "params": [
            {"name": str(name), "value": NAN, "text": value}
            if isinstance(value, str)
            else {"name": str(name), "value": _float(value), "text": ""}
            for name, value in params.items()
        ],
    }


def _optional(obj: Any) -> list[Msg]:
    got = command(obj)
    return [] if got is None else [got]


def odometry(row: Mapping[str, Any]) -> Msg:
    """``nav_msgs/Odometry`` of a track row with a position (NED -> ENU, the yaw about up);
    its child frame the row's vehicle's body (:func:`body_frame`)."""
    enu = ned_to_enu(NedPose(row["x_m"], row["y_m"], row["z_m"], row["heading_deg"]))
    qx, qy, qz, qw = quaternion_from_roll_yaw(0.0, enu.yaw_deg)
    zero6 = [0.0] * 36
    return {
        "header": header(row["t_s"], MAP_FRAME),
        "child_frame_id": body_frame(row.get("vehicle")),
        "pose": {
            "pose": {
                "position": {"x": enu.x_east_m, "y": enu.y_north_m, "z": enu.z_up_m},
                "orientation": {"x": qx, "y": qy, "z": qz, "w": qw},
            },
            "covariance": zero6,
        },
        "twist": {
            "twist": {
                "linear": {"x": _float(row.get("speed_mps")), "y": 0.0, "z": 0.0},
                "angular": {"x": 0.0, "y": 0.0, "z": 0.0},
            },
            "covariance": zero6,
        },
    }


def nav_sat_fix(row: Mapping[str, Any], lat_deg: float, lon_deg: float) -> Msg:
    """``sensor_msgs/NavSatFix`` of a track row's position: a position the vehicle's navigation
    and the datum give (not a GNSS fix: no service, covariance unknown); the altitude is
    above the water surface, minus the depth."""
    return {
        "header": header(row["t_s"], MAP_FRAME),
        "status": {"status": 0, "service": 0},  # STATUS_FIX: the position is known
        "latitude": lat_deg,
        "longitude": lon_deg,
        "altitude": -float(row["z_m"]) + 0.0,
        "position_covariance": [0.0] * 9,
        "position_covariance_type": 0,  # COVARIANCE_TYPE_UNKNOWN
    }


def status(row: Mapping[str, Any]) -> Msg:
    """``nemesys_msgs/Status`` of a track row (a row without a position included)."""
    depth = row.get("depth_m")
    active = row.get("active")
    nav_valid = row.get("nav_valid")
    return {
        "header": header(row["t_s"], POSE_FRAME_ID),
        "x_m": _float(row.get("x_m")),
        "y_m": _float(row.get("y_m")),
        "depth_m": _float(depth if depth is not None else row.get("z_m")),
        "commanded_depth_m": _float(row.get("commanded_depth_m")),
        "heading_deg": _float(row.get("heading_deg")),
        "speed_mps": _float(row.get("speed_mps")),
        "battery_pct": _float(row.get("battery_pct")),
        "mode": _text(row.get("mode")),
        "pattern": _text(active.get("pattern")) if isinstance(active, Mapping) else "",
        "active": _optional(active),
        "nav_valid": nav_valid is not False,  # not said: a 1.x vehicle, taken as true
        "nav_age_s": _float(row.get("nav_age_s")),
    }


def ack(obj: Mapping[str, Any], t_s: float) -> Msg:
    """``nemesys_msgs/Ack`` of an acknowledgement as logged, stamped ``t_s`` (its own ``t_s``
    when it has one: the caller's choice)."""
    return {
        "header": header(t_s),
        "seq": max(0, _count(obj.get("seq"))),
        "outcome": _text(obj.get("outcome")),
        "frame_hex": _text(obj.get("frame_hex")),
        "corrected_bits": _count(obj.get("corrected_bits")),
        "sync_errors": _count(obj.get("sync_errors")),
        "reason": _text(obj.get("reason")),
        "detail": _text(obj.get("detail")),
        "field": _text(obj.get("field")),
        "command": _optional(obj.get("command")),
        "duplicate": obj.get("duplicate") is True,
        "decode_latency_ms": _float(obj.get("decode_latency_ms")),
        "replan_latency_ms": _float(obj.get("replan_latency_ms")),
        "waypoints": _count(obj.get("waypoints")),
        "active": _optional(obj.get("active")),
        "late": obj.get("late") is True,
    }


def command_record(record: Mapping[str, Any], t_s: float) -> Msg:
    """``nemesys_msgs/CommandRecord`` of a command row (``MissionLog.commands``), stamped
    ``t_s`` (when the console wrote it)."""
    sent = command(record) or {"pattern": _text(record.get("pattern")), "pattern_id": 0}
    return {
        "header": header(t_s),
        "id": int(record["id"]),
        "kind": _text(record.get("kind")),
        "command": {"params": [], **sent},
        "frame_hex": _text(record.get("hex")),
        "state": _text(record.get("state")),
        "reason": _text(record.get("reason")),
        "operator": _text(record.get("operator")),
        "origin": _text(record.get("origin")),
        "copies": max(0, _count(record.get("copies"))),
        "copies_sent": max(0, _count(record.get("copies_sent"))),
        "p_delivered": _float(record.get("p_delivered")),
        "retry_of": max(0, _count(record.get("retry_of"))),
    }


def frame(hex_text: str) -> Msg:
    """``std_msgs/UInt8MultiArray`` of a frame (25 hex digits; a fleet's addressed frame 27):
    its 13 (14) bytes, MSB first, the last 4 bits zero, as a station publishes it (no
    layout)."""
    value = int(hex_text, 16)
    addressed = len(hex_text) == ADDRESSED_FRAME_BITS // 4
    data = (AddressedFrame(value) if addressed else Frame(value)).to_bytes()
    return {"layout": {"dim": [], "data_offset": 0}, "data": list(data)}


def json_string(obj: Any) -> Msg:
    """``std_msgs/String`` holding ``obj`` as JSON (the contract's compatibility form)."""
    return {"data": json.dumps(obj, separators=(",", ":"))}
