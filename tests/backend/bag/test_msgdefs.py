"""The typed NemeSys messages: an interface package ROS can build (ros2/nemesys_msgs), whose
.msg files are what the exports declare, and message builders that fill every field."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from typing import Any

import pytest
from rosbags.interfaces import Nodetype

from backend.bag import messages as m
from backend.bag.msgdefs import MSG_DIR, NEMESYS_MESSAGES, definition, msg_text, typestore

PACKAGE_DIR = MSG_DIR.parent


def test_the_package_generates_exactly_its_msg_files_in_dependency_order() -> None:
    cmake = (PACKAGE_DIR / "CMakeLists.txt").read_text()
    listed = re.findall(r'"msg/(\w+)\.msg"', cmake)
    assert listed == list(NEMESYS_MESSAGES)
    assert sorted(p.stem for p in MSG_DIR.glob("*.msg")) == sorted(NEMESYS_MESSAGES)
    assert "rosidl_generate_interfaces(${PROJECT_NAME}" in cmake
    assert "DEPENDENCIES std_msgs" in cmake


def test_package_xml_is_an_interface_package_depending_on_what_the_msgs_use() -> None:
    root = ET.parse(PACKAGE_DIR / "package.xml").getroot()
    assert root.get("format") == "3" and root.findtext("name") == "nemesys_msgs"

    def texts(tag: str) -> set[str]:
        return {e.text or "" for e in root.iter(tag)}

    assert texts("buildtool_depend") == {"ament_cmake", "rosidl_default_generators"}
    assert texts("exec_depend") == {"rosidl_default_runtime"}
    assert texts("member_of_group") == {"rosidl_interface_packages"}
    assert root.findtext("export/build_type") == "ament_cmake"
    used = set()  # the packages of the types the .msg files name with a package
    for name in NEMESYS_MESSAGES:
        for line in msg_text(name).splitlines():
            code = line.split("#")[0].split()
            if code and "/" in code[0]:
                used.add(code[0].split("/")[0])
    assert used == {"std_msgs"} and used <= texts("depend")


def test_an_exported_definition_is_the_msg_files_own_fields() -> None:
    """The definition written into an export lists the file's fields, in order, and then the
    types it uses."""
    for name in NEMESYS_MESSAGES:
        own = [
            line.split("#")[0].split()[1]
            for line in msg_text(name).splitlines()
            if line.split("#")[0].strip()
        ]
        text = definition(f"nemesys_msgs/msg/{name}").split("=" * 80)[0]
        assert [line.split()[1] for line in text.splitlines() if line.strip()] == own, name
    assert "MSG: nemesys_msgs/Command" in definition("nemesys_msgs/msg/Status")


COMMAND: dict[str, Any] = {
    "pattern": "circle",
    "params": {"speed": 0.18, "depth": 3.0, "radius": 5.0, "direction": "cw"},
}
ROW: dict[str, Any] = {
    "t_s": 12.5,
    "x_m": 1.0,
    "y_m": 2.0,
    "z_m": 3.0,
    "heading_deg": 30.0,
    "depth_m": 3.1,
    "speed_mps": 0.2,
    "battery_pct": 80.0,
    "mode": "running",
    "active": COMMAND,
    "commanded_depth_m": 3.0,
    "nav_valid": True,
    "nav_age_s": 0.1,
}
RECORD: dict[str, Any] = {
    "id": 3,
    "kind": "command",
    "pattern": "circle",
    "pattern_id": 3,
    "params": COMMAND["params"],
    "hex": "aaaa7c3121e5a0000008e1570",
    "state": "acknowledged",
}


@pytest.mark.parametrize(
    ("ros_type", "msg"),
    [
        ("nav_msgs/msg/Odometry", m.odometry(ROW)),
        ("sensor_msgs/msg/NavSatFix", m.nav_sat_fix(ROW, 43.0, 5.0)),
        ("nemesys_msgs/msg/Status", m.status(ROW)),
        ("nemesys_msgs/msg/Ack", m.ack({"outcome": "accepted", "command": COMMAND}, 1.0)),
        ("nemesys_msgs/msg/CommandRecord", m.command_record(RECORD, 2.0)),
        ("std_msgs/msg/UInt8MultiArray", m.frame(RECORD["hex"])),
        ("std_msgs/msg/String", m.json_string({"a": 1})),
    ],
)
def test_a_builder_fills_every_field_of_its_type(ros_type: str, msg: dict[str, Any]) -> None:
    """No field left to a writer's default (one writer would fill it silently, the other
    refuse), none too many: checked against the type store, recursively."""
    store = typestore()

    def check(type_name: str, value: dict[str, Any]) -> None:
        _, fields = store.fielddefs[type_name]
        assert set(value) == {name for name, _ in fields}, type_name
        for name, (node, detail) in fields:
            desc: Any = detail  # its shape depends on the node type
            if node == Nodetype.NAME:  # a nested message
                check(desc, value[name])
            elif node == Nodetype.SEQUENCE and desc[0][0] == Nodetype.NAME:
                for item in value[name]:
                    check(desc[0][1], item)

    check(ros_type, msg)
