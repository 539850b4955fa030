"""The core's outputs: status and pose from odometry (NED, map_ned), guidance setpoints."""

from __future__ import annotations

import json
import math

import pytest

from nemesys_vehicle.frames import yaw_deg_of
from tests.nemesys_vehicle.helpers import (
    CIRCLE,
    T0_S,
    frame_bytes,
    make_core,
    odometry,
    receive_checked,
    running_core,
)
from vehicle_contract.codes import Mode
from vehicle_contract.payloads import validate_status

# --- status and pose -----------------------------------------------------------------------

STATUS_KEYS = {
    "t_s",
    "x_m",
    "y_m",
    "depth_m",
    "heading_deg",
    "speed_mps",
    "battery_pct",
    "mode",
    "pattern",
    "active",
    "nav_valid",
    "nav_age_s",
    "frame_input",
    "recent_acks",
}


def test_status_before_odometry_says_null_for_what_is_unknown() -> None:
    core, rec = make_core()
    status = core.tick_status(T0_S)
    assert rec.statuses == [status]
    assert set(status) == STATUS_KEYS
    assert status["t_s"] == T0_S
    for key in ("x_m", "y_m", "depth_m", "heading_deg", "speed_mps", "battery_pct", "nav_age_s"):
        assert status[key] is None
    assert (status["mode"], status["pattern"], status["active"]) == ("idle", None, None)
    assert (status["nav_valid"], status["frame_input"], status["recent_acks"]) == (
        False,
        "topic",
        [],
    )
    assert validate_status(status) == []
    json.dumps(status, allow_nan=False)


def test_status_from_odometry_is_ned() -> None:
    core, _ = make_core()
    # 3 m east, 4 m north, 5 m deep, facing north (ENU yaw 90)
    core.on_odometry(odometry(T0_S, east_m=3.0, north_m=4.0, up_m=-5.0, yaw_enu_deg=90.0))
    core.on_battery(87.5)
    status = core.tick_status(T0_S + 0.25)
    assert set(status) == STATUS_KEYS
    assert status["t_s"] == T0_S + 0.25
    assert (status["x_m"], status["y_m"], status["depth_m"]) == (4.0, 3.0, 5.0)
    assert status["heading_deg"] == pytest.approx(0.0, abs=1e-9)
    assert status["speed_mps"] == 0.1
    assert status["battery_pct"] == 87.5
    assert status["mode"] == "idle"
    assert (status["nav_valid"], status["nav_age_s"]) == (True, 0.25)
    assert validate_status(status) == []
    text = json.dumps(status, allow_nan=False)
    assert json.loads(text) == status


def test_pose_is_ned_in_map_ned_with_a_yaw_quaternion() -> None:
    core, rec = make_core()
    # 3 m east, 4 m north, 5 m deep, facing east (ENU yaw 0 -> heading 90)
    core.on_odometry(odometry(T0_S, east_m=3.0, north_m=4.0, up_m=-5.0, yaw_enu_deg=0.0))
    pose = core.tick_pose(T0_S + 0.5)
    assert pose is not None
    assert rec.poses == [pose]
    assert pose["header"] == {  # stamped when the navigation solution came, not when sent
        "stamp": {"sec": int(T0_S), "nanosec": 0},
        "frame_id": "map_ned",
    }
    assert pose["pose"]["position"] == {"x": 4.0, "y": 3.0, "z": 5.0}
    q = pose["pose"]["orientation"]
    half = 0.5**0.5
    assert (q["x"], q["y"]) == (0.0, 0.0)
    assert q["z"] == pytest.approx(half)
    assert q["w"] == pytest.approx(half)
    json.dumps(pose, allow_nan=False)


# --- setpoints -----------------------------------------------------------------------------


def test_following_a_path_aims_at_the_line_of_sight_point() -> None:
    core, rec = running_core()
    g = core.guidance
    odo = core.odometry
    assert odo is not None
    sp = core.tick_guidance(odo.t_s + 0.1)
    assert sp is not None
    assert g.mode is Mode.RUNNING
    north, east = odo.y_north_m, odo.x_east_m
    reach = math.hypot(sp.x_north_m - north, sp.y_east_m - east)
    assert reach == pytest.approx(math.hypot(g.config.lookahead_m, g.cross_track_m))
    course = math.degrees(math.atan2(sp.y_east_m - east, sp.x_north_m - north)) % 360.0
    assert course == pytest.approx(sp.course_deg)
    assert sp.speed_mps == pytest.approx(0.2)
    assert sp.vertical is True
    # published in ENU, in the odometry's frame: x east, y north, z up, yaw = 90 - course
    msg = rec.setpoints[-1]
    assert msg["header"]["frame_id"] == "odom"
    p = msg["pose"]["position"]
    assert (p["x"], p["y"], p["z"]) == pytest.approx((sp.y_east_m, sp.x_north_m, -sp.depth_m))
    q = msg["pose"]["orientation"]
    yaw = yaw_deg_of((q["x"], q["y"], q["z"], q["w"]))
    assert (yaw - (90.0 - sp.course_deg)) % 360.0 == pytest.approx(0.0, abs=1e-9)


def test_hover_aims_at_its_hold_point_in_ned() -> None:
    core, rec = make_core(setpoint_frame="ned")
    core.on_odometry(odometry(T0_S))
    ack = receive_checked(core, rec, frame_bytes("hover", duration=60, depth=3, heading=0), T0_S)
    assert ack["outcome"] == "accepted"
    sp = core.tick_guidance(T0_S + 1)
    assert sp is not None
    assert (sp.x_north_m, sp.y_east_m) == core.guidance.hold[:2]
    assert sp.depth_m == 3.0
    msg = rec.setpoints[-1]
    assert msg["header"]["frame_id"] == "map_ned"
    assert msg["pose"]["position"] == {"x": sp.x_north_m, "y": sp.y_east_m, "z": 3.0}


def test_a_vehicle_just_above_the_surface_plans_from_depth_zero() -> None:
    core, rec = make_core()
    core.on_odometry(odometry(T0_S, up_m=0.2))
    assert core.state(T0_S).z_m == 0.0
    ack = receive_checked(core, rec, frame_bytes("circle", **CIRCLE), T0_S)
    assert ack["from"]["z_m"] == 0.0
    assert core.tick_status(T0_S)["depth_m"] == pytest.approx(-0.2)  # the reading, as it is


def test_battery_must_be_a_percentage() -> None:
    core, _ = make_core()
    core.on_battery(0.0)
    core.on_battery(None)
    for bad in (-1.0, 100.5, math.nan):
        with pytest.raises(ValueError, match="battery_pct"):
            core.on_battery(bad)
    assert core.battery_pct is None
