"""``compression`` on subscriptions, without sockets, against the real ROS 2 rosbridge_server:
``cbor`` (the message's values in CBOR, typed arrays), ``cbor-raw`` (``{secs, nsecs, bytes}``
with the CDR), which subscription's compression wins, unknown values, fragments, and
messages that cannot be encoded (logged, never raised). The CDR is read back with
mcap_ros2's decoder (Foxglove's ROS 2 reader), not with the store that wrote it."""

from __future__ import annotations

import json
import math
import re
import struct
from typing import Any

import cbor2
import pytest
from mcap_ros2._dynamic import generate_dynamic

from rosbridge.compression import EncodeError, cbor_raw_publish, strongest, typed
from rosbridge.errors import JsonObject
from rosbridge.graph import Graph
from rosbridge.protocol import (
    FRAME_TOPIC,
    POSE_TOPIC,
    STATUS_TOPIC,
    ClientSession,
    Outcome,
    json_string_msg,
    pose_stamped_msg,
)
from rosbridge.typedefs import full_text
from vehicle_contract.endpoint import Pose

POSE = Pose(t_s=12.25, x_m=1.5, y_m=-2.0, z_m=3.0, heading_deg=60.0, roll_deg=0.0)


class Clocks:
    """The graph's monotonic clock and ROS time, set by the test."""

    def __init__(self) -> None:
        self.now = 100.0
        self.ros = 42.5


def new_session(clocks: Clocks | None = None, graph: Graph | None = None) -> ClientSession:
    c = clocks or Clocks()
    return ClientSession(graph=graph or Graph(clock=lambda: c.now, ros_time=lambda: c.ros))


def send(session: ClientSession, message: dict[str, Any]) -> Outcome:
    return session.receive_text(json.dumps(message))


def subscribe(session: ClientSession, topic: str, compression: str, **more: Any) -> Outcome:
    return send(session, {"op": "subscribe", "topic": topic, "compression": compression, **more})


def decode_cdr(kind: str, data: bytes) -> Any:
    return generate_dynamic(kind, full_text(kind))[kind](data)


def test_strongest_compression_wins() -> None:
    assert strongest([]) == "none"
    assert strongest(["none", "zip", ""]) == "none"
    assert strongest(["png", "none"]) == "png"
    assert strongest(["png", "cbor", "none"]) == "cbor"
    assert strongest(["cbor", "cbor-raw", "png"]) == "cbor-raw"


def test_cbor_is_the_json_message_in_cbor() -> None:
    session = new_session()
    assert subscribe(session, POSE_TOPIC, "cbor").logs[-1].text == f"Subscribed to {POSE_TOPIC}"
    msg = pose_stamped_msg(POSE)
    (frame,) = session.deliver(POSE_TOPIC, msg)
    assert isinstance(frame, bytes)
    assert cbor2.loads(frame) == {"op": "publish", "topic": POSE_TOPIC, "msg": msg}
    assert list(cbor2.loads(frame)) == ["op", "topic", "msg"]


def test_cbor_raw_is_the_cdr_stamped_with_the_bridges_ros_time() -> None:
    session = new_session()
    subscribe(session, POSE_TOPIC, "cbor-raw")
    (frame,) = session.deliver(POSE_TOPIC, pose_stamped_msg(POSE))
    assert isinstance(frame, bytes)
    message = cbor2.loads(frame)
    assert (message["op"], message["topic"]) == ("publish", POSE_TOPIC)
    assert (message["msg"]["secs"], message["msg"]["nsecs"]) == (42, 500_000_000)
    cdr = message["msg"]["bytes"]
    assert cdr[:4] == b"\x00\x01\x00\x00"  # little-endian CDR encapsulation, as rclpy's raw
    pose = decode_cdr("geometry_msgs/msg/PoseStamped", cdr)
    assert (pose.header.stamp.sec, pose.header.stamp.nanosec) == (12, 250_000_000)
    assert pose.header.frame_id == "map_ned"
    p, q = pose.pose.position, pose.pose.orientation
    assert (p.x, p.y, p.z) == (1.5, -2.0, 3.0)
    assert math.isclose(q.z, math.sin(math.radians(30.0)))
    assert math.isclose(q.w, math.cos(math.radians(30.0)))


def test_bytes_and_nan_in_each_form() -> None:
    """The frame echo: ``uint8[]`` is base64 in JSON, a byte string in CBOR, raw in CDR;
    a NaN is ``null`` in JSON and NaN in CBOR (as the real server's conversions)."""
    frame = bytes(range(13))
    graph = Graph()
    publisher, json_sub, cbor_sub, raw_sub = (new_session(graph=graph) for _ in range(4))
    subscribe(json_sub, FRAME_TOPIC, "none")
    subscribe(cbor_sub, FRAME_TOPIC, "cbor")
    subscribe(raw_sub, FRAME_TOPIC, "cbor-raw")
    published = send(
        publisher, {"op": "publish", "topic": FRAME_TOPIC, "msg": {"data": list(frame)}}
    )
    assert published.publication is not None
    msg = published.publication.msg
    (text,) = json_sub.deliver(FRAME_TOPIC, msg)
    assert isinstance(text, str) and json.loads(text)["msg"]["data"] == "AAECAwQFBgcICQoLDA=="
    (binary,) = cbor_sub.deliver(FRAME_TOPIC, msg)
    assert isinstance(binary, bytes)
    assert cbor2.loads(binary)["msg"] == {"layout": {"dim": [], "data_offset": 0}, "data": frame}
    (raw,) = raw_sub.deliver(FRAME_TOPIC, msg)
    assert isinstance(raw, bytes)
    decoded = decode_cdr("std_msgs/msg/UInt8MultiArray", cbor2.loads(raw)["msg"]["bytes"])
    assert bytes(decoded.data) == frame

    nan_pose = pose_stamped_msg(POSE)
    nan_pose["pose"]["position"]["x"] = None  # a NaN, as the JSON form holds it
    subscribe(cbor_sub, POSE_TOPIC, "cbor")
    (binary,) = cbor_sub.deliver(POSE_TOPIC, nan_pose)
    assert isinstance(binary, bytes)
    assert math.isnan(cbor2.loads(binary)["msg"]["pose"]["position"]["x"])


def test_numeric_arrays_are_typed_arrays() -> None:
    """A type the simulator does not lay out but the store defines (a client's
    ``std_msgs/Float64MultiArray``): ``cbor`` gives RFC 8746 tags, little-endian."""
    graph = Graph()
    publisher, sub = new_session(graph=graph), new_session(graph=graph)
    topic, kind = "/arrays", "std_msgs/msg/Float64MultiArray"
    send(publisher, {"op": "advertise", "topic": topic, "type": kind})
    subscribe(sub, topic, "cbor")
    msg: JsonObject = {"layout": {"dim": [], "data_offset": 0}, "data": [1.5, -2.0]}
    out = send(publisher, {"op": "publish", "topic": topic, "msg": msg})
    assert out.publication is not None
    (binary,) = sub.deliver(topic, out.publication.msg)
    assert isinstance(binary, bytes)
    data = cbor2.loads(binary)["msg"]["data"]
    assert isinstance(data, cbor2.CBORTag) and data.tag == 86
    assert struct.unpack("<2d", data.value) == (1.5, -2.0)
    ints = typed("std_msgs/msg/Int16MultiArray", {"data": [1, -2]})
    assert list(ints.data) == [1, -2]


def test_unknown_compression_is_json_and_png_is_logged() -> None:
    """The real server sends JSON for any value it does not know, and logs nothing; png
    (not implemented here) is logged and sent as JSON."""
    session = new_session()
    out = subscribe(session, STATUS_TOPIC, "zip")
    assert [line.text for line in out.logs] == [f"Subscribed to {STATUS_TOPIC}"]
    (text,) = session.deliver(STATUS_TOPIC, json_string_msg({"a": 1}))
    assert isinstance(text, str) and json.loads(text)["msg"] == {"data": '{"a":1}'}
    png = subscribe(new_session(), STATUS_TOPIC, "png")
    assert "'png' is not implemented" in png.logs[-1].text
    bad = subscribe(new_session(), STATUS_TOPIC, 5)  # type: ignore[arg-type]
    assert bad.dropped and "compression" in bad.logs[0].text


def test_the_strongest_of_a_clients_subscriptions_applies_until_it_leaves() -> None:
    session = new_session()
    subscribe(session, STATUS_TOPIC, "none", id="a")
    subscribe(session, STATUS_TOPIC, "cbor-raw", id="b")
    (frame,) = session.deliver(STATUS_TOPIC, json_string_msg({"a": 1}))
    assert isinstance(frame, bytes)
    send(session, {"op": "unsubscribe", "topic": STATUS_TOPIC, "id": "b"})
    (text,) = session.deliver(STATUS_TOPIC, json_string_msg({"a": 2}))
    assert isinstance(text, str)


def test_a_latched_message_goes_out_compressed() -> None:
    graph = Graph()
    publisher = new_session(graph=graph)
    send(
        publisher, {"op": "advertise", "topic": "/latched", "type": "std_msgs/Int32", "latch": True}
    )
    send(publisher, {"op": "publish", "topic": "/latched", "msg": {"data": 7}})
    out = subscribe(new_session(graph=graph), "/latched", "cbor")
    (binary,) = out.texts
    assert isinstance(binary, bytes) and cbor2.loads(binary)["msg"] == {"data": 7}


def test_a_queued_message_is_encoded_when_it_goes_out() -> None:
    """With ``queue_length`` the real server stamps ``secs``/``nsecs`` when it sends."""
    clocks = Clocks()
    session = new_session(clocks)
    subscribe(session, STATUS_TOPIC, "cbor-raw", throttle_rate=1000, queue_length=1)
    assert len(session.deliver(STATUS_TOPIC, json_string_msg(1))) == 1
    assert session.deliver(STATUS_TOPIC, json_string_msg(2)) == []
    clocks.now, clocks.ros = 101.5, 50.0
    (frame,) = session.poll()
    assert isinstance(frame, bytes)
    message = cbor2.loads(frame)["msg"]
    assert message["secs"] == 50
    assert decode_cdr("std_msgs/msg/String", message["bytes"]).data == "2"


def test_a_cbor_message_longer_than_fragment_size_is_logged_not_sent() -> None:
    """The real server cannot fragment CBOR: its send fails, and it logs the failure."""
    session = new_session()
    subscribe(session, POSE_TOPIC, "cbor-raw", fragment_size=50)
    assert session.deliver(POSE_TOPIC, pose_stamped_msg(POSE)) == []
    (line,) = session.drain_logs()
    assert (
        line.text == "Exception calling subscribe callback: 'bytes' object has no attribute 'get'"
    )
    json_session = new_session()
    subscribe(json_session, POSE_TOPIC, "none", fragment_size=50)
    assert len(json_session.deliver(POSE_TOPIC, pose_stamped_msg(POSE))) > 1  # JSON: fragments


def test_cbor_of_a_type_without_a_definition_carries_the_values_as_relayed() -> None:
    """The simulator relays a type it cannot lay out as sent; ``cbor`` sends those values
    (``cbor-raw`` cannot: it needs the definition, below)."""
    session = new_session()
    kind, msg = "example_interfaces/msg/Nothing", {"x": [1, 2], "s": "a"}
    send(session, {"op": "subscribe", "topic": "/t", "type": kind, "compression": "cbor"})
    (binary,) = session.deliver("/t", msg)
    assert isinstance(binary, bytes) and cbor2.loads(binary)["msg"] == msg


@pytest.mark.parametrize(
    ("kind", "msg", "words"),
    [
        ("example_interfaces/msg/Nothing", {"x": 1}, "no definition of example_interfaces"),
        ("std_msgs/msg/Int32", {"data": "seven"}, "std_msgs/msg/Int32"),
        ("std_msgs/msg/UInt8", {"data": 300}, "std_msgs/msg/UInt8"),
    ],
)
def test_a_message_that_cannot_be_encoded_is_logged(kind: str, msg: JsonObject, words: str) -> None:
    """Relayed messages the simulator does not check (a type it does not lay out) can fail to
    encode: the subscriber gets nothing, the server logs it, nothing is raised."""
    session = new_session()
    send(session, {"op": "subscribe", "topic": "/t", "type": kind, "compression": "cbor-raw"})
    assert session.deliver("/t", msg) == []
    (line,) = session.drain_logs()
    assert line.text.startswith("Exception calling subscribe callback: ") and words in line.text
    with pytest.raises(EncodeError, match=re.escape(words)):
        cbor_raw_publish("/t", kind, msg, 0.0)
