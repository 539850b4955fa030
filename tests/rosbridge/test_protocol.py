"""The rosbridge v2 protocol layer without sockets: parsing, the input buffer, message types
and conversion, outgoing messages and fragments, and the client side. The session (rosapi,
pacing, fragments in) is tests/rosbridge/test_session.py."""

from __future__ import annotations

import base64
import json
import math
from typing import Any

import pytest

from rosbridge.client import ClientProtocol, decode_json_string, decode_server_message
from rosbridge.flow import NOTHING
from rosbridge.protocol import (
    FRAME_TOPIC,
    MISSION_TOPIC,
    OP_PARSERS,
    POSE_STAMPED_TYPE,
    POSE_TOPIC,
    ROS2_TOPIC_TYPES,
    STATUS_TOPIC,
    STRING_TYPE,
    TOPIC_TYPES,
    UINT8_MULTIARRAY_TYPE,
    UNSUPPORTED_OPS,
    Advertise,
    BinaryMessage,
    CallService,
    ClientSession,
    Fragment,
    FragmentError,
    IncomingBuffer,
    InvalidData,
    InvalidType,
    MalformedMessage,
    Publish,
    Subscribe,
    TypeMismatch,
    Unadvertise,
    Unimplemented,
    UnknownOp,
    Unsubscribe,
    canonical_type,
    decode_uint8_data,
    decode_uint8_multiarray,
    extract,
    fragments,
    json_string_msg,
    log_msg,
    parse_message,
    populate,
    publish_message,
    resolve_type,
    ros2_type,
    same_type,
    service_response,
    string_msg,
    to_json,
    uint8_multiarray_msg,
    wire_json,
)
from tests.rosbridge.helpers import EXAMPLE
from vehicle_contract import contract
from vehicle_contract.endpoint import FRAME_BYTES

# ------------------------------------------------------------------------------------------
# Topics and type names
# ------------------------------------------------------------------------------------------


def test_topic_tables_come_from_the_contract() -> None:
    assert dict(ROS2_TOPIC_TYPES) == contract.TOPIC_TYPES
    assert dict(TOPIC_TYPES) == {
        "/nemesys/frame": "std_msgs/UInt8MultiArray",
        "/nemesys/pose": "geometry_msgs/PoseStamped",
        "/nemesys/mission": "std_msgs/String",
        "/nemesys/status": "std_msgs/String",
        "/nemesys/datum": "std_msgs/String",
    }
    assert tuple(contract.TOPIC_TYPES) == (
        FRAME_TOPIC,
        POSE_TOPIC,
        MISSION_TOPIC,
        STATUS_TOPIC,
        contract.DATUM_TOPIC,
    )
    assert len(EXAMPLE) == FRAME_BYTES


@pytest.mark.parametrize(
    ("name", "canonical"),
    [
        ("std_msgs/msg/UInt8MultiArray", UINT8_MULTIARRAY_TYPE),
        ("std_msgs/UInt8MultiArray", UINT8_MULTIARRAY_TYPE),
        ("std_msgs/msg/String", STRING_TYPE),
        ("geometry_msgs/msg/PoseStamped", POSE_STAMPED_TYPE),
        (" geometry_msgs/PoseStamped ", POSE_STAMPED_TYPE),
        ("std_msgs/srv/String", "std_msgs/srv/String"),
        ("String", "String"),
        ("std_msgs//String", "std_msgs//String"),
    ],
)
def test_canonical_type(name: str, canonical: str) -> None:
    assert canonical_type(name) == canonical


def test_same_type_and_ros2_type() -> None:
    assert same_type("std_msgs/msg/String", "std_msgs/String")
    assert not same_type("std_msgs/String", "std_msgs/UInt8MultiArray")
    assert ros2_type("std_msgs/String") == "std_msgs/msg/String"
    assert ros2_type("std_msgs/msg/String") == "std_msgs/msg/String"


@pytest.mark.parametrize(
    ("name", "resolved"),
    [
        ("std_msgs/String", "std_msgs/msg/String"),
        ("std_msgs/msg/String", "std_msgs/msg/String"),
        ("std_msgs/srv/String", "std_msgs/msg/String"),  # the real loader falls back to msg
        ("/std_msgs//String/", "std_msgs/msg/String"),  # empty parts are dropped
        ("sensor_msgs/Imu", "sensor_msgs/msg/Imu"),  # not laid out, but a standard package
        ("rosbridge_msgs/msg/ConnectedClients", "rosbridge_msgs/msg/ConnectedClients"),
    ],
)
def test_resolve_type(name: str, resolved: str) -> None:
    assert resolve_type(name) == resolved


@pytest.mark.parametrize(
    ("name", "words"),
    [
        ("String", "String is not a valid type string"),
        ("a/b/c/d", "a/b/c/d is not a valid type string"),
        ("std_msg/String", "Unable to import std_msg.msg from package std_msg"),
        ("std_msgs/Strin", "Unable to import msg class Strin from package std_msgs"),
    ],
)
def test_resolve_type_errors(name: str, words: str) -> None:
    with pytest.raises(InvalidType, match=words):
        resolve_type(name)


# ------------------------------------------------------------------------------------------
# Parsing: the op table and each op's field checks, worded as the real server words them
# ------------------------------------------------------------------------------------------


def test_op_table_is_the_ros2_servers() -> None:
    assert list(OP_PARSERS) == [
        "advertise",
        "unadvertise",
        "publish",
        "subscribe",
        "unsubscribe",
        "fragment",
        "advertise_service",
        "call_service",
        "service_response",
        "unadvertise_service",
        "advertise_action",
        "action_feedback",
        "action_result",
        "send_action_goal",
        "cancel_action_goal",
        "unadvertise_action",
    ]
    assert "set_level" not in OP_PARSERS and "status" not in OP_PARSERS
    assert (
        set(OP_PARSERS)
        - {
            "advertise",
            "unadvertise",
            "publish",
            "subscribe",
            "unsubscribe",
            "fragment",
            "call_service",
        }
        == UNSUPPORTED_OPS
    )


def test_parse_roslibpy_wire_messages() -> None:
    """The exact messages roslibpy 2.1.0 sends."""
    assert parse_message(
        '{"op":"advertise","id":"advertise:/nemesys/frame:1","type":"std_msgs/UInt8MultiArray",'
        '"topic":"/nemesys/frame","latch":false,"queue_size":100}'
    ) == Advertise(FRAME_TOPIC, UINT8_MULTIARRAY_TYPE, "advertise:/nemesys/frame:1")
    publish = parse_message(
        '{"op":"publish","id":"publish:/nemesys/frame:2","topic":"/nemesys/frame",'
        '"msg":{"data":[1,2,3]},"latch":false}'
    )
    assert publish == Publish(FRAME_TOPIC, {"data": [1, 2, 3]}, "publish:/nemesys/frame:2")
    assert parse_message(
        '{"op":"subscribe","id":"subscribe:/nemesys/pose:3","type":"geometry_msgs/PoseStamped",'
        '"topic":"/nemesys/pose","compression":"none","throttle_rate":1000,"queue_length":2}'
    ) == Subscribe(POSE_TOPIC, POSE_STAMPED_TYPE, "subscribe:/nemesys/pose:3", 1000, 2)
    assert parse_message(
        '{"op":"call_service","id":"c:4","service":"/rosapi/topics","args":{}}'
    ) == CallService("/rosapi/topics", {}, "c:4")
    assert parse_message('{"op":"unsubscribe","id":"s","topic":"/nemesys/pose"}') == (
        Unsubscribe(POSE_TOPIC, "s")
    )
    assert parse_message('{"op":"unadvertise","topic":"/nemesys/frame"}') == (
        Unadvertise(FRAME_TOPIC)
    )
    assert parse_message('{"op":"fragment","id":"m","num":0,"total":2,"data":"{"}') == (
        Fragment("m", 0, 2, "{")
    )
    assert parse_message('{"op":"advertise_service","id":7}') == Unimplemented(
        "advertise_service", 7
    )


def test_parse_defaults() -> None:
    assert parse_message('{"op":"subscribe","topic":"/x"}') == Subscribe("/x")
    assert parse_message('{"op":"publish","topic":"/x"}') == Publish("/x", {})
    assert parse_message('{"op":"call_service","service":"/s"}') == CallService("/s", [])
    assert parse_message('{"op":"call_service","service":"/s","args":"?"}') == CallService(
        "/s", "?"
    )
    assert parse_message('{"op":"advertise","topic":"/x","type":"t","latch":true}') == (
        Advertise("/x", "t", latch=True)
    )


@pytest.mark.parametrize(
    ("text", "error", "words"),
    [
        ("{}", UnknownOp, "Received a message without an op."),
        ('{"receiver": "/x"}', UnknownOp, "rosbridge v1.0 message"),
        ("[1, 2]", UnknownOp, "without an op"),
        ('{"op": "set_level", "level": "error"}', UnknownOp, "Unknown operation: set_level."),
        ('{"op": "status", "level": "error"}', UnknownOp, "Unknown operation: status."),
        ('{"op": "auth"}', UnknownOp, "Unknown operation: auth."),
        ('{"op": 3}', UnknownOp, "Unknown operation: 3."),
        ('{"op": "advertise", "topic": "/x"}', MalformedMessage, "Expected a type field"),
        ('{"op": "advertise", "topic": 5, "type": "x"}', MalformedMessage, "field topic"),
        ('{"op": "unadvertise"}', MalformedMessage, "Expected a topic field"),
        ('{"op": "publish", "msg": {}}', MalformedMessage, "Expected a topic field"),
        ('{"op": "subscribe", "topic": "/a", "type": 1}', MalformedMessage, "field type"),
        (
            '{"op": "subscribe", "topic": "/a", "throttle_rate": 1000.0}',
            MalformedMessage,
            "Expected field throttle_rate to be one of (<class 'int'>,). Invalid value: 1000.0",
        ),
        ('{"op": "subscribe", "topic": "/a", "queue_length": "1"}', MalformedMessage, "queue"),
        ('{"op": "subscribe", "topic": "/a", "compression": 1}', MalformedMessage, "compr"),
        ('{"op": "unsubscribe", "id": "s"}', MalformedMessage, "Expected a topic field"),
        ('{"op": "call_service"}', MalformedMessage, "Expected a service field"),
        (
            '{"op": "call_service", "service": "/s", "fragment_size": "x"}',
            MalformedMessage,
            "(<class 'int'>, <class 'NoneType'>)",
        ),
    ],
)
def test_parse_errors(text: str, error: type[Exception], words: str) -> None:
    with pytest.raises(error) as caught:
        parse_message(text)
    assert type(caught.value) is error
    assert words in str(caught.value)


def test_parse_errors_name_the_op_and_keep_the_id() -> None:
    with pytest.raises(MalformedMessage) as caught:
        parse_message('{"op": "publish", "id": [1], "msg": {}}')
    assert caught.value.reason.startswith("publish: Expected a topic field")
    assert caught.value.op_id == [1]  # any JSON id, as the real server takes it
    with pytest.raises(UnknownOp) as unknown:
        parse_message('{"op": "fly", "id": "f1"}')
    assert unknown.value.op_id == "f1"
    with pytest.raises(MalformedMessage, match="not valid JSON"):
        parse_message("{")


# ------------------------------------------------------------------------------------------
# The input buffer (the real server's Protocol.incoming)
# ------------------------------------------------------------------------------------------


def take_all(buffer: IncomingBuffer) -> list[Any]:
    """As the session takes them: after a message without an op the real server stops."""
    out = []
    while (value := buffer.take()) is not NOTHING:
        out.append(value)
        if not isinstance(value, dict) or "op" not in value or not buffer.more():
            break
    return out


def test_buffer_whole_text_and_several_objects() -> None:
    buffer = IncomingBuffer(limit=1000)
    buffer.add('{"op": "a"}')
    assert take_all(buffer) == [{"op": "a"}] and buffer.buffer == ""
    buffer.add('{"op": "a"}{"op": "b"} {"op": "c"}')
    assert take_all(buffer) == [{"op": "a"}, {"op": "b"}, {"op": "c"}]
    buffer.add("[1, 2]")  # JSON that is not an object is taken too (and refused later)
    assert take_all(buffer) == [[1, 2]]


def test_buffer_joins_a_message_split_over_two_texts_and_skips_garbage() -> None:
    buffer = IncomingBuffer(limit=1000)
    buffer.add('{"op": "subscribe", ')
    assert buffer.take() is NOTHING
    buffer.add('"topic": "/x"}')
    assert take_all(buffer) == [{"op": "subscribe", "topic": "/x"}]
    buffer.add("this is not json")
    assert buffer.take() is NOTHING
    buffer.add('{"op": "b"}')
    assert take_all(buffer) == [{"op": "b"}]
    assert buffer.buffer == ""


def test_buffer_keeps_garbage_in_front_of_an_object_without_op() -> None:
    """The real server's quirk: such a text poisons the connection's later messages."""
    buffer = IncomingBuffer(limit=1000)
    buffer.add('xx{"a": 1}')
    assert take_all(buffer) == [{"a": 1}]
    buffer.add('{"op": "subscribe", "topic": "/x"}')
    assert take_all(buffer) == [{"a": 1}]


def test_buffer_is_bounded() -> None:
    buffer = IncomingBuffer(limit=10)
    buffer.add("x" * 8)
    assert buffer.take() is NOTHING and not buffer.overflowed
    buffer.add('{"op": 1}')  # the leftover would pass 10 characters: dropped
    assert buffer.overflowed
    assert take_all(buffer) == [{"op": 1}]
    buffer.add("{" * 200 + '{"op": "late"}')  # beyond the first 64 braces: not searched
    assert buffer.take() is NOTHING


# ------------------------------------------------------------------------------------------
# uint8[] and message conversion (the real server's message_conversion)
# ------------------------------------------------------------------------------------------


def test_uint8_data_list_and_base64() -> None:
    assert decode_uint8_data(list(EXAMPLE)) == EXAMPLE
    assert decode_uint8_data(base64.b64encode(EXAMPLE).decode()) == EXAMPLE
    assert decode_uint8_data("qqp8EyFHMAAACJFWAA==") == EXAMPLE
    assert decode_uint8_data("qqp8EyFHMAAA CJFWAA==\n") == EXAMPLE  # lenient, as the real one
    assert decode_uint8_data([True, False, 255]) == b"\x01\x00\xff"  # booleans are ints there
    assert decode_uint8_data([]) == b"" == decode_uint8_data("")


@pytest.mark.parametrize(
    ("data", "words"),
    [
        ([1, 256], "data[1] = 256"),
        ([-1], "data[0] = -1"),
        ([1.0], "data[0] = 1.0"),
        (["1"], "data[0] = '1'"),
        ([None], "data[0] = None"),
        ("qqp8EyFHMAAACJFWAA=", "base64"),
        ("hello world", "base64"),
        ("é===", "base64"),
        ({"0": 1}, "<class 'dict'>"),
        (5, "<class 'int'>"),
        (None, "<class 'NoneType'>"),
    ],
)
def test_uint8_data_rejected(data: object, words: str) -> None:
    with pytest.raises(InvalidData) as caught:
        decode_uint8_data(data, "id9")
    assert words in caught.value.reason
    assert caught.value.op_id == "id9"


def test_uint8_multiarray() -> None:
    assert decode_uint8_multiarray({"data": [1, 2]}) == b"\x01\x02"
    assert decode_uint8_multiarray({}) == b""  # missing fields take their defaults
    assert decode_uint8_multiarray(uint8_multiarray_msg(EXAMPLE)) == EXAMPLE
    with pytest.raises(TypeMismatch, match="does not have a field header") as caught:
        decode_uint8_multiarray({"header": {}, "pose": {}}, "p")
    assert (
        caught.value.reason == "Message type std_msgs/UInt8MultiArray does not have a field header"
    )
    assert caught.value.op_id == "p"
    with pytest.raises(TypeMismatch, match="requires a std_msgs/MultiArrayLayout for field layout"):
        decode_uint8_multiarray({"layout": [], "data": [1]})
    with pytest.raises(TypeMismatch, match="Expected a JSON object for type std_msgs/UInt8Multi"):
        decode_uint8_multiarray([1, 2])


def test_populate_fills_defaults_and_checks_fields() -> None:
    pose = populate("geometry_msgs/msg/PoseStamped", {"pose": {"position": {"x": 1}}}, 12.5)
    assert pose == {
        "header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""},
        "pose": {
            "position": {"x": 1.0, "y": 0.0, "z": 0.0},
            "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
        },
    }
    # A header that is sent gets the time now (ROS time), unless its stamp is given.
    now = populate("geometry_msgs/msg/PoseStamped", {"header": {}}, 12.5)
    assert now["header"]["stamp"] == {"sec": 12, "nanosec": 500_000_000}
    stamped = populate(
        "geometry_msgs/msg/PoseStamped", {"header": {"stamp": {"secs": 3, "nsecs": 4}}}, 12.5
    )
    assert stamped["header"]["stamp"] == {"sec": 3, "nanosec": 4}
    assert populate("std_msgs/msg/Int32", {"data": -5}) == {"data": -5}
    assert populate("sensor_msgs/msg/Imu", {"anything": 1}) == {"anything": 1}  # not laid out
    with pytest.raises(TypeMismatch, match=r"does not have a field pose\.position\.q"):
        populate("geometry_msgs/msg/PoseStamped", {"pose": {"position": {"q": 1}}})
    with pytest.raises(
        TypeMismatch, match=r"requires a double for field pose\.position\.x, but got"
    ):
        populate("geometry_msgs/msg/PoseStamped", {"pose": {"position": {"x": "1"}}})
    with pytest.raises(TypeMismatch, match=r"must be an integer in \[-2147483648, 2147483647\]"):
        populate("std_msgs/msg/Int32", {"data": 2**31})
    with pytest.raises(TypeMismatch, match="requires a int32 for field data, but got a <class 'bo"):
        populate("std_msgs/msg/Int32", {"data": True})
    with pytest.raises(TypeMismatch, match="requires a string for field data"):
        populate("std_msgs/msg/String", {"data": 5})


def test_extract_sends_bytes_as_base64_and_nan_as_null() -> None:
    message = populate("std_msgs/msg/UInt8MultiArray", {"data": [1, 2, 255]})
    assert extract("std_msgs/msg/UInt8MultiArray", message) == {
        "layout": {"dim": [], "data_offset": 0},
        "data": "AQL/",
    }
    point = {"x": math.nan, "y": math.inf, "z": 1.5}
    assert extract("geometry_msgs/msg/Point", point) == {"x": None, "y": None, "z": 1.5}


# ------------------------------------------------------------------------------------------
# Outgoing messages, fragments (the pose, the stamps and to_json: tests/vehicle_contract)
# ------------------------------------------------------------------------------------------


def test_builders() -> None:
    assert publish_message(MISSION_TOPIC, string_msg('{"seq":1}')) == {
        "op": "publish",
        "topic": "/nemesys/mission",
        "msg": {"data": '{"seq":1}'},
    }
    assert uint8_multiarray_msg(b"\x01\xff") == {
        "layout": {"dim": [], "data_offset": 0},
        "data": "Af8=",
    }
    ok = service_response("/rosapi/topics", {"topics": []}, True, "c1")
    assert ok == {
        "op": "service_response",
        "service": "/rosapi/topics",
        "values": {"topics": []},
        "result": True,
        "id": "c1",
    }
    failed = service_response("/nope", "no such service", False)
    assert failed["values"] == "no such service" and failed["result"] is False
    assert "id" not in failed
    assert json_string_msg({"seq": 1, "ber": math.nan}) == {"data": '{"seq":1,"ber":null}'}
    log = log_msg(2.5, 40, "rosbridge_websocket", "boom")
    assert log["stamp"] == {"sec": 2, "nanosec": 500_000_000} and log["level"] == 40
    assert set(log) == {"stamp", "level", "name", "msg", "file", "function", "line"}


def test_to_json_is_compact_and_wire_json_is_the_real_servers() -> None:
    text = to_json({"a": math.nan, "b": [math.inf, 1.5], "c": {"d": -math.inf}, "e": (1, 2)})
    assert text == '{"a":null,"b":[null,1.5],"c":{"d":null},"e":[1,2]}'
    assert wire_json({"op": "publish", "msg": {"x": math.nan}}) == (
        '{"op": "publish", "msg": {"x": null}}'
    )


def test_fragments_as_the_real_server_sends_them() -> None:
    text = wire_json(publish_message(STATUS_TOPIC, {"data": "x" * 30}))
    assert fragments(text, None) == (text,)
    assert fragments(text, len(text)) == (text,)
    parts = [json.loads(f) for f in fragments(text, 20)]
    n = len(text)
    assert [p["num"] for p in parts] == list(range(math.ceil(n / 20)))
    assert all(p["op"] == "fragment" and p["id"] == 0 for p in parts)  # no id: 0
    assert all(p["total"] == (n - 1) / 20 + 1 for p in parts)  # a float, as the real one
    assert isinstance(parts[0]["total"], float)
    assert "".join(p["data"] for p in parts) == text
    assert all(len(p["data"]) <= 20 for p in parts)
    assert {json.loads(f)["id"] for f in fragments(text, 20, "call-7")} == {"call-7"}
    assert list(json.loads(fragments(text, 20)[0])) == ["op", "id", "data", "num", "total"]


@pytest.mark.parametrize(
    ("size", "words"),
    [("10", "'>' not supported"), (10.5, "'float'"), (0, "sends nothing"), (-3, "sends nothing")],
)
def test_fragment_sizes_the_real_server_cannot_use(size: object, words: str) -> None:
    with pytest.raises(FragmentError, match=words):
        fragments("x" * 100, size)


# ------------------------------------------------------------------------------------------
# Client side: what the transmitter and the console's link send and read
# ------------------------------------------------------------------------------------------


def test_client_protocol_messages_are_roslibpys() -> None:
    client = ClientProtocol(advertise=[FRAME_TOPIC], subscribe=[POSE_TOPIC, MISSION_TOPIC])
    opening = [json.loads(text) for text in client.open_messages()]
    assert opening == [
        {
            "op": "advertise",
            "id": "advertise:/nemesys/frame:1",
            "type": "std_msgs/UInt8MultiArray",
            "topic": "/nemesys/frame",
            "latch": False,
            "queue_size": 100,
        },
        {
            "op": "subscribe",
            "id": "subscribe:/nemesys/pose:2",
            "type": "geometry_msgs/PoseStamped",
            "topic": "/nemesys/pose",
            "compression": "none",
            "throttle_rate": 0,
            "queue_length": 0,
        },
        {
            "op": "subscribe",
            "id": "subscribe:/nemesys/mission:3",
            "type": "std_msgs/String",
            "topic": "/nemesys/mission",
            "compression": "none",
            "throttle_rate": 0,
            "queue_length": 0,
        },
    ]
    assert json.loads(client.publish(FRAME_TOPIC, {"data": [1, 2]})) == {
        "op": "publish",
        "id": "publish:/nemesys/frame:4",
        "topic": "/nemesys/frame",
        "msg": {"data": [1, 2]},
        "latch": False,
    }
    assert json.loads(client.publish(FRAME_TOPIC, {"data": []}))["id"] == "publish:/nemesys/frame:5"
    # Every connection opens with the same ids, and closes with them.
    assert [json.loads(text) for text in client.open_messages()] == opening
    assert [json.loads(text) for text in client.close_messages()] == [
        {"op": "unsubscribe", "id": "subscribe:/nemesys/pose:2", "topic": "/nemesys/pose"},
        {"op": "unsubscribe", "id": "subscribe:/nemesys/mission:3", "topic": "/nemesys/mission"},
        {"op": "unadvertise", "id": "advertise:/nemesys/frame:1", "topic": "/nemesys/frame"},
    ]
    with pytest.raises(KeyError, match="/camera"):
        ClientProtocol(advertise=[], subscribe=["/camera"])


def test_the_server_session_takes_what_the_client_protocol_sends() -> None:
    client = ClientProtocol(advertise=[FRAME_TOPIC], subscribe=[MISSION_TOPIC])
    session = ClientSession()
    for text in client.open_messages():
        out = session.receive_text(text)
        assert out.request == parse_message(text) and out.error is None and out.replies == ()
    assert dict(session.advertised) == {FRAME_TOPIC: "std_msgs/msg/UInt8MultiArray"}
    assert session.subscriptions == {MISSION_TOPIC: frozenset({"subscribe:/nemesys/mission:2"})}
    published = session.receive_text(client.publish(FRAME_TOPIC, {"data": list(EXAMPLE)}))
    assert published.frame == EXAMPLE
    for text in client.close_messages():
        out = session.receive_text(text)
        assert out.error is None and out.replies == ()
    assert session.subscriptions == {} and dict(session.advertised) == {}


def test_decode_server_message() -> None:
    ack = publish_message(MISSION_TOPIC, json_string_msg({"seq": 4}))
    assert decode_server_message(to_json(ack)) == ack
    assert decode_server_message('{"op": "status", "level": "error"}')["op"] == "status"
    with pytest.raises(BinaryMessage, match="a binary message of 3 bytes"):
        decode_server_message(b"abc")
    with pytest.raises(MalformedMessage, match="a message that is not JSON: 'nope'"):
        decode_server_message("nope")
    with pytest.raises(MalformedMessage, match="not a JSON object"):
        decode_server_message("[1]")
    with pytest.raises(MalformedMessage) as long:
        decode_server_message("x" * 500)
    assert len(long.value.reason) < 120


def test_decode_json_string() -> None:
    assert decode_json_string(json_string_msg({"seq": 1, "outcome": "accepted"})) == {
        "seq": 1,
        "outcome": "accepted",
    }
    assert decode_json_string({"data": {"seq": 2}}) == {"seq": 2}  # already decoded
    for msg, words in [
        ({"data": "{broken"}, "data is not JSON"),
        ({"data": "[1]"}, "no JSON object"),
        ({"data": 42}, "no JSON object"),
        ({}, "no JSON object"),
        ([1], "no JSON object"),
    ]:
        with pytest.raises(InvalidData) as caught:
            decode_json_string(msg)
        assert words in caught.value.reason
