"""The ament package around the node: files, parameters, conversions, configuration."""

from __future__ import annotations

import ast
import json
import math
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

import nemesys_vehicle
from nemesys_vehicle.config import VehicleConfig
from nemesys_vehicle.convert import (
    battery_fraction,
    config_from_parameters,
    contract_qos,
    fill_pose_stamped,
    frame_data,
    json_text,
    navsatfix_from_msg,
    odometry_from_msg,
    ros_time_s,
)
from nemesys_vehicle.frames import MapOrigin, NedPose
from nemesys_vehicle.messages import Odometry, Setpoint, pose_msg, setpoint_msg
from planner import CircleFence
from tests.nemesys_vehicle import fake_rclpy
from vehicle_contract.contract import FRAME_TOPIC, Durability, Reliability

PACKAGE = Path(nemesys_vehicle.__file__).parent.parent


def _params_yaml() -> dict[str, Any]:
    """The flat ``ros__parameters`` of config/params.yaml (scalars only, JSON-compatible)."""
    text = (PACKAGE / "config" / "params.yaml").read_text(encoding="utf-8")
    assert re.search(r"^/\*\*:\n  ros__parameters:\n", text, re.MULTILINE)
    values: dict[str, Any] = {}
    for line in text.splitlines():
        m = re.fullmatch(r" {4}(\w+): (.+)", line)
        if m:
            values[m[1]] = json.loads(m[2])
    return values


# --- package files -------------------------------------------------------------------------


def test_params_yaml_lists_every_parameter_with_its_default_and_type() -> None:
    values = _params_yaml()
    defaults = dict(VehicleConfig.parameter_defaults())
    assert values == defaults
    for name, value in values.items():
        # ROS 2 types a parameter by its default: 2 and 2.0 are not the same
        assert type(value) is type(defaults[name]), name


def test_package_xml() -> None:
    root = ET.parse(PACKAGE / "package.xml").getroot()
    assert root.tag == "package"
    assert root.get("format") == "3"
    assert root.findtext("name") == "nemesys_vehicle"
    deps = {e.text for e in root if e.tag in ("depend", "exec_depend")}
    assert {
        "rclpy",
        "std_msgs",
        "geometry_msgs",
        "nav_msgs",
        "launch",
        "launch_ros",
        "python3-serial",
    } <= deps
    assert root.findtext("export/build_type") == "ament_python"


def test_setup_files_and_marker() -> None:
    setup_py = (PACKAGE / "setup.py").read_text(encoding="utf-8")
    ast.parse(setup_py)
    assert '"vehicle_node = nemesys_vehicle.node:main"' in setup_py
    assert "resource/{PACKAGE}" in setup_py
    cfg = (PACKAGE / "setup.cfg").read_text(encoding="utf-8")
    assert "script_dir=$base/lib/nemesys_vehicle" in cfg
    assert "install_scripts=$base/lib/nemesys_vehicle" in cfg
    assert (PACKAGE / "resource" / "nemesys_vehicle").is_file()
    assert (PACKAGE / "README.md").is_file()


def test_launch_file_starts_the_node_with_the_params_file() -> None:
    text = (PACKAGE / "launch" / "vehicle.launch.py").read_text(encoding="utf-8")
    tree = ast.parse(text)
    names = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}
    assert "generate_launch_description" in names
    strings = {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant)}
    assert {"nemesys_vehicle", "vehicle_node", "params.yaml", "params_file"} <= strings


#: What the node may import of this repository: the vehicle side, nothing of the station, the
#: simulator or the console (README.md, "Install").
VEHICLE_SIDE = {"codec", "planner", "onboard", "vehicle_contract", "nemesys_vehicle"}
#: Top-level packages of this repository that a vehicle does not install.
STATION_SIDE = ("rosbridge", "station", "sim", "backend", "cli", "bench", "analysis")


def test_the_node_imports_only_the_vehicle_side() -> None:
    """Read with ``ast``, lazy imports inside functions included."""
    found: dict[str, str] = {}
    for path in sorted((PACKAGE / "nemesys_vehicle").glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                names = [node.module]
            else:
                continue
            for name in names:
                found.setdefault(name.split(".")[0], f"{path.name}:{node.lineno}")
    assert {"codec", "planner", "onboard", "vehicle_contract"} <= set(found)
    for top in STATION_SIDE:
        assert top not in found, f"{found[top]} imports {top}"


def test_the_nodes_core_runs_without_the_station_side() -> None:
    """The ROS-free modules, imported in a fresh interpreter, load none of the station's."""
    code = (
        "import sys; import nemesys_vehicle.core, nemesys_vehicle.convert, "
        "nemesys_vehicle.frames, nemesys_vehicle.config, nemesys_vehicle.stream; "
        "print('\\n'.join(sys.modules))"
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(PACKAGE), str(PACKAGE.parents[1])])}
    out = subprocess.run(
        [sys.executable, "-c", code], check=True, capture_output=True, text=True, env=env
    ).stdout.split()
    assert "vehicle_contract.messages" in out and "onboard.agent" in out
    loaded = {m.split(".")[0] for m in out}
    assert not loaded & set(STATION_SIDE), sorted(loaded & set(STATION_SIDE))
    assert "jsonschema" not in loaded


# --- configuration -------------------------------------------------------------------------


def test_config_builds_the_limits_and_guidance() -> None:
    config = VehicleConfig(
        max_depth_m=10.0,
        max_speed_mps=0.5,
        geofence_radius_m=30.0,
        geofence_north_m=5.0,
        geofence_east_m=-5.0,
        lookahead_m=2.5,
    )
    limits = config.limits()
    assert (limits.max_depth_m, limits.max_speed_mps) == (10.0, 0.5)
    assert limits.geofence == CircleFence(30.0, (5.0, -5.0))
    assert VehicleConfig().limits().geofence is None
    assert config.guidance_config().lookahead_m == 2.5
    assert config.status_period_s == 0.5
    assert config.guidance_period_s == 0.1


@pytest.mark.parametrize(
    "bad",
    [
        {"frame_input": "udp"},
        {"frame_input": "serial"},  # without a URL
        {"setpoint_frame": "ecef"},
        {"status_hz": 0.0},
        {"pose_hz": math.nan},
        {"serial_baud": 0},
        {"max_depth_m": 500.0},  # beyond the rated depth
        {"max_speed_mps": -1.0},
        {"geofence_radius_m": -1.0},
        {"vehicle_namespace": "auv-1"},
        {"vehicle_namespace": "1auv"},
        {"nav_timeout_s": 0.0},
        {"nav_timeout_s": math.inf},
        {"nav_fault_action": "drift"},
        {"datum_source": "gps"},
        {"datum_lat_deg": 91.0},
        {"datum_lon_deg": math.nan},
        {"odometry_origin_at_datum": True},  # the datum is the first fix's: no origin there
        {"fix_max_depth_m": -0.1},
        {"magnetic_declination_deg": 200.0},
        {"navsatfix_topic": ""},
        {"setpoint_topic": "/"},
    ],
    ids=str,
)
def test_config_refuses_bad_values(bad: dict[str, Any]) -> None:
    with pytest.raises(ValueError):
        VehicleConfig(**bad)


def test_topic_parameters_without_a_slash_go_under_the_vehicle_namespace() -> None:
    plain = VehicleConfig()
    assert plain.resolve(plain.setpoint_topic) == "/nemesys/setpoint"
    assert plain.resolve(plain.odometry_topic) == "/odom"
    named = VehicleConfig(vehicle_namespace="fleet/auv1/")
    assert named.resolve(named.setpoint_topic) == "/fleet/auv1/nemesys/setpoint"
    assert named.resolve("odom") == "/fleet/auv1/odom"
    assert named.resolve("/odom") == "/odom"


def test_config_from_parameters() -> None:
    params = [
        SimpleNamespace(name="pose_hz", value=12.0),
        SimpleNamespace(name="serial_baud", value=9600),
    ]
    config = config_from_parameters(params)
    assert (config.pose_hz, config.serial_baud) == (12.0, 9600)
    with pytest.raises(ValueError, match="unknown parameters"):
        config_from_parameters([SimpleNamespace(name="max_depht_m", value=1.0)])


# --- conversions to and from ROS message objects -------------------------------------------


def test_odometry_from_msg() -> None:
    msg: Any = fake_rclpy.OdometryMsg()
    msg.header.frame_id = "map"
    p, q = msg.pose.pose.position, msg.pose.pose.orientation
    p.x, p.y, p.z = 1.0, 2.0, -3.0
    q.z, q.w = math.sin(math.pi / 4), math.cos(math.pi / 4)
    v = msg.twist.twist.linear
    v.x, v.y, v.z = 0.3, 0.4, 0.0
    odo = odometry_from_msg(msg, 12.5)
    assert odo == Odometry(12.5, 1.0, 2.0, -3.0, 0.0, 0.0, q.z, q.w, odo.speed_mps, "map")
    assert odo.speed_mps == pytest.approx(0.5)
    enu = odo.enu()
    assert enu[:3] == (1.0, 2.0, -3.0)
    assert enu.yaw_deg == pytest.approx(90.0)  # facing north
    assert odo.depth_m == 3.0
    msg.header.frame_id = ""
    assert odometry_from_msg(msg, 0.0).frame_id == "odom"


def test_fill_pose_stamped_casts_to_the_field_types() -> None:
    msg: Any = fake_rclpy.PoseStamped()
    pose = pose_msg(3.75, NedPose(1, 2, 3, 90))  # ints where ROS wants float64
    assert fill_pose_stamped(msg, pose) is msg
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (3, 750_000_000)
    assert msg.header.frame_id == "map_ned"
    position = msg.pose.position
    assert (position.x, position.y, position.z) == (1.0, 2.0, 3.0)
    assert all(type(getattr(position, a)) is float for a in "xyz")
    assert msg.pose.orientation.z == pytest.approx(math.sqrt(0.5))


def test_setpoint_frames() -> None:
    # aiming 1 m north and 2 m east of the origin, 4 m deep, course 90 (east)
    sp = Setpoint(5.0, 1.0, 2.0, 4.0, 90.0, 0.3, True, "running")
    ned = setpoint_msg(sp, "ned", "odom")
    assert ned["header"]["frame_id"] == "map_ned"
    assert ned["pose"]["position"] == {"x": 1.0, "y": 2.0, "z": 4.0}
    enu = setpoint_msg(sp, "enu", "world")
    assert enu["header"]["frame_id"] == "world"
    assert enu["pose"]["position"] == {"x": 2.0, "y": 1.0, "z": -4.0}
    assert enu["pose"]["orientation"] == {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}  # ENU yaw 0
    # the odometry's origin 10 m north of the datum: the same point is 9 m south of it
    shifted = setpoint_msg(sp, "enu", "world", MapOrigin(10.0, 0.0, 0.0))
    assert shifted["pose"]["position"] == {"x": 2.0, "y": -9.0, "z": -4.0}


def test_navsatfix_and_battery_from_msg() -> None:
    fix = fake_rclpy.NavSatFix(29.5, -82.25, status=0)
    assert navsatfix_from_msg(fix) == (29.5, -82.25, True)
    fix.status.status = -1  # STATUS_NO_FIX
    assert navsatfix_from_msg(fix)[2] is False
    fix.status.status = 2  # STATUS_GBAS_FIX
    assert navsatfix_from_msg(fix)[2] is True
    assert battery_fraction(fake_rclpy.BatteryState(0.42)) == 0.42
    assert math.isnan(battery_fraction(fake_rclpy.BatteryState()))


def test_small_conversions() -> None:
    assert frame_data(SimpleNamespace(data=[1, 2, 255])) == b"\x01\x02\xff"
    assert ros_time_s(1_500_000_000) == 1.5
    assert json.loads(json_text({"a": math.nan, "b": 1})) == {"a": None, "b": 1}
    qos = contract_qos(FRAME_TOPIC)
    assert (qos.reliability, qos.durability) == (Reliability.RELIABLE, Durability.TRANSIENT_LOCAL)
