"""Conversions between ROS 2 message objects and the core's plain values. No ROS imports.

The functions read and write message objects by attribute (duck typing), so they run, and are
tested, without ROS 2: ``nav_msgs/msg/Odometry``, ``sensor_msgs/msg/NavSatFix`` and
``sensor_msgs/msg/BatteryState`` in, ``geometry_msgs/msg/PoseStamped`` filled in place, JSON
text for ``std_msgs/msg/String``, parameters to :class:`VehicleConfig`, and the QoS of every
topic the node uses (the contract's for the contract topics).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any, Final

from nemesys_vehicle.config import VehicleConfig
from nemesys_vehicle.messages import Odometry
from vehicle_contract.contract import Durability, QoS, Reliability, topic
from vehicle_contract.messages import to_json

#: Odometry in: BEST_EFFORT matches both reliable and best-effort publishers (sensor data).
ODOMETRY_QOS: Final = QoS(Reliability.BEST_EFFORT, Durability.VOLATILE, 5)
#: Setpoints out: a RELIABLE publisher matches reliable and best-effort subscribers; only the
#: latest setpoint matters.
SETPOINT_QOS: Final = QoS(Reliability.RELIABLE, Durability.VOLATILE, 1)
#: GPS fixes and battery states in: sensor data, as odometry (matches any publisher).
SENSOR_QOS: Final = QoS(Reliability.BEST_EFFORT, Durability.VOLATILE, 5)
#: ``sensor_msgs/msg/NavSatStatus.STATUS_FIX``: a status at or above it has a fix.
STATUS_FIX: Final = 0


def contract_qos(topic_name: str) -> QoS:
    """The contract's QoS of one of its topics."""
    return topic(topic_name).qos


def ros_time_s(nanoseconds: int) -> float:
    """ROS time (``Time.nanoseconds``) in seconds."""
    return nanoseconds * 1e-9


def frame_data(msg: Any) -> bytes:
    """The bytes of a ``std_msgs/msg/UInt8MultiArray`` (``data``: array('B') or a list)."""
    return bytes(msg.data)


def odometry_from_msg(msg: Any, t_s: float) -> Odometry:
    """A ``nav_msgs/msg/Odometry`` as :class:`Odometry` at ``t_s`` (the node's clock when it
    arrived: some drivers leave the header stamp zero). The speed is the norm of the twist's
    linear velocity (child frame)."""
    pose = msg.pose.pose
    p, q = pose.position, pose.orientation
    v = msg.twist.twist.linear
    return Odometry(
        t_s,
        float(p.x),
        float(p.y),
        float(p.z),
        float(q.x),
        float(q.y),
        float(q.z),
        float(q.w),
        math.sqrt(v.x * v.x + v.y * v.y + v.z * v.z),
        str(msg.header.frame_id) or "odom",
    )


def navsatfix_from_msg(msg: Any) -> tuple[float, float, bool]:
    """A ``sensor_msgs/msg/NavSatFix`` as ``(lat_deg, lon_deg, fixed)``: ``fixed`` when its
    status says it has a fix (``status.status >= STATUS_FIX``)."""
    return float(msg.latitude), float(msg.longitude), int(msg.status.status) >= STATUS_FIX


def battery_fraction(msg: Any) -> float:
    """The state of charge of a ``sensor_msgs/msg/BatteryState``: ``percentage``, 0..1 (NaN:
    not measured)."""
    return float(msg.percentage)


def fill_pose_stamped(msg: Any, pose: Mapping[str, Any]) -> Any:
    """Write a PoseStamped dict (``core.pose_msg``, ``core.setpoint_msg``) into a
    ``geometry_msgs/msg/PoseStamped`` object; returns it. Numbers are cast to the field types
    (rclpy refuses an int in a float64 field)."""
    header, body = pose["header"], pose["pose"]
    msg.header.stamp.sec = int(header["stamp"]["sec"])
    msg.header.stamp.nanosec = int(header["stamp"]["nanosec"])
    msg.header.frame_id = str(header["frame_id"])
    for name in ("x", "y", "z"):
        setattr(msg.pose.position, name, float(body["position"][name]))
    for name in ("x", "y", "z", "w"):
        setattr(msg.pose.orientation, name, float(body["orientation"][name]))
    return msg


def json_text(value: Any) -> str:
    """The ``data`` of a ``std_msgs/msg/String`` carrying JSON, as the simulator's bridge
    writes it (strict JSON: NaN and infinities as ``null``)."""
    return to_json(value)


def config_from_parameters(parameters: Iterable[Any]) -> VehicleConfig:
    """A config from ``rclpy`` Parameter objects (``.name``, ``.value``)."""
    return VehicleConfig.from_values({p.name: p.value for p in parameters})
