"""One client's rosbridge session without sockets, against the behaviour of the real ROS 2
rosbridge_server: nothing back for errors, rosapi (names, spelling, graph), subscriptions
with throttle_rate and queue_length (fake clock), fragments both ways, the graph's
publishers and subscribers."""

from __future__ import annotations

import base64
import json
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rosbridge.errors import BridgeError
from rosbridge.protocol import (
    CLIENT_COUNT_TOPIC,
    FRAME_TOPIC,
    MISSION_TOPIC,
    OP_PARSERS,
    POSE_TOPIC,
    STATUS_TOPIC,
    TOPIC_TYPES,
    ClientSession,
    Defragmenter,
    Fragment,
    Graph,
    InvalidData,
    InvalidName,
    InvalidType,
    MalformedMessage,
    MessageHandler,
    Outcome,
    OversizedMessage,
    TopicNotEstablished,
    TypeMismatch,
    UnknownOp,
    UnsupportedOp,
    decode_uint8_data,
    expand_name,
    fragments,
    to_json,
    wire_json,
)
from tests.rosbridge.helpers import EXAMPLE


class FakeClock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def new_session(clock: FakeClock | None = None, **options: Any) -> ClientSession:
    graph = Graph(clock=clock or FakeClock(), ros_time=lambda: 42.5)
    return ClientSession(graph=graph, **options)


def send(session: ClientSession, message: dict[str, Any]) -> Outcome:
    return session.receive_text(json.dumps(message))


def call(session: ClientSession, service: str, args: Any = None, op_id: Any = "c") -> Any:
    message: dict[str, Any] = {"op": "call_service", "id": op_id, "service": service}
    if args is not None:
        message["args"] = args
    (reply,) = send(session, message).replies
    assert reply["op"] == "service_response" and reply["service"] == service
    assert reply["id"] == op_id
    return reply["values"] if reply["result"] else ("failed", reply["values"])


# ------------------------------------------------------------------------------------------
# Errors: logged, never answered
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("message", "error", "words"),
    [
        ({"op": "set_level", "level": "error"}, UnknownOp, "Unknown operation: set_level"),
        ({"op": "status", "level": "error", "msg": "x"}, UnknownOp, "Unknown operation: status"),
        ({"op": "fly", "id": "f"}, UnknownOp, "Unknown operation: fly"),
        ({"topic": "/x"}, UnknownOp, "without an op"),
        ({"op": "subscribe"}, MalformedMessage, "subscribe: Expected a topic field"),
        ({"op": "subscribe", "topic": "/camera"}, TopicNotEstablished, "Cannot infer topic"),
        ({"op": "subscribe", "topic": "/x", "type": "nope"}, InvalidType, "valid type string"),
        ({"op": "subscribe", "topic": "/a b", "type": "std_msgs/String"}, InvalidName, "Invalid"),
        (
            {"op": "subscribe", "topic": POSE_TOPIC, "type": "std_msgs/String"},
            TypeMismatch,
            "Tried to register topic /nemesys/pose with type std_msgs/msg/String but it is "
            "already established with type geometry_msgs/msg/PoseStamped",
        ),
        ({"op": "subscribe", "topic": POSE_TOPIC, "queue_length": -1}, BridgeError, "maxlen"),
        ({"op": "advertise", "topic": FRAME_TOPIC, "type": "std_msgs/String"}, TypeMismatch, ""),
        ({"op": "publish", "topic": "/nobody"}, TopicNotEstablished, "/nobody"),
        ({"op": "publish", "topic": FRAME_TOPIC, "msg": {"data": [1, 300]}}, InvalidData, "300"),
        ({"op": "publish", "topic": FRAME_TOPIC, "msg": {"text": "hi"}}, TypeMismatch, "text"),
        ({"op": "advertise_service", "service": "/s", "type": "t"}, UnsupportedOp, "NemeSys"),
        ({"op": "fragment", "id": "m"}, BridgeError, "received invalid fragment!"),
    ],
)
def test_errors_are_logged_and_nothing_is_sent_back(
    message: dict[str, Any], error: type[BridgeError], words: str
) -> None:
    session = new_session()
    out = send(session, message)
    assert isinstance(out.error, error), out
    assert out.replies == () and out.texts == () and out.frame is None
    ((level, text),) = [(line.level, line.text) for line in out.logs]
    assert level == 40 and words in text
    assert session.subscriptions == {} and dict(session.advertised) == {}


def test_log_lines_carry_the_op_and_the_id() -> None:
    session = new_session()
    out = send(session, {"op": "subscribe", "id": "s9", "topic": "/camera"})
    assert out.logs[0].op_id == "s9"
    assert out.logs[0].text.startswith("subscribe: Cannot infer topic type for topic /camera")


def test_non_json_gets_nothing_at_all_and_later_messages_still_work() -> None:
    session = new_session()
    assert session.receive("this is not json") == []
    out = send(session, {"op": "subscribe", "topic": STATUS_TOPIC})
    assert out.error is None and session.is_subscribed(STATUS_TOPIC)


def test_several_messages_in_one_text_and_one_message_in_two() -> None:
    session = new_session()
    first, second = session.receive(
        json.dumps({"op": "subscribe", "topic": POSE_TOPIC})
        + json.dumps({"op": "subscribe", "topic": STATUS_TOPIC})
    )
    assert first.error is None and second.error is None
    assert session.receive('{"op": "subscribe", ') == []
    (joined,) = session.receive(f'"topic": "{MISSION_TOPIC}"}}')
    assert joined.error is None and set(session.subscriptions) == {
        POSE_TOPIC,
        STATUS_TOPIC,
        MISSION_TOPIC,
    }


def test_oversized_and_binary_messages() -> None:
    session = new_session(max_message_bytes=200)
    assert isinstance(session.receive_text("x" * 201).error, OversizedMessage)
    wide = json.dumps({"op": "fly", "pad": "é" * 99}, ensure_ascii=False)
    assert len(wide) <= 200 < len(wide.encode())
    assert isinstance(session.receive_text(wide).error, OversizedMessage)
    (utf8,) = session.receive_binary(json.dumps({"op": "subscribe", "topic": POSE_TOPIC}).encode())
    assert utf8.error is None and session.is_subscribed(POSE_TOPIC)
    (bad,) = session.receive_binary(b"\xff\xfe")
    assert bad.close and bad.error is not None


# ------------------------------------------------------------------------------------------
# rosapi
# ------------------------------------------------------------------------------------------


def test_rosapi_topics_in_ros2_spelling_with_the_servers_own() -> None:
    session = new_session()
    values = call(session, "/rosapi/topics", {})
    listing = dict(zip(values["topics"], values["types"], strict=True))
    assert listing == {
        "/client_count": "std_msgs/msg/Int32",
        "/connected_clients": "rosbridge_msgs/msg/ConnectedClients",
        "/nemesys/frame": "std_msgs/msg/UInt8MultiArray",
        "/nemesys/mission": "std_msgs/msg/String",
        "/nemesys/pose": "geometry_msgs/msg/PoseStamped",
        "/nemesys/status": "std_msgs/msg/String",
        "/parameter_events": "rcl_interfaces/msg/ParameterEvent",
        "/rosout": "rcl_interfaces/msg/Log",
    }
    assert values["topics"] == sorted(values["topics"])


@pytest.mark.parametrize("name", ["rosapi/topics", "/rosapi/topics", "rosapi/topics#7"])
def test_relative_and_absolute_service_names(name: str) -> None:
    session = new_session()
    message: dict[str, Any] = {"op": "call_service", "service": name}
    (reply,) = send(session, message).replies
    assert reply["result"] is True and reply["service"] == name
    assert "/nemesys/pose" in reply["values"]["topics"]
    assert reply.get("id") == ("7" if "#" in name else None)


def test_rosapi_queries() -> None:
    session = new_session()
    assert call(session, "rosapi/topic_type", {"topic": POSE_TOPIC}) == {
        "type": "geometry_msgs/msg/PoseStamped"
    }
    assert call(session, "rosapi/topic_type", [MISSION_TOPIC]) == {"type": "std_msgs/msg/String"}
    assert call(session, "rosapi/topic_type", {"topic": "/x"}) == {"type": ""}
    assert call(session, "rosapi/topic_type", "ignored") == {"type": ""}
    assert call(session, "/rosapi/subscribers", {"topic": FRAME_TOPIC}) == {
        "subscribers": ["/nemesys_vehicle"]
    }
    assert call(session, "/rosapi/publishers", {"topic": POSE_TOPIC}) == {
        "publishers": ["/nemesys_vehicle"]
    }
    assert call(session, "/rosapi/publishers", {"topic": "/rosout"}) == {
        "publishers": ["/nemesys_vehicle", "/rosapi", "/rosapi_params", "/rosbridge_websocket"]
    }
    assert call(session, "/rosapi/topics_for_type", {"type": "std_msgs/msg/String"}) == {
        "topics": [MISSION_TOPIC, STATUS_TOPIC]
    }
    assert call(session, "/rosapi/topics_for_type", {"type": "std_msgs/String"}) == {"topics": []}
    services = call(session, "/rosapi/services")["services"]
    assert services == sorted(services)
    assert {"/rosapi/topics", "/rosapi/topic_type", "/rosapi/get_time"} <= set(services)
    assert "/rosbridge_websocket/get_parameters" in services
    assert call(session, "/rosapi/service_type", {"service": "/rosapi/topics"}) == {
        "type": "rosapi_msgs/srv/Topics"
    }
    assert call(session, "/rosapi/nodes") == {
        "nodes": ["/nemesys_vehicle", "/rosapi", "/rosapi_params", "/rosbridge_websocket"]
    }
    details = call(session, "/rosapi/node_details", {"node": "/nemesys_vehicle"})
    assert details["subscribing"] == [FRAME_TOPIC]
    assert set(details["publishing"]) == {POSE_TOPIC, MISSION_TOPIC, STATUS_TOPIC} | {
        "/rosout",
        "/parameter_events",
    }
    assert call(session, "/rosapi/get_time") == {"time": {"sec": 42, "nanosec": 500_000_000}}
    assert call(session, "/rosapi/get_ros_version") == {"version": 2, "distro": "jazzy"}


@pytest.mark.parametrize(
    ("service", "args", "words"),
    [
        ("/rosapi/get_mission", None, "Service /rosapi/get_mission does not exist"),
        ("launch", None, "Service /launch does not exist"),
        ("/a//b", None, "Invalid service name"),
        ("/rosapi/topic_type", {"topic": 5}, "requires a string for field topic"),
        ("/rosapi/topic_type", {"tpoic": "/x"}, "TopicType_Request does not have a field tpoic"),
        ("/rosapi/get_param_names", None, "not modelled by the NemeSys simulator"),
    ],
)
def test_failed_calls_answer_result_false_with_the_error_text(
    service: str, args: Any, words: str
) -> None:
    session = new_session()
    result = call(session, service, args, op_id=5)
    assert result[0] == "failed" and words in result[1]


def test_expand_name() -> None:
    assert expand_name("rosapi/topics", "service") == "/rosapi/topics"
    assert expand_name("~/x") == "/rosbridge_websocket/x"
    for bad, words in [
        ("", "must not be empty"),
        ("/a b", "characters other than"),
        ("/a//b", "repeated '/'"),
        ("/a/", "forward slash"),
        ("/1a", "start with a number"),
    ]:
        with pytest.raises(InvalidName, match=words):
            expand_name(bad)


# ------------------------------------------------------------------------------------------
# Topics: advertise, publish, subscribe, and the graph they change
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("data", [list(EXAMPLE), base64.b64encode(EXAMPLE).decode()])
def test_publish_a_frame_without_advertising(data: Any) -> None:
    session = new_session()
    out = send(session, {"op": "publish", "topic": FRAME_TOPIC, "msg": {"data": data}})
    assert out.frame == EXAMPLE and out.replies == () and out.error is None
    assert out.publication is not None
    assert out.publication.msg == {
        "layout": {"dim": [], "data_offset": 0},
        "data": base64.b64encode(EXAMPLE).decode(),
    }
    # The bridge now publishes the topic (as the real server after a publish).
    assert call(session, "/rosapi/publishers", {"topic": FRAME_TOPIC}) == {
        "publishers": ["/rosbridge_websocket"]
    }


def test_publish_without_msg_sends_an_empty_frame() -> None:
    assert send(new_session(), {"op": "publish", "topic": FRAME_TOPIC}).frame == b""


def test_a_wrong_advertise_does_not_stop_publishing() -> None:
    """The real server logs the type conflict; a later publish uses the topic's type."""
    session = new_session()
    assert send(session, {"op": "advertise", "topic": FRAME_TOPIC, "type": "std_msgs/String"}).error
    assert send(
        session, {"op": "publish", "topic": FRAME_TOPIC, "msg": {"data": "AAAA"}}
    ).frame == (b"\x00\x00\x00")


def test_relative_topic_name_publishes_on_the_absolute_topic() -> None:
    """As the real server: the type of a relative name is not found (the graph has absolute
    names), so it takes an advertise with the type; then rclpy publishes on /name."""
    session = new_session()
    frame = {"op": "publish", "topic": "nemesys/frame", "msg": {"data": [1]}}
    assert isinstance(send(session, frame).error, TopicNotEstablished)
    send(session, {"op": "advertise", "topic": "nemesys/frame", "type": "std_msgs/UInt8MultiArray"})
    out = send(session, frame)
    assert out.frame == b"\x01" and out.publication is not None
    assert out.publication.topic == FRAME_TOPIC


def test_a_client_topic_appears_in_the_graph_and_lingers_10_s() -> None:
    clock = FakeClock()
    session = new_session(clock)
    send(session, {"op": "advertise", "id": "a", "topic": "/chat", "type": "std_msgs/String"})
    assert call(session, "/rosapi/topic_type", {"topic": "/chat"}) == {
        "type": "std_msgs/msg/String"
    }
    out = send(session, {"op": "publish", "topic": "/chat", "msg": {"data": "hi"}})
    assert out.publication is not None and out.publication.msg == {"data": "hi"}
    assert out.frame is None
    send(session, {"op": "unadvertise", "id": "a", "topic": "/chat"})
    assert dict(session.advertised) == {}
    clock.now += 9.9
    assert call(session, "/rosapi/topic_type", {"topic": "/chat"})["type"] != ""
    clock.now += 0.2
    assert call(session, "/rosapi/topic_type", {"topic": "/chat"}) == {"type": ""}


def test_subscribing_shows_the_bridge_as_subscriber_until_unsubscribed() -> None:
    session = new_session()
    send(session, {"op": "subscribe", "id": "p1", "topic": POSE_TOPIC})
    send(
        session,
        {"op": "subscribe", "id": "p2", "topic": POSE_TOPIC, "type": TOPIC_TYPES[POSE_TOPIC]},
    )
    assert session.subscriptions == {POSE_TOPIC: frozenset({"p1", "p2"})}
    assert call(session, "/rosapi/subscribers", {"topic": POSE_TOPIC}) == {
        "subscribers": ["/rosbridge_websocket"]
    }
    out = send(session, {"op": "unsubscribe", "id": "p1", "topic": POSE_TOPIC})
    assert [line.text for line in out.logs] == [f"Unsubscribed from {POSE_TOPIC}"]
    assert session.is_subscribed(POSE_TOPIC)
    send(session, {"op": "unsubscribe", "id": "nope", "topic": POSE_TOPIC})
    assert session.is_subscribed(POSE_TOPIC)
    send(session, {"op": "unsubscribe", "topic": POSE_TOPIC})  # no id: all of them
    assert not session.is_subscribed(POSE_TOPIC)
    assert call(session, "/rosapi/subscribers", {"topic": POSE_TOPIC}) == {"subscribers": []}
    assert send(session, {"op": "unsubscribe", "topic": "/never"}).logs == ()


def test_subscribe_with_a_type_creates_the_topic() -> None:
    session = new_session()
    out = send(session, {"op": "subscribe", "topic": "/later", "type": "std_msgs/Int32"})
    assert out.error is None
    assert call(session, "/rosapi/topic_type", {"topic": "/later"}) == {
        "type": "std_msgs/msg/Int32"
    }
    # Another client can now publish there without a type, and the first receives it.
    other = ClientSession(graph=session.graph)
    published = send(other, {"op": "publish", "topic": "/later", "msg": {"data": 7}})
    assert published.publication is not None
    (text,) = session.deliver("/later", published.publication.msg)
    assert json.loads(text) == {"op": "publish", "topic": "/later", "msg": {"data": 7}}


def test_close_removes_the_clients_endpoints() -> None:
    clock = FakeClock()
    session = new_session(clock)
    send(session, {"op": "subscribe", "topic": "/a", "type": "std_msgs/String"})
    send(session, {"op": "advertise", "topic": "/b", "type": "std_msgs/String"})
    session.close()
    clock.now += 11
    topics = call(ClientSession(graph=session.graph), "/rosapi/topics")["topics"]
    assert "/a" not in topics and "/b" not in topics


def test_latched_topics_are_delivered_on_subscribe() -> None:
    session = new_session()
    session.graph.latched[CLIENT_COUNT_TOPIC] = {"data": 3}
    out = send(session, {"op": "subscribe", "topic": CLIENT_COUNT_TOPIC})
    assert [json.loads(t)["msg"] for t in out.texts] == [{"data": 3}]
    send(session, {"op": "advertise", "topic": "/l", "type": "std_msgs/String", "latch": True})
    send(session, {"op": "publish", "topic": "/l", "msg": {"data": "kept"}})
    late = ClientSession(graph=session.graph)
    out = send(late, {"op": "subscribe", "topic": "/l"})
    assert [json.loads(t)["msg"] for t in out.texts] == [{"data": "kept"}]


# ------------------------------------------------------------------------------------------
# Pacing: throttle_rate and queue_length (fake clock)
# ------------------------------------------------------------------------------------------


def test_throttle_sends_at_most_one_message_per_throttle_rate() -> None:
    clock = FakeClock()
    session = new_session(clock)
    send(session, {"op": "subscribe", "topic": POSE_TOPIC, "throttle_rate": 1000})
    sent = []
    for i in range(60):  # 20 Hz for 3 s
        clock.now = 100.0 + i / 20
        sent += session.deliver(POSE_TOPIC, {"i": i})
    assert [json.loads(t)["msg"]["i"] for t in sent] == [0, 20, 40]


def test_queue_keeps_the_newest_and_releases_one_per_throttle_rate() -> None:
    clock = FakeClock()
    session = new_session(clock)
    send(
        session, {"op": "subscribe", "topic": STATUS_TOPIC, "throttle_rate": 500, "queue_length": 2}
    )
    first = session.deliver(STATUS_TOPIC, {"i": 0})
    assert [json.loads(t)["msg"]["i"] for t in first] == [0]
    for i in range(1, 5):
        assert session.deliver(STATUS_TOPIC, {"i": i}) == []
    assert session.poll() == []
    clock.now += 0.5
    assert [json.loads(t)["msg"]["i"] for t in session.poll()] == [3]
    assert session.poll() == []
    clock.now += 0.5
    assert [json.loads(t)["msg"]["i"] for t in session.poll()] == [4]


def test_several_subscriptions_take_the_lowest_throttle_and_queue() -> None:
    clock = FakeClock()
    session = new_session(clock)
    send(session, {"op": "subscribe", "id": "slow", "topic": POSE_TOPIC, "throttle_rate": 1000})
    send(session, {"op": "subscribe", "id": "fast", "topic": POSE_TOPIC, "throttle_rate": 100})
    sent = []
    for i in range(10):
        sent += session.deliver(POSE_TOPIC, {"i": i})
        clock.now += 0.05
    assert len(sent) == 5
    send(session, {"op": "unsubscribe", "id": "fast", "topic": POSE_TOPIC})
    sent = []
    for i in range(10):
        sent += session.deliver(POSE_TOPIC, {"i": i})
        clock.now += 0.25
    assert [json.loads(t)["msg"]["i"] for t in sent] == [4, 8]  # one a second again


def test_message_handler_transitions() -> None:
    handler = MessageHandler()
    handler.configure(0, 3)
    assert handler.handle("a", 0.0) == ["a"]  # a queue without throttle sends at once
    handler.configure(1000, 3)
    assert handler.handle("b", 0.5) == []
    assert handler.handle("c", 0.6) == []
    handler.configure(1000, 1)  # the queue shrinks to the newest
    assert handler.poll(1.0) == ["c"]
    handler.configure(1000, 0)
    assert handler.handle("d", 1.5) == [] and handler.handle("e", 2.0) == ["e"]
    with pytest.raises(ValueError, match="maxlen"):
        handler.configure(0, -1)


# ------------------------------------------------------------------------------------------
# Fragments
# ------------------------------------------------------------------------------------------


def test_fragment_size_from_any_message_applies_to_everything_sent() -> None:
    session = new_session()
    send(session, {"op": "subscribe", "topic": STATUS_TOPIC, "fragment_size": 30})
    assert session.fragment_size == 30
    texts = session.deliver(STATUS_TOPIC, {"data": "x" * 50})
    parts = [json.loads(t) for t in texts]
    assert all(p["op"] == "fragment" and p["id"] == 0 for p in parts)
    whole = "".join(p["data"] for p in parts)
    assert json.loads(whole) == {"op": "publish", "topic": STATUS_TOPIC, "msg": {"data": "x" * 50}}
    (reply,) = send(session, {"op": "call_service", "id": "t", "service": "rosapi/topics"}).replies
    pieces = [json.loads(t) for t in session.encode(reply)]
    assert {p["id"] for p in pieces} == {"t"} and len(pieces) > 1
    send(session, {"op": "unsubscribe", "topic": "/x", "fragment_size": None})
    assert session.fragment_size is None
    assert session.encode(reply) == (wire_json(reply),)


def test_bad_fragment_size_loses_the_messages_as_the_real_server() -> None:
    session = new_session()
    send(session, {"op": "subscribe", "topic": STATUS_TOPIC, "fragment_size": 0})
    assert session.deliver(STATUS_TOPIC, {"data": "x"}) == []
    (line,) = session.drain_logs()
    assert line.level == 40 and "subscribe callback" in line.text


def test_incoming_fragments_are_reassembled_in_the_order_received() -> None:
    session = new_session()
    text = json.dumps({"op": "publish", "topic": FRAME_TOPIC, "msg": {"data": list(EXAMPLE)}})
    parts = [json.loads(f) for f in fragments(text, 16, "m1")]
    total = len(parts)
    for part in parts[:-1]:
        part["total"] = total  # a client sends an integer total
        out = session.receive(json.dumps(part))
        assert [o.frame for o in out] == [None]
    parts[-1]["total"] = total
    outcomes = session.receive(json.dumps(parts[-1]))
    assert [o.frame for o in outcomes] == [None, EXAMPLE]


def test_defragmenter_refusals_and_timeout() -> None:
    defrag = Defragmenter(limit=10, timeout_s=600)
    assert defrag.add(Fragment("a", 0, 2, "ab"), 0.0) == (None, [])
    with pytest.raises(BridgeError, match="error while trying to append fragment 0"):
        defrag.add(Fragment("a", 0, 2, "ab"), 0.0)  # twice
    with pytest.raises(BridgeError, match="error while trying to append fragment 1"):
        defrag.add(Fragment("a", 1, 3, "cd"), 0.0)  # another total
    with pytest.raises(BridgeError, match="exceed 10 characters"):
        defrag.add(Fragment("a", 1, 2, "x" * 9), 0.0)
    defrag.add(Fragment("b", 0, 2, "{"), 0.0)
    text, warnings = defrag.add(Fragment("c", 0, 1, "{}"), 700.0)
    assert text == "{}" and warnings == ["fragment list b timed out.. -> removing it.."]
    with pytest.raises(BridgeError, match="'float' object cannot be interpreted"):
        defrag.add(Fragment("d", 0, 1.0, "x"), 700.0)


# ------------------------------------------------------------------------------------------
# Any input
# ------------------------------------------------------------------------------------------

_JSON = st.recursive(
    st.none() | st.booleans() | st.integers(-300, 300) | st.floats() | st.text(max_size=8),
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner, max_size=4)
    ),
    max_leaves=12,
)
_DATA = (
    st.lists(st.integers(-1, 256), max_size=14)
    | st.binary(max_size=14).map(lambda b: base64.b64encode(b).decode())
    | _JSON
)
_MESSAGES = st.fixed_dictionaries(
    {"op": st.sampled_from([*OP_PARSERS, "fly", "set_level"])},
    optional={
        "id": _JSON,
        "topic": st.sampled_from([*TOPIC_TYPES, "/x", "", "a b", "rosout"]) | _JSON,
        "type": st.sampled_from([*TOPIC_TYPES.values(), "std_msgs/msg/String", "x"]) | _JSON,
        "msg": st.fixed_dictionaries({}, optional={"data": _DATA, "layout": _JSON}) | _JSON,
        "service": st.sampled_from(["/rosapi/topics", "rosapi/topic_type", "/s", "#"]) | _JSON,
        "args": _JSON,
        "throttle_rate": st.integers(-5, 2000) | _JSON,
        "queue_length": st.integers(-1, 3) | _JSON,
        "fragment_size": st.integers(-1, 50) | _JSON,
        "num": _JSON,
        "total": _JSON,
        "data": _JSON,
    },
)


@pytest.mark.slow  # a fuzz run, ~2 s
@settings(max_examples=150, deadline=None)
@given(messages=st.lists(_MESSAGES, max_size=6))
def test_session_never_raises_and_only_passes_valid_frames(messages: list[dict[str, Any]]) -> None:
    session = new_session()
    for message in messages:
        for out in session.receive(json.dumps(message)):
            assert isinstance(out, Outcome)
            if out.frame is not None:
                assert message["op"] in ("publish", "fragment")
                if message["op"] == "publish" and isinstance(message.get("msg"), dict):
                    data = message["msg"].get("data", [])
                    assert out.frame == decode_uint8_data(data)
            assert out.replies == () or all(r["op"] == "service_response" for r in out.replies)
            for reply in out.replies:
                assert json.loads(to_json(reply))["op"] == "service_response"
        session.deliver(STATUS_TOPIC, {"data": "s"})
        session.poll()
