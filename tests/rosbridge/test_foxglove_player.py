"""Foxglove's (Lichtblick's) rosbridge player against `nemesys sim`: a real websocket client
makes the player's calls and reads the answers as the player does.

The player (``RosbridgePlayer``, through roslibjs) calls ``/rosapi/topics_and_raw_types``,
takes ROS 2 when a type is ``rcl_interfaces/msg/Log``, parses every ``typedefs_full_text``,
and subscribes with ``compression: "cbor-raw"``; each binary frame is CBOR whose ``msg.bytes``
it reads as CDR with the parsed definition. Here the definitions are parsed by mcap_ros2
(Foxglove's Python ROS 2 reader) and rosbags, and the CDR decoded by both, against the pose a
JSON subscription gets at the same time stamp; a ``cbor`` subscription is checked the same way.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import cbor2
import pytest
from mcap_ros2._dynamic import generate_dynamic
from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from websockets.sync.client import ClientConnection, connect

from codec import encode_frame
from rosbridge.protocol import FRAME_TOPIC, MISSION_TOPIC, POSE_TOPIC
from tests.rosbridge.helpers import definition_sections
from tests.sim.sim_process import nemesys_sim

#: Against the player's calls and third-party decoders: the interop tier (make test).
pytestmark = pytest.mark.interop

FRAME = encode_frame("circle", speed=0.18, depth=2.5, radius=4, direction="cw").frame
POSE_TYPE = "geometry_msgs/msg/PoseStamped"


class Client:
    """One connection, speaking as roslibjs does: JSON text out; text in is JSON, binary
    in is CBOR."""

    def __init__(self, port: int) -> None:
        self.ws: ClientConnection = connect(f"ws://127.0.0.1:{port}/", max_size=None)
        self._ids = 0

    def send(self, message: dict[str, Any]) -> None:
        self.ws.send(json.dumps(message))

    def receive(self, timeout_s: float) -> tuple[bool, dict[str, Any]]:
        """``(binary?, message)``."""
        data = self.ws.recv(timeout=timeout_s)
        if isinstance(data, bytes):
            return True, dict(cbor2.loads(data))
        return False, dict(json.loads(data))

    def call(self, service: str, args: dict[str, Any] | None = None) -> dict[str, Any]:
        """``call_service`` as roslibjs sends it; the matching response."""
        self._ids += 1
        op_id = f"call_service:{service}:{self._ids}"
        self.send({"op": "call_service", "id": op_id, "service": service, "args": args or {}})
        deadline = time.monotonic() + 5.0
        while True:
            _, message = self.receive(max(0.01, deadline - time.monotonic()))
            if message.get("op") == "service_response" and message.get("id") == op_id:
                return message

    def subscribe(self, topic: str, compression: str = "none") -> None:
        """roslibjs's ``Topic.subscribe`` (Lichtblick's player gives no type)."""
        self._ids += 1
        self.send(
            {
                "op": "subscribe",
                "id": f"subscribe:{topic}:{self._ids}",
                "topic": topic,
                "compression": compression,
                "throttle_rate": 0,
                "queue_length": 0,
            }
        )

    def publications(self, topic: str, count: int, within_s: float) -> list[tuple[bool, Any]]:
        """The next ``count`` ``(binary?, msg)`` published on ``topic`` (fewer at the deadline)."""
        out: list[tuple[bool, Any]] = []
        deadline = time.monotonic() + within_s
        while len(out) < count and time.monotonic() < deadline:
            try:
                binary, message = self.receive(max(0.01, deadline - time.monotonic()))
            except TimeoutError:
                break
            if message.get("op") == "publish" and message.get("topic") == topic:
                out.append((binary, message["msg"]))
        return out

    def close(self) -> None:
        self.ws.close()


@pytest.fixture(scope="module")
def sim_port() -> Iterator[int]:
    """`nemesys sim` with the vehicle flying a circle (so successive poses differ)."""
    with nemesys_sim("--time-scale", "5", "--seed", "5") as port:
        client = Client(port)
        try:
            send_frame(client)
            assert client.publications(MISSION_TOPIC, 1, 5.0), "the frame was not acknowledged"
        finally:
            client.close()
        yield port


def send_frame(client: Client) -> None:
    client.subscribe(MISSION_TOPIC)
    client.send({"op": "advertise", "topic": FRAME_TOPIC, "type": "std_msgs/msg/UInt8MultiArray"})
    client.send({"op": "publish", "topic": FRAME_TOPIC, "msg": {"data": list(FRAME.to_bytes())}})


@pytest.fixture(scope="module")
def listing(sim_port: int) -> dict[str, Any]:
    """The player's first call, as it makes it."""
    client = Client(sim_port)
    try:
        reply = client.call("/rosapi/topics_and_raw_types")
    finally:
        client.close()
    assert reply["result"] is True, reply["values"]
    values: dict[str, Any] = reply["values"]
    return values


def parsed_fields(kind: str, text: str) -> dict[str, Any]:
    """rosbags' parse of a full definition: type -> its fields."""
    out: dict[str, Any] = {}
    for name, body in definition_sections(text):
        for parsed, (_, fields) in get_types_from_msg(body, name or kind).items():
            out[parsed] = fields
    return out


def assert_layout(kind: str, value: Any, fields: dict[str, Any], where: str) -> None:
    """The JSON ``value`` has exactly the fields the definition of ``kind`` gives, nested."""
    layout = fields[kind]
    assert isinstance(value, dict), where
    assert set(value) == {name for name, _ in layout}, (where, kind, sorted(value))
    for name, desc in layout:
        inner = desc[1][0] if desc[0] in (Nodetype.ARRAY, Nodetype.SEQUENCE) else desc
        if inner[0] != Nodetype.NAME:
            continue
        items = value[name] if inner is not desc else [value[name]]
        for item in items:
            assert_layout(inner[1], item, fields, f"{where}.{name}")


def test_topics_and_raw_types_parse_with_two_parsers(listing: dict[str, Any]) -> None:
    topics, types, texts = listing["topics"], listing["types"], listing["typedefs_full_text"]
    assert len(topics) == len(types) == len(texts)
    assert "rcl_interfaces/msg/Log" in types  # how the player tells ROS 2 from ROS 1
    assert dict(zip(topics, types, strict=True))[POSE_TOPIC] == POSE_TYPE
    for kind, text in zip(types, texts, strict=True):
        assert kind in generate_dynamic(kind, text), kind  # mcap_ros2: Foxglove's reader
        assert kind in parsed_fields(kind, text), kind  # rosbags


def test_every_published_message_has_the_fields_its_definition_gives(
    sim_port: int, listing: dict[str, Any]
) -> None:
    """Every topic the simulator publishes (all but ``/parameter_events``, which no node of
    it publishes), read in JSON, against the definition it gave for that topic."""
    kinds = dict(zip(listing["topics"], listing["types"], strict=True))
    texts = dict(zip(listing["topics"], listing["typedefs_full_text"], strict=True))
    wanted = set(kinds) - {"/parameter_events"}
    client = Client(sim_port)
    seen: dict[str, Any] = {}
    try:
        for topic in sorted(wanted):
            client.subscribe(topic)
        send_frame(client)  # the frame's echo and its acknowledgement
        deadline = time.monotonic() + 10.0
        while wanted - set(seen) and time.monotonic() < deadline:
            binary, message = client.receive(max(0.01, deadline - time.monotonic()))
            if message.get("op") == "publish":
                assert not binary
                seen.setdefault(message["topic"], message["msg"])
    finally:
        client.close()
    assert set(seen) == wanted
    for topic, msg in seen.items():
        fields = parsed_fields(kinds[topic], texts[topic])
        assert_layout(kinds[topic], msg, fields, topic)


def _poses(port: int, compression: str) -> list[tuple[bool, Any]]:
    client = Client(port)
    try:
        client.subscribe(POSE_TOPIC, compression)
        return client.publications(POSE_TOPIC, 40, 6.0)
    finally:
        client.close()


def _stamp(msg: dict[str, Any]) -> tuple[int, int]:
    stamp = msg["header"]["stamp"]
    return stamp["sec"], stamp["nanosec"]


def test_cbor_raw_and_cbor_poses_equal_the_json_ones(
    sim_port: int, listing: dict[str, Any]
) -> None:
    """Three players at once: JSON, ``cbor-raw`` (Foxglove's) and ``cbor``; each binary pose
    equals the JSON pose with the same time stamp."""
    with ThreadPoolExecutor(3) as pool:
        runs = {c: pool.submit(_poses, sim_port, c) for c in ("none", "cbor-raw", "cbor")}
        got = {c: run.result(30) for c, run in runs.items()}
    assert all(not binary for binary, _ in got["none"])
    assert all(binary for binary, _ in got["cbor-raw"] + got["cbor"])
    json_poses = {_stamp(msg): msg for _, msg in got["none"]}
    assert (
        len({(m["pose"]["position"]["x"], m["pose"]["position"]["y"]) for m in json_poses.values()})
        > 1
    )

    text = dict(zip(listing["topics"], listing["typedefs_full_text"], strict=True))[POSE_TOPIC]
    decode = generate_dynamic(POSE_TYPE, text)[POSE_TYPE]  # from the definition the sim gave
    store = get_typestore(Stores.ROS2_JAZZY)
    matched = 0
    for _, raw in got["cbor-raw"]:
        assert set(raw) == {"secs", "nsecs", "bytes"}
        assert isinstance(raw["secs"], int) and isinstance(raw["nsecs"], int)
        pose = decode(raw["bytes"])
        stamp = (pose.header.stamp.sec, pose.header.stamp.nanosec)
        other: Any = store.deserialize_cdr(raw["bytes"], POSE_TYPE)
        assert (other.header.stamp.sec, other.header.stamp.nanosec) == stamp
        assert other.pose.position.x == pose.pose.position.x
        if stamp not in json_poses:
            continue
        matched += 1
        expected = json_poses[stamp]
        assert pose.header.frame_id == expected["header"]["frame_id"]
        for part in ("position", "orientation"):
            for axis, value in expected["pose"][part].items():
                assert getattr(getattr(pose.pose, part), axis) == value, (stamp, part, axis)
    assert matched >= 5, (matched, len(got["cbor-raw"]), len(json_poses))

    matched = 0
    for _, msg in got["cbor"]:
        if _stamp(msg) in json_poses:
            matched += 1
            assert msg == json_poses[_stamp(msg)]
    assert matched >= 5, matched


def test_an_unknown_compression_gets_json_and_the_connection_goes_on(sim_port: int) -> None:
    client = Client(sim_port)
    try:
        client.subscribe(POSE_TOPIC, "zstd")
        poses = client.publications(POSE_TOPIC, 3, 5.0)
        assert len(poses) == 3 and not any(binary for binary, _ in poses)
        assert client.call("/rosapi/get_ros_version")["values"] == {"version": 2, "distro": "jazzy"}
    finally:
        client.close()
