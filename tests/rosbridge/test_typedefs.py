"""Full message definitions (``/rosapi/topics_and_raw_types``): rosapi's layout and order,
every type the simulator's graph lists parsed by two parsers that are not ours (mcap_ros2's
vendored ``rosidl_adapter`` and rosbags' ``.msg`` parser), and the JSON layouts the bridge
publishes agreeing with the definitions it gives."""

from __future__ import annotations

import json
from typing import Any

import pytest
from mcap_ros2._dynamic import generate_dynamic
from rosbags.typesys import get_types_from_msg

from rosbridge.graph import Graph
from rosbridge.protocol import ClientSession
from rosbridge.typedefs import full_text, msg_text
from rosbridge.types import MESSAGE_FIELDS
from tests.rosbridge.helpers import definition_sections as sections


def graph_listing() -> dict[str, Any]:
    """``topics_and_raw_types`` as a client gets it from a session of the simulator."""
    session = ClientSession(graph=Graph(clock=lambda: 0.0))
    message = {"op": "call_service", "id": 1, "service": "/rosapi/topics_and_raw_types"}
    (reply,) = session.receive_text(json.dumps(message)).replies
    assert reply["result"] is True
    values: dict[str, Any] = reply["values"]
    return values


def test_every_listed_topic_has_a_definition_two_parsers_read() -> None:
    listing = graph_listing()
    assert len(listing["topics"]) == len(listing["types"]) == len(listing["typedefs_full_text"])
    assert "rcl_interfaces/msg/Log" in listing["types"]  # how Foxglove tells ROS 2
    for kind, text in zip(listing["types"], listing["typedefs_full_text"], strict=True):
        assert not text.startswith("#"), text
        decoders = generate_dynamic(kind, text)  # mcap_ros2 (Foxglove's ROS 2 reader)
        assert kind in decoders
        for name, body in sections(text):
            parsed = get_types_from_msg(body, name or kind)  # rosbags' .msg parser
            assert parsed, (kind, name)


def _field_names(kind: str, text: str) -> dict[str, list[str]]:
    """Each type's field names, as rosbags parses the full text."""
    out: dict[str, list[str]] = {}
    for name, body in sections(text):
        full = name or kind
        for parsed_name, (_, fields) in get_types_from_msg(body, full).items():
            out[parsed_name] = [field for field, _ in fields]
    return out


def test_the_json_layouts_the_bridge_publishes_match_the_definitions() -> None:
    for kind, layout in MESSAGE_FIELDS.items():
        names = _field_names(kind, full_text(kind))
        assert names[kind] == [name for name, _ in layout], kind


def test_rosapi_order_and_separators() -> None:
    """Root first; then the types used, last found first (rosapi pops them off a stack)."""
    text = full_text("geometry_msgs/msg/PoseStamped")
    assert [name for name, _ in sections(text)] == [
        None,
        "geometry_msgs/Pose",
        "geometry_msgs/Quaternion",
        "geometry_msgs/Point",
        "std_msgs/Header",
        "builtin_interfaces/Time",
    ]
    assert text.startswith("std_msgs/Header header\ngeometry_msgs/Pose pose\n\n=====")
    assert text.count("\n" + "=" * 80 + "\n") == 5
    assert text.endswith("int32 sec\nuint32 nanosec\n")
    assert full_text("geometry_msgs/PoseStamped") == text  # either spelling


def test_each_type_once_and_constants_kept() -> None:
    text = full_text("rcl_interfaces/msg/ParameterEvent")
    names = [name for name, _ in sections(text)]
    assert len(names) == len(set(names))
    assert "byte[] byte_array_value" in text
    log = msg_text("rcl_interfaces/msg/Log")
    assert log.startswith("uint8 DEBUG=10\nuint8 INFO=20\n")
    assert "builtin_interfaces/Time stamp\nuint8 level\n" in log


def test_rosbridge_msgs_are_defined() -> None:
    """/connected_clients is the simulator's too; rosbags does not ship rosbridge_msgs."""
    text = full_text("rosbridge_msgs/msg/ConnectedClients")
    assert [name for name, _ in sections(text)] == [
        None,
        "rosbridge_msgs/ConnectedClient",
        "builtin_interfaces/Time",
    ]
    generate_dynamic("rosbridge_msgs/msg/ConnectedClients", text)


@pytest.mark.parametrize("kind", ["example_interfaces/msg/Nothing", "not a type"])
def test_a_type_without_a_definition_gets_rosapis_failure_line(kind: str) -> None:
    text = full_text(kind)
    assert text.startswith(f"# failed to get full definition text for {kind}: ")
    assert "\n" not in text
