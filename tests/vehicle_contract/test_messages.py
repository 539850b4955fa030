"""The contract's pose and status messages (:mod:`vehicle_contract.messages`): the heading
quaternion against an independent rotation matrix, the time stamps, the pose message and its
reading back, strict JSON of the payloads, and the numbers the console reads from a status."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rosbridge.convert import extract
from rosbridge.wire import wire_json
from vehicle_contract.contract import POSE_FRAME_ID
from vehicle_contract.endpoint import Pose
from vehicle_contract.messages import (
    POSE_KEYS,
    STATUS_NUMBERS,
    number,
    pose_from_message,
    pose_stamped_msg,
    position_known,
    quaternion_from_roll_yaw,
    stamp,
    status_from_message,
    to_json,
    unknown_count,
)


def rotate(q: tuple[float, float, float, float], v: tuple[float, float, float]) -> list[float]:
    """``q v q*`` for a unit quaternion ``(x, y, z, w)``."""
    x, y, z, w = q
    # Rotation matrix of a unit quaternion (Hamilton convention).
    m = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    return [sum(m[i][j] * v[j] for j in range(3)) for i in range(3)]


def euler_matrix(roll_deg: float, yaw_deg: float) -> list[list[float]]:
    """R = Rz(yaw) Rx(roll): body to NED, built independently of the quaternion code."""
    r, y = math.radians(roll_deg), math.radians(yaw_deg)
    rz = [[math.cos(y), -math.sin(y), 0.0], [math.sin(y), math.cos(y), 0.0], [0.0, 0.0, 1.0]]
    rx = [[1.0, 0.0, 0.0], [0.0, math.cos(r), -math.sin(r)], [0.0, math.sin(r), math.cos(r)]]
    return [[sum(rz[i][k] * rx[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def test_quaternion_identity_and_axes() -> None:
    assert quaternion_from_roll_yaw(0.0, 0.0) == (0.0, 0.0, 0.0, 1.0)
    # Heading 90 deg: the bow (+x body) points east (+y NED).
    assert rotate(quaternion_from_roll_yaw(0.0, 90.0), (1, 0, 0)) == pytest.approx(
        [0, 1, 0], abs=1e-12
    )
    # Heading 180: south.
    assert rotate(quaternion_from_roll_yaw(0.0, 180.0), (1, 0, 0)) == pytest.approx(
        [-1, 0, 0], abs=1e-12
    )
    # Roll +90 deg: starboard (+y body) goes down (+z NED).
    assert rotate(quaternion_from_roll_yaw(90.0, 0.0), (0, 1, 0)) == pytest.approx(
        [0, 0, 1], abs=1e-12
    )
    # Roll 90 then heading 90: starboard still points down, the bow east.
    q = quaternion_from_roll_yaw(90.0, 90.0)
    assert rotate(q, (0, 1, 0)) == pytest.approx([0, 0, 1], abs=1e-12)
    assert rotate(q, (1, 0, 0)) == pytest.approx([0, 1, 0], abs=1e-12)


def test_quaternion_sign_is_canonical() -> None:
    q = quaternion_from_roll_yaw(0.0, 359.0)
    assert q[3] > 0.0
    assert q == pytest.approx(quaternion_from_roll_yaw(0.0, -1.0), abs=1e-15)
    assert all(math.copysign(1.0, c) == 1.0 for c in quaternion_from_roll_yaw(0.0, 360.0)[:2])
    for roll, yaw in [(170.0, 200.0), (-179.0, -181.0), (90.0, 540.0)]:
        assert quaternion_from_roll_yaw(roll, yaw)[3] >= 0.0


@pytest.mark.parametrize(
    ("roll", "yaw"), [(30.0, 45.0), (-12.5, 300.0), (5.0, -170.0), (170.0, 200.0)]
)
def test_quaternion_matches_euler_matrix(roll: float, yaw: float) -> None:
    q = quaternion_from_roll_yaw(roll, yaw)
    assert math.fsum(c * c for c in q) == pytest.approx(1.0, abs=1e-12)
    m = euler_matrix(roll, yaw)
    for axis in ((1, 0, 0), (0, 1, 0), (0, 0, 1)):
        expected = [sum(m[i][j] * axis[j] for j in range(3)) for i in range(3)]
        assert rotate(q, axis) == pytest.approx(expected, abs=1e-12)


def test_stamp() -> None:
    assert stamp(0.0) == {"sec": 0, "nanosec": 0}
    assert stamp(12.5) == {"sec": 12, "nanosec": 500_000_000}
    assert stamp(3.000000001) == {"sec": 3, "nanosec": 1}
    assert stamp(0.9999999999) == {"sec": 1, "nanosec": 0}
    assert stamp(-0.25) == {"sec": -1, "nanosec": 750_000_000}
    assert stamp(math.nan) == {"sec": 0, "nanosec": 0}
    assert stamp(math.inf) == {"sec": 0, "nanosec": 0}


def test_pose_stamped_msg() -> None:
    msg = pose_stamped_msg(Pose(t_s=7.25, x_m=10.0, y_m=-3.5, z_m=4.0, roll_deg=0, heading_deg=90))
    assert msg["header"] == {"stamp": {"sec": 7, "nanosec": 250_000_000}, "frame_id": "map_ned"}
    assert POSE_FRAME_ID == "map_ned"
    assert msg["pose"]["position"] == {"x": 10.0, "y": -3.5, "z": 4.0}
    o = msg["pose"]["orientation"]
    half = math.sqrt(0.5)
    assert (o["x"], o["y"], o["z"], o["w"]) == pytest.approx((0.0, 0.0, half, half))
    # The same message a ROS 2 rosbridge would send for it: complete, NaN as null.
    assert extract("geometry_msgs/msg/PoseStamped", msg) == msg
    nan = pose_stamped_msg(Pose(1.0, math.nan, 0.0, 0.0, 0.0, 0.0))
    assert json.loads(wire_json(nan))["pose"]["position"]["x"] is None


def test_to_json_takes_numpy_values() -> None:
    status = {"depth_m": np.float32(2.5), "frames": np.int64(3), "ber": np.array([1e-3, np.nan])}
    assert to_json(status) == '{"depth_m":2.5,"frames":3,"ber":[0.001,null]}'
    with pytest.raises(TypeError, match="object is not JSON serializable"):
        to_json({"x": object()})


@pytest.mark.parametrize(
    "pose",
    [
        Pose(7.25, 10.0, -3.5, 4.0, 0.0, 90.0),
        Pose(1_700_000_000.125, -250.5, 731.25, 99.5, -12.5, 359.5),
        Pose(0.0, 0.0, 0.0, 0.0, 30.0, 0.0),
    ],
)
def test_a_pose_message_reads_back_as_the_pose_it_was_built_from(pose: Pose) -> None:
    read = pose_from_message(json.loads(to_json(pose_stamped_msg(pose))))
    assert list(read) == list(POSE_KEYS)
    assert read["t_s"] == pytest.approx(pose.t_s, abs=1e-9)
    assert (read["x_m"], read["y_m"], read["z_m"]) == (pose.x_m, pose.y_m, pose.z_m)
    assert read["heading_deg"] == pytest.approx(pose.heading_deg % 360.0, abs=1e-9)
    assert read["roll_deg"] == pytest.approx(pose.roll_deg, abs=1e-9)
    assert position_known(read) and unknown_count(read) == 0


def test_what_the_vehicle_did_not_send_is_unknown() -> None:
    msg = json.loads(wire_json(pose_stamped_msg(Pose(2.0, math.nan, 1.0, math.inf, 0.0, 0.0))))
    read = pose_from_message(msg)
    assert read["x_m"] is None and read["z_m"] is None and read["y_m"] == 1.0
    assert not position_known(read) and unknown_count(read) == 2
    assert not position_known(None)
    empty = pose_from_message({})
    assert all(value is None for value in empty.values()) and unknown_count(empty) == 6
    no_w = {"pose": {"orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": True}}}
    assert pose_from_message(no_w)["heading_deg"] is None  # a boolean is not a number


@pytest.mark.parametrize(
    ("value", "expected"),
    [(1, 1.0), (2.5, 2.5), (math.nan, None), (-math.inf, None), (True, None), ("3", None)],
)
def test_number(value: object, expected: float | None) -> None:
    assert number(value) == expected


def test_status_numbers_are_finite_or_none_and_counted() -> None:
    msg = {"t_s": 3.5, "depth_m": None, "battery_pct": True, "speed_mps": 0.2, "mode": "idle"}
    status, unknown = status_from_message(msg)
    assert status["t_s"] == 3.5 and status["speed_mps"] == 0.2 and status["mode"] == "idle"
    assert status["depth_m"] is None and status["battery_pct"] is None
    assert set(STATUS_NUMBERS) <= set(status)
    assert unknown == len(STATUS_NUMBERS) - 2  # all but t_s and speed_mps
