"""The log's rows as ROS 2 messages: NED -> ENU at the one edge, frames as the station sends
them, what the log does not hold as ROS's "unknown" (NaN, -1, an empty sequence)."""

from __future__ import annotations

import math
from typing import Any

import pytest

from backend.bag import messages as m
from codec import encode_frame
from station.transmit_base import frame_msg


def row(**fields: Any) -> dict[str, Any]:
    base = {"t_s": 100.25, "x_m": 10.0, "y_m": 5.0, "z_m": 3.0, "heading_deg": 90.0}
    return {**base, **fields}


def test_odometry_is_enu_with_the_yaw_from_east() -> None:
    odom = m.odometry(row(speed_mps=0.3))
    pose = odom["pose"]["pose"]
    assert pose["position"] == {"x": 5.0, "y": 10.0, "z": -3.0}  # east, north, up
    q = pose["orientation"]
    assert (q["x"], q["y"], q["w"]) == (0.0, 0.0, 1.0) and q["z"] == pytest.approx(0.0)  # east
    north = m.odometry(row(heading_deg=0.0))["pose"]["pose"]["orientation"]
    assert 2 * math.degrees(math.atan2(north["z"], north["w"])) == pytest.approx(90.0)
    assert odom["header"] == {"stamp": {"sec": 100, "nanosec": 250_000_000}, "frame_id": "map"}
    assert odom["child_frame_id"] == "base_link"
    assert odom["twist"]["twist"]["linear"]["x"] == 0.3  # forward, FLU


def test_a_frame_is_the_13_bytes_a_station_publishes() -> None:
    frame = encode_frame("circle", {"speed": 0.18, "depth": 3, "radius": 5, "direction": "cw"})
    assert m.frame(frame.frame.hex)["data"] == frame_msg(frame.frame)["data"]


def test_a_choice_parameter_is_text_and_the_pattern_id_comes_from_the_dictionary() -> None:
    cmd = m.command({"pattern": "circle", "params": {"radius": 5, "direction": "ccw"}})
    assert cmd is not None and cmd["pattern_id"] == 3
    radius, direction = cmd["params"]
    assert radius == {"name": "radius", "value": 5.0, "text": ""}
    assert direction["text"] == "ccw" and math.isnan(direction["value"])
    assert m.command(None) is None and m.command({"params": {}}) is None


def test_what_the_log_does_not_hold_is_unknown_in_ros_terms() -> None:
    fault = m.status({"t_s": 5.0, "x_m": None, "nav_valid": False, "mode": "nav_fault"})
    assert math.isnan(fault["x_m"]) and math.isnan(fault["depth_m"])
    assert fault["nav_valid"] is False and fault["active"] == [] and fault["pattern"] == ""
    older = m.status(row(depth_m=None, nav_valid=None))
    assert older["nav_valid"] is True  # a 1.x vehicle that does not say: taken as true
    assert older["depth_m"] == 3.0  # no depth sensor reading: the pose's
    ack = m.ack({"outcome": "rejected", "reason": "crc", "waypoints": [1, 2]}, 7.0)
    assert ack["corrected_bits"] == -1 and ack["waypoints"] == -1 and ack["command"] == []
    assert math.isnan(ack["decode_latency_ms"]) and ack["reason"] == "crc"


def test_the_altitude_of_a_fix_is_minus_the_depth() -> None:
    fix = m.nav_sat_fix(row(), 43.0, 5.0)
    assert fix["altitude"] == -3.0 and fix["position_covariance_type"] == 0


def test_a_fleets_addressed_frame_is_its_14_bytes() -> None:
    frame = encode_frame("surface", {}, address=0).frame
    assert m.frame(frame.hex)["data"] == frame_msg(frame)["data"]
    assert len(m.frame(frame.hex)["data"]) == 14
